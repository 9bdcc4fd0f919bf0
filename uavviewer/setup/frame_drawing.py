"""The motor layout drawn from above, as AP_MotorsMatrix sets it up: each motor at its angle with its output
number, its letter in the motor test's order (A = test 1) and its spin direction (green clockwise, blue
counter-clockwise, with an arrow)."""
from __future__ import annotations

import math

from PyQt5.QtCore import QPointF, QRectF, Qt
from PyQt5.QtGui import QColor, QPainter, QPen
from PyQt5.QtWidgets import QWidget

__all__ = ["FrameDrawing", "LAYOUTS"]

CW, CCW = "CW", "CCW"
# (FRAME_CLASS, FRAME_TYPE) → per output 1..n: (angle from the nose, clockwise, spin, test order)
LAYOUTS = {
    (1, 0): ((90, CCW, 2), (-90, CCW, 4), (0, CW, 1), (180, CW, 3)),                            # quad +
    (1, 1): ((45, CCW, 1), (-135, CCW, 3), (-45, CW, 4), (135, CW, 2)),                         # quad X
    (2, 0): ((0, CW, 1), (180, CCW, 4), (-120, CW, 5), (60, CCW, 2), (-60, CCW, 6), (120, CW, 3)),   # hexa +
    (2, 1): ((90, CW, 2), (-90, CCW, 5), (-30, CW, 6), (150, CCW, 3), (30, CCW, 1), (-150, CW, 4)),  # hexa X
}


class FrameDrawing(QWidget):
    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.frame: tuple[int, int] | None = None
        self.setMinimumSize(220, 220)

    def set_frame(self, frame_class: int | None, frame_type: int | None) -> None:
        frame = None if frame_class is None or frame_type is None else (int(frame_class), int(frame_type))
        if frame != self.frame:
            self.frame = frame
            self.update()

    @property
    def motors(self) -> tuple | None:
        return LAYOUTS.get(self.frame) if self.frame else None

    def paintEvent(self, _event) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        motors = self.motors
        if motors is None:
            p.drawText(self.rect(), Qt.AlignCenter | Qt.TextWordWrap,
                       "No drawing for this frame" if self.frame else "Frame not read yet")
            return
        side = min(self.width(), self.height())
        p.translate(self.width() / 2, self.height() / 2)
        arm, prop = side * 0.34, side * 0.11
        p.setPen(QPen(QColor("#999"), 2))
        p.setBrush(QColor("#555"))
        p.drawEllipse(QPointF(0, 0), side * 0.07, side * 0.07)
        p.setPen(QPen(QColor("#e0a030"), 3))                      # the nose
        p.drawLine(QPointF(0, -side * 0.07), QPointF(0, -side * 0.2))
        p.drawText(QRectF(-30, -side * 0.5, 60, 16), Qt.AlignCenter, "front")
        for output, (angle, spin, test) in enumerate(motors, start=1):
            a = math.radians(angle)
            centre = QPointF(arm * math.sin(a), -arm * math.cos(a))
            p.setPen(QPen(QColor("#999"), 3))
            p.drawLine(QPointF(0, 0), centre)
            colour = QColor("#2e7d32") if spin == CW else QColor("#1565c0")
            p.setPen(QPen(colour, 3))
            p.setBrush(colour.lighter(170))
            p.drawEllipse(centre, prop, prop)
            # the spin: an arrowhead on the rim, pointing the way the propeller turns
            tip = QPointF(centre.x(), centre.y() - prop)
            d = 6 if spin == CW else -6
            p.drawLine(tip, QPointF(tip.x() - d, tip.y() - 5))
            p.drawLine(tip, QPointF(tip.x() - d, tip.y() + 5))
            p.setPen(Qt.black)
            p.drawText(QRectF(centre.x() - prop, centre.y() - prop, 2 * prop, 2 * prop), Qt.AlignCenter,
                       f"{output}\n{chr(ord('A') + test - 1)} {spin}")
