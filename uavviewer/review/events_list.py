"""The log's events in a list (mode changes, arming, failsafes, errors, events, messages): a click puts the
time cursor there."""
from __future__ import annotations

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtGui import QColor
from PyQt5.QtWidgets import QListWidget, QListWidgetItem, QWidget

from .plots import EVENT_COLOURS

__all__ = ["EventsList"]


class EventsList(QListWidget):
    timeChosen = pyqtSignal(float)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.itemClicked.connect(lambda item: self.timeChosen.emit(float(item.data(Qt.UserRole))))

    def show_events(self, events) -> None:
        self.clear()
        for e in events:
            item = QListWidgetItem(f"{e.t:8.1f} s  {e.kind:<8}  {e.text}")
            item.setData(Qt.UserRole, e.t)
            item.setForeground(QColor(EVENT_COLOURS.get(e.kind, "#cfd8dc")))
            self.addItem(item)
