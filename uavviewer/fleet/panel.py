"""The fleet: every vehicle of the lab in a row (name, mode, armed, battery, link age); a click picks the one
the sticks fly; Take off / Land / Stop for all. It only shows rows and says what was clicked
(uavviewer.fleet.controller.FleetController decides)."""
from __future__ import annotations

from PyQt5 import uic
from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtGui import QBrush, QColor, QFont
from PyQt5.QtWidgets import QHeaderView, QTableWidgetItem, QWidget

from .. import RESOURCES

__all__ = ["FleetPanel"]

STALE = QColor("#7f8791")


class FleetPanel(QWidget):
    vehiclePicked = pyqtSignal(str)         # a row was clicked: fly that vehicle
    allRequested = pyqtSignal(str)          # "takeoff", "land" or "stop", for every vehicle

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        uic.loadUi(str(RESOURCES / "ui" / "fleet_panel.ui"), self)
        self.setObjectName("fleetPanel")
        header = self.table.horizontalHeader()
        for column in range(self.table.columnCount() - 1):
            header.setSectionResizeMode(column, QHeaderView.ResizeToContents)
        self.table.cellClicked.connect(lambda row, _column: self._clicked(row))
        self.takeoffAllButton.clicked.connect(lambda: self.allRequested.emit("takeoff"))
        self.landAllButton.clicked.connect(lambda: self.allRequested.emit("land"))
        self.stopAllButton.clicked.connect(lambda: self.allRequested.emit("stop"))
        self._names: list[str] = []

    def _clicked(self, row: int) -> None:
        if 0 <= row < len(self._names):
            self.vehiclePicked.emit(self._names[row])

    def set_rows(self, rows) -> None:
        """``rows``: uavviewer.fleet.controller.FleetRow, one per vehicle."""
        self._names = [r.name for r in rows]
        self.table.setRowCount(len(rows))
        picked = ""
        for i, r in enumerate(rows):
            cells = (("▶ " if r.picked else "") + r.name, r.mode or "–", "ARMED" if r.armed else "disarmed",
                     r.battery, r.link)
            for column, text in enumerate(cells):
                item = self.table.item(i, column)
                if item is None:
                    item = QTableWidgetItem()
                    item.setFlags(Qt.ItemIsEnabled | Qt.ItemIsSelectable)
                    self.table.setItem(i, column, item)
                item.setText(text)
                font = QFont(item.font())
                font.setBold(r.picked)
                item.setFont(font)
                item.setForeground(QBrush(STALE) if r.stale else QBrush())
            if r.picked:
                picked = r.name
                self.table.selectRow(i)
        self.flyingLabel.setText(f"Flying: <b>{picked}</b>" if picked else "Flying: –")
        for button in (self.takeoffAllButton, self.landAllButton, self.stopAllButton):
            button.setEnabled(bool(rows))

    def row_texts(self) -> list[list[str]]:
        """What each row shows, for tests."""
        return [[self.table.item(i, c).text() for c in range(self.table.columnCount())]
                for i in range(self.table.rowCount())]

    def click_vehicle(self, name: str):
        """The cell a pilot would click to pick ``name`` (tests click it with the mouse)."""
        row = self._names.index(name)
        return self.table.visualItemRect(self.table.item(row, 0)).center()
