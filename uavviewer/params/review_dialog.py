"""Every pending change before it is written: the vehicle's value, the new one, what to know about it; then
each write's outcome as the vehicle confirmed it (or did not)."""
from __future__ import annotations

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtGui import QBrush, QIcon
from PyQt5.QtWidgets import QDialog, QDialogButtonBox, QLabel, QPushButton, QTableWidgetItem, QVBoxLayout, QWidget

from .checklist import checklist

from .rows import ReviewRow
from .table_model import CONFIRMED, FAILED, PENDING, WriteState

__all__ = ["ReviewDialog"]

_NAME, _VEHICLE, _NEW, _NOTES, _RESULT = range(5)


class ReviewDialog(QDialog):
    writeRequested = pyqtSignal(list)        # the names ticked, to write in one go
    discardRequested = pyqtSignal(list)      # the names ticked, to drop

    def __init__(self, rows: list[ReviewRow], parent: QWidget | None = None, armed: bool = False) -> None:
        super().__init__(parent)
        self.setObjectName("reviewDialog")
        self.setWindowTitle("Review parameter changes")
        self.resize(820, 420)
        self.summary = QLabel()
        self.summary.setWordWrap(True)
        self.table = checklist(len(rows), ["Parameter", "Vehicle", "New", "Notes", "Result"], _NOTES)
        self._armed = armed
        self._rows = {r.name: i for i, r in enumerate(rows)}
        for i, r in enumerate(rows):
            name = QTableWidgetItem(r.name)
            name.setFlags(Qt.ItemIsEnabled | Qt.ItemIsUserCheckable)
            name.setCheckState(Qt.Checked)
            self.table.setItem(i, _NAME, name)
            self.table.setItem(i, _VEHICLE, QTableWidgetItem(r.vehicle))
            new = QTableWidgetItem(r.new)
            new.setForeground(QBrush(PENDING))
            self.table.setItem(i, _NEW, new)
            notes = QTableWidgetItem(r.notes)
            notes.setToolTip(r.notes)
            if r.warn:
                notes.setForeground(QBrush(FAILED))
            self.table.setItem(i, _NOTES, notes)
            self.table.setItem(i, _RESULT, QTableWidgetItem("not written"))
        self.buttons = QDialogButtonBox()
        self.write_button = QPushButton()
        self.write_button.setObjectName("writeButton")
        self.write_button.setDefault(False)
        self.write_button.setAutoDefault(False)      # Enter must not write to the vehicle; only a click does
        self.discard_button = QPushButton("Discard ticked")
        self.buttons.addButton(self.write_button, QDialogButtonBox.ActionRole)
        self.buttons.addButton(self.discard_button, QDialogButtonBox.ActionRole)
        close = self.buttons.addButton(QDialogButtonBox.Close)
        close.setAutoDefault(False)
        close.setIcon(QIcon())
        layout = QVBoxLayout(self)
        layout.addWidget(self.summary)
        layout.addWidget(self.table, 1)
        layout.addWidget(self.buttons)
        self.write_button.clicked.connect(lambda: self.writeRequested.emit(self.ticked()))
        self.discard_button.clicked.connect(self._discard)
        close.clicked.connect(self.reject)
        self.table.itemChanged.connect(lambda _item: self._update())
        self._update()

    def ticked(self) -> list[str]:
        return [self.table.item(i, _NAME).text() for i in range(self.table.rowCount())
                if self.table.item(i, _NAME).checkState() == Qt.Checked
                and self.table.item(i, _NAME).flags() & Qt.ItemIsUserCheckable]

    def set_ticked(self, name: str, on: bool) -> None:
        self.table.item(self._rows[name], _NAME).setCheckState(Qt.Checked if on else Qt.Unchecked)

    def result(self, name: str) -> str:
        return self.table.item(self._rows[name], _RESULT).text()

    def show_write(self, name: str, state: WriteState, reason: str = "") -> None:
        """How the write of ``name`` stands; a confirmed one can no longer be ticked."""
        row = self._rows.get(name)
        if row is None:
            return
        item = self.table.item(row, _RESULT)
        # the driver's reason may already begin with the state's words ("not confirmed: no answer to ..."): once
        reason_text = reason.removeprefix(f"{state.value}: ")
        item.setText(state.value + (f": {reason_text}" if reason and state is WriteState.FAILED else ""))
        item.setToolTip(reason)
        item.setForeground(QBrush({WriteState.WRITING: PENDING, WriteState.CONFIRMED: CONFIRMED,
                                   WriteState.FAILED: FAILED}[state]))
        if state is WriteState.CONFIRMED:
            check = self.table.item(row, _NAME)
            check.setCheckState(Qt.Unchecked)
            check.setFlags(Qt.ItemIsEnabled)
        self._update()

    def _discard(self) -> None:
        names = self.ticked()
        for name in names:
            self.show_write(name, WriteState.FAILED, "discarded")
            check = self.table.item(self._rows[name], _NAME)
            check.setCheckState(Qt.Unchecked)
            check.setFlags(Qt.ItemIsEnabled)
        self.discardRequested.emit(names)

    def _update(self) -> None:
        ticked = self.ticked()
        results = [self.table.item(i, _RESULT).text() for i in range(self.table.rowCount())]
        confirmed = sum(r.startswith(WriteState.CONFIRMED.value) for r in results)
        failed = sum(r.startswith(WriteState.FAILED.value) and "discarded" not in r for r in results)
        writing = sum(r == WriteState.WRITING.value for r in results)
        self.write_button.setText(f"Write {len(ticked)} to the vehicle")
        self.write_button.setEnabled(bool(ticked) and not writing)
        self.discard_button.setEnabled(bool(ticked) and not writing)
        parts = [f"{self.table.rowCount()} change(s) to review."]
        if writing or confirmed or failed:
            parts.append(f"{confirmed} confirmed by the vehicle, {failed} not confirmed, {writing} writing.")
        else:
            parts.append("Nothing is written until you press Write; each value counts only once the vehicle "
                         "reports it back.")
        if self._armed:
            parts.append("<b>The vehicle is armed: a new value acts at once, in the air too.</b>")
        self.summary.setText(" ".join(parts))
