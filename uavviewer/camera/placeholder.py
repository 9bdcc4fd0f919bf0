"""The space the camera view will fill; neutral until a camera exists."""
from __future__ import annotations

from PyQt5.QtCore import QRectF, Qt
from PyQt5.QtGui import QColor, QFont, QPainter, QPen
from PyQt5.QtWidgets import QSizePolicy, QWidget

__all__ = ["CameraPlaceholder"]


class CameraPlaceholder(QWidget):
    """Draws a framed, quiet "No camera" card."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._text = "No camera"
        self.setMinimumSize(240, 160)
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Expanding)

    def set_text(self, text: str) -> None:
        self._text = text
        self.update()

    def text(self) -> str:
        return self._text

    def paintEvent(self, event) -> None:  # noqa: N802
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        r = QRectF(self.rect()).adjusted(1, 1, -1, -1)
        p.setPen(QPen(QColor(52, 60, 70), 1.5))
        p.setBrush(QColor(20, 24, 30))
        p.drawRoundedRect(r, 6, 6)
        # A simple camera glyph.
        c = r.center()
        s = min(r.width(), r.height()) * 0.12
        p.setPen(QPen(QColor(80, 90, 102), 2))
        p.setBrush(Qt.NoBrush)
        p.drawRoundedRect(QRectF(c.x() - s, c.y() - s * 0.9, 2 * s, 1.4 * s), 4, 4)
        p.drawEllipse(QRectF(c.x() - s * 0.4, c.y() - s * 0.6, s * 0.8, s * 0.8))
        font = QFont(self.font())
        font.setPixelSize(14)
        p.setFont(font)
        p.setPen(QColor(110, 120, 132))
        p.drawText(QRectF(r.left(), c.y() + s * 0.7, r.width(), 30), Qt.AlignCenter, self._text)
        p.end()
