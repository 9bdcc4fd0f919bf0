"""The map's labels: light text on a dark box, readable on the grid and on any tile, and never over one another.

Each label drawn in a paint keeps its box; a label that may move (a traffic contact's) takes the first of the places
offered that covers no label drawn before it (the range rings' distances are drawn first), as a name on the map
tries the sides of its arrow.
"""
from __future__ import annotations

from PyQt5.QtCore import QPointF, QRectF
from PyQt5.QtGui import QColor, QPainter

__all__ = ["Labels", "LABEL_BOX", "LABEL_TEXT"]

LABEL_BOX = QColor(20, 26, 34, 170)
LABEL_TEXT = QColor("#e6ebf0")


class Labels:
    def __init__(self) -> None:
        self.boxes: list[tuple[QRectF, str]] = []     # every label of the paint under way, and its text

    def clear(self) -> None:
        """A new paint: nothing is labelled yet."""
        self.boxes = []

    def draw(self, p: QPainter, at: QPointF, text: str) -> QRectF:
        """``text`` with its baseline starting at ``at``, wherever the others are."""
        box = self._box(p, at, text)
        p.fillRect(box, LABEL_BOX)
        p.setPen(LABEL_TEXT)
        p.drawText(at, text)
        self.boxes.append((box, text))
        return box

    def place(self, p: QPainter, anchor: QPointF, text: str, offsets: list[QPointF]) -> QRectF:
        """``text`` at the first of ``offsets`` from ``anchor`` whose box covers no label drawn before (the first
        when none is free). A negative x offset puts the label's right edge there, left of the anchor."""
        width = p.fontMetrics().horizontalAdvance(text)
        spots = [anchor + QPointF(o.x() - (width if o.x() < 0 else 0), o.y()) for o in offsets]
        free = next((at for at in spots if not any(self._box(p, at, text).intersects(b) for b, _ in self.boxes)),
                    spots[0])
        return self.draw(p, free, text)

    @staticmethod
    def _box(p: QPainter, at: QPointF, text: str) -> QRectF:
        return QRectF(p.fontMetrics().boundingRect(text)).translated(at).adjusted(-2, -1, 2, 1)
