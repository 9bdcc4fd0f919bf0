"""The vehicle drawn in the position the accelerometer calibration asks for (ACCELCAL_VEHICLE_POS 1..6)."""
from __future__ import annotations

from PyQt5.QtCore import QPointF, QRectF, Qt
from PyQt5.QtGui import QColor, QPainter, QPen
from PyQt5.QtWidgets import QSizePolicy, QWidget

__all__ = ["AccelPose"]

# position → (view, clockwise rotation on screen): the side view has the nose to the right, the front view the
# nose towards the pilot (the vehicle's left on the pilot's right)
_VIEWS = {1: ("side", 0), 2: ("front", 90), 3: ("front", -90), 4: ("side", 90), 5: ("side", -90), 6: ("side", 180)}


class AccelPose(QWidget):
    """A side (or front) view of a quadcopter on the ground line, turned as asked; an arrow marks the nose."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.position: int | None = None
        self.setMinimumSize(160, 110)
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Preferred)

    def set_position(self, position: int | None) -> None:
        if position != self.position:
            self.position = position
            self.update()

    def paintEvent(self, _event) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        w, h = self.width(), self.height()
        ground = h - 12
        p.setPen(QPen(QColor("#888"), 2))
        p.drawLine(8, ground, w - 8, ground)
        if self.position not in _VIEWS:
            p.drawText(self.rect(), Qt.AlignCenter, "no position asked")
            return
        view, angle = _VIEWS[self.position]
        p.drawText(8, 16, "seen from the side, nose →" if view == "side" else "seen from the front, nose towards you")
        p.translate(w / 2, ground - 34)
        p.rotate(angle)
        p.setPen(QPen(QColor("#ddd"), 3))
        p.setBrush(QColor("#3a6ea5"))
        p.drawRoundedRect(QRectF(-40, -8, 80, 16), 4, 4)            # the body
        for x in (-36, 36):                                          # arms and propellers, on top
            p.drawLine(QPointF(x, -8), QPointF(x, -18))
            p.drawLine(QPointF(x - 16, -18), QPointF(x + 16, -18))
        p.setPen(QPen(QColor("#e0a030"), 3))
        if view == "side":                                           # the nose: an arrow to the front
            p.drawLine(QPointF(20, 0), QPointF(56, 0))
            p.drawLine(QPointF(56, 0), QPointF(48, -6))
            p.drawLine(QPointF(56, 0), QPointF(48, 6))
        else:
            p.drawEllipse(QPointF(0, 0), 5, 5)                        # the nose towards the viewer
