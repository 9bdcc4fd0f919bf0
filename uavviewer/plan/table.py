"""One list of the Plan dock (mission, fence or rally points): rows can be dragged to another place.

Qt's own InternalMove would move the cells itself; here the drop only says which rows go where
(``rowsDropped``) and the editor moves the items in the plan, one undo step, and shows the list again from it.
"""
from __future__ import annotations

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import QAbstractItemView, QTableWidget

__all__ = ["PlanTable"]

_ROWS = "application/x-qabstractitemmodeldatalist"      # what a view's own drag carries


class PlanTable(QTableWidget):
    rowsDropped = pyqtSignal(list, int)      # the rows dragged, the row they go before (rowCount(): the end)

    def __init__(self, rows: int, columns: int, parent=None) -> None:
        super().__init__(rows, columns, parent)
        self.setDragEnabled(True)
        self.setAcceptDrops(True)
        self.viewport().setAcceptDrops(True)
        self.setDragDropMode(QAbstractItemView.InternalMove)
        self.setDragDropOverwriteMode(False)
        self.setDropIndicatorShown(True)

    def dropEvent(self, event) -> None:  # noqa: N802 (Qt's name)
        if event.source() not in (self, None) or not event.mimeData().hasFormat(_ROWS):
            event.ignore()
            return
        index = self.indexAt(event.pos())
        if not index.isValid():
            before = self.rowCount()
        else:
            rect = self.visualRect(index)
            before = index.row() + (1 if event.pos().y() > rect.center().y() else 0)
        rows = sorted({i.row() for i in self.selectionModel().selectedRows()})
        event.setDropAction(Qt.IgnoreAction)         # nothing for Qt to remove: the list is drawn from the plan
        event.accept()
        if rows:
            self.rowsDropped.emit(rows, before)
