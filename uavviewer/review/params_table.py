"""The parameters as they were in the reviewed flight, beside the vehicle's current values: the differences
first (the vehicle's table, when one is connected and has sent its parameters)."""
from __future__ import annotations

from PyQt5.QtGui import QColor
from PyQt5.QtWidgets import QCheckBox, QLabel, QTableWidget, QTableWidgetItem, QVBoxLayout, QWidget

from driver.review.log import param_diff

__all__ = ["FlightParams"]

CHANGED = QColor("#ffb74d")


def _text(v: float | None) -> str:
    return "—" if v is None else f"{v:g}"


class FlightParams(QWidget):
    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.summary = QLabel()
        self.only_diff = QCheckBox("Only differences")
        self.table = QTableWidget(0, 3)
        self.table.setHorizontalHeaderLabels(["Parameter", "In the flight", "On the vehicle now"])
        self.table.horizontalHeader().setStretchLastSection(True)
        self.table.setEditTriggers(QTableWidget.NoEditTriggers)
        self.only_diff.toggled.connect(lambda _on: self._fill())
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.summary)
        layout.addWidget(self.only_diff)
        layout.addWidget(self.table)
        self.flight: dict[str, float] = {}
        self.current: dict[str, float] = {}
        self.differences: list[tuple[str, float | None, float | None]] = []

    def show_params(self, flight: dict[str, float], current: dict[str, float]) -> None:
        self.flight, self.current = flight, current
        self.differences = param_diff(flight, current) if current else []
        if not flight:
            self.summary.setText("This log holds no parameters.")
        elif not current:
            self.summary.setText(f"{len(flight)} parameters in the flight; no vehicle parameters to compare "
                                 "(connect and read them to see the differences).")
        else:
            self.summary.setText(f"{len(flight)} parameters in the flight; {len(self.differences)} differ from "
                                 "the vehicle's now.")
        self.only_diff.setEnabled(bool(current))
        self.only_diff.setChecked(bool(current))
        self._fill()

    def _fill(self) -> None:
        differ = {name for name, _a, _b in self.differences}
        names = sorted(differ) if self.only_diff.isChecked() else sorted(set(self.flight) | set(self.current))
        self.table.setRowCount(len(names))
        for row, name in enumerate(names):
            cells = [name, _text(self.flight.get(name)), _text(self.current.get(name)) if self.current else ""]
            for col, text in enumerate(cells):
                item = QTableWidgetItem(text)
                if name in differ:
                    item.setForeground(CHANGED)
                self.table.setItem(row, col, item)
        self.table.resizeColumnsToContents()
