"""A .param file beside the vehicle: every difference listed, the ones ticked staged for review."""
from __future__ import annotations

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtGui import QBrush, QIcon
from PyQt5.QtWidgets import QDialog, QDialogButtonBox, QLabel, QPushButton, QTableWidgetItem, QVBoxLayout, QWidget

from .checklist import checklist

from .rows import FileRow
from .table_model import DIM, FAILED, PENDING

__all__ = ["CompareDialog"]

_NAME, _VEHICLE, _FILE, _NOTES = range(4)


class CompareDialog(QDialog):
    applyRequested = pyqtSignal(dict)          # name → the file's value, for every ticked row

    def __init__(self, path: str, differences: list[FileRow], same: int, vehicle_only: int,
                 parent: QWidget | None = None, problems: list[str] = (), excluded: list[str] = ()) -> None:
        super().__init__(parent)
        self.setObjectName("compareDialog")
        self.setWindowTitle(f"Compare with {path}")
        self.resize(820, 480)
        self._differences = differences
        applicable = sum(d.applicable for d in differences)
        summary = (f"<b>{path}</b>: {len(differences)} difference(s) with the vehicle, {same} the same"
                   + (f", {vehicle_only} on the vehicle only (left as they are)" if vehicle_only else "") + ". "
                   + ("Tick the values to take from the file; they are staged for review, nothing is written yet."
                      if applicable else "Nothing to apply.")
                   + (f"<br>Not read: {'; '.join(problems[:5])}" + (" …" if len(problems) > 5 else "")
                      if problems else "")
                   + (f"<br>Left out as MAVProxy does: {', '.join(excluded)}" if excluded else ""))
        self.summary = QLabel(summary)
        self.summary.setWordWrap(True)
        self.table = checklist(len(differences), ["Parameter", "Vehicle", "File", "Notes"], _NOTES)
        self._rows: dict[str, int] = {}
        for i, d in enumerate(differences):
            self._rows[d.name] = i
            name = QTableWidgetItem(d.name)
            if d.applicable:
                name.setFlags(Qt.ItemIsEnabled | Qt.ItemIsUserCheckable)
                name.setCheckState(Qt.Checked)
            else:
                name.setFlags(Qt.ItemIsEnabled)
                name.setForeground(QBrush(DIM))
            self.table.setItem(i, _NAME, name)
            self.table.setItem(i, _VEHICLE, QTableWidgetItem(d.vehicle or "—"))
            new = QTableWidgetItem(d.file)
            new.setForeground(QBrush(PENDING if d.applicable else DIM))
            self.table.setItem(i, _FILE, new)
            notes = QTableWidgetItem(d.notes)
            notes.setToolTip(d.notes)
            if d.warn or not d.applicable:
                notes.setForeground(QBrush(FAILED if d.warn else DIM))
            self.table.setItem(i, _NOTES, notes)
        self.buttons = QDialogButtonBox()
        self.all_button = QPushButton("Tick all")
        self.none_button = QPushButton("Tick none")
        self.apply_button = QPushButton()
        self.apply_button.setObjectName("applyButton")
        for b in (self.all_button, self.none_button, self.apply_button):
            b.setAutoDefault(False)
            self.buttons.addButton(b, QDialogButtonBox.ActionRole)
        close = self.buttons.addButton(QDialogButtonBox.Close)
        close.setIcon(QIcon())
        close.clicked.connect(self.reject)
        layout = QVBoxLayout(self)
        layout.addWidget(self.summary)
        layout.addWidget(self.table, 1)
        layout.addWidget(self.buttons)
        self.all_button.clicked.connect(lambda: self._tick_all(True))
        self.none_button.clicked.connect(lambda: self._tick_all(False))
        self.apply_button.clicked.connect(self._apply)
        self.table.itemChanged.connect(lambda _item: self._update())
        self._update()

    def names(self) -> list[str]:
        return [d.name for d in self._differences]

    def ticked(self) -> list[str]:
        return [d.name for i, d in enumerate(self._differences)
                if d.applicable and self.table.item(i, _NAME).checkState() == Qt.Checked]

    def set_ticked(self, name: str, on: bool) -> None:
        self.table.item(self._rows[name], _NAME).setCheckState(Qt.Checked if on else Qt.Unchecked)

    def _tick_all(self, on: bool) -> None:
        for name in (d.name for d in self._differences if d.applicable):
            self.set_ticked(name, on)

    def _apply(self) -> None:
        chosen = {d.name: d.value for d in self._differences if d.name in set(self.ticked())}
        if chosen:
            self.applyRequested.emit(chosen)
            self.accept()

    def _update(self) -> None:
        n = len(self.ticked())
        self.apply_button.setText(f"Stage {n} for review")
        self.apply_button.setEnabled(n > 0)
