"""One list of the Plan dock (mission, fence or rally points): rows are dragged to another place with the mouse.

The gesture is the list's own: press on a row (on one of several selected rows: they move together), move, and a
line shows where they will go; release and ``rowsDropped`` says which rows go where. The editor moves the items in
the plan, one undo step, and shows the list again from it. Qt's drag and drop (QDrag) was set up, but the items
were not draggable, so a drag only stretched the selection; a drag confined to one list needs none of it (no data
to carry, no platform drag loop), and the same mouse events a pilot makes drive it in the tests.
"""
from __future__ import annotations

from PyQt5.QtCore import QPoint, Qt, pyqtSignal
from PyQt5.QtGui import QColor, QPainter, QPen
from PyQt5.QtWidgets import QAbstractItemView, QApplication, QTableWidget

__all__ = ["PlanTable"]

LINE = QColor("#2f81f7")             # where the dragged rows will go


class PlanTable(QTableWidget):
    rowsDropped = pyqtSignal(list, int)      # the rows dragged, the row they go before (rowCount(): the end)

    def __init__(self, rows: int, columns: int, parent=None) -> None:
        super().__init__(rows, columns, parent)
        self._pressed: tuple[QPoint, int] | None = None     # where the left button went down, on which row
        self._selection_held = False         # pressed on one of several selected rows: they stay selected until
                                             # the release (a drag takes them all; a click, that one alone)
        self.before: int | None = None       # while dragging: the row the dragged ones go before

    def selected(self) -> list[int]:
        return sorted({i.row() for i in self.selectionModel().selectedRows()})

    def row_before(self, pos: QPoint) -> int:
        """The row a drop at ``pos`` (viewport) goes before: the upper half of a row is before it."""
        row = self.rowAt(pos.y())
        if row < 0:
            return 0 if self.rowCount() and pos.y() < self.rowViewportPosition(0) else self.rowCount()
        rect = self.visualRect(self.model().index(row, 0))
        return row + (1 if pos.y() > rect.center().y() else 0)

    def mousePressEvent(self, event) -> None:  # noqa: N802 (Qt's name)
        row = self.rowAt(event.pos().y())
        self._pressed, self._selection_held, self.before = None, False, None
        if event.button() == Qt.LeftButton and not event.modifiers() and row >= 0:
            self._pressed = (event.pos(), row)
            if row in self.selected() and len(self.selected()) > 1:   # several to drag: keep them selected
                self._selection_held = True
                event.accept()
                return
        super().mousePressEvent(event)

    def mouseMoveEvent(self, event) -> None:  # noqa: N802 (Qt's name)
        if self._pressed is not None and event.buttons() & Qt.LeftButton:
            if self.before is not None or \
                    (event.pos() - self._pressed[0]).manhattanLength() >= QApplication.startDragDistance():
                self.before = self.row_before(event.pos())      # a drag, not a stretched selection
                self.viewport().update()
                event.accept()
                return
        if not self._selection_held:
            super().mouseMoveEvent(event)

    def mouseReleaseEvent(self, event) -> None:  # noqa: N802 (Qt's name)
        pressed, held, before = self._pressed, self._selection_held, self.before
        self._pressed, self._selection_held, self.before = None, False, None
        if before is not None:
            self.viewport().update()
            self.setState(QAbstractItemView.NoState)
            event.accept()
            rows = self.selected()
            if rows and not (rows == list(range(rows[0], rows[-1] + 1)) and rows[0] <= before <= rows[-1] + 1):
                self.rowsDropped.emit(rows, before)          # (dropped where they are: nothing moves)
            return
        if held and pressed is not None:                        # a click on one of several: that one alone
            self.selectRow(pressed[1])
            event.accept()
            return
        super().mouseReleaseEvent(event)

    def paintEvent(self, event) -> None:  # noqa: N802 (Qt's name)
        super().paintEvent(event)
        if self.before is None:
            return
        if self.before < self.rowCount():
            y = self.rowViewportPosition(self.before)
        else:
            last = self.rowCount() - 1
            y = self.rowViewportPosition(last) + self.rowHeight(last) if last >= 0 else 0
        p = QPainter(self.viewport())
        p.setPen(QPen(LINE, 2))
        p.drawLine(0, y, self.viewport().width(), y)
        p.end()
