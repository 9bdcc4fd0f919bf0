"""The motor layout drawn from above, as AP_MotorsMatrix (AP_MotorsTri) sets it up (frames.py): each motor where its
factors put it, with its output number, its letter in the motor test's order (A = test 1) and its spin direction
(green clockwise, blue counter-clockwise, with an arrow). The two motors of a coaxial arm (octaquad, Y6,
dodecahexa) are drawn side by side so both numbers show; the tricopter's yaw servo is drawn and labelled."""
from __future__ import annotations

import math
from collections import defaultdict

from PyQt5.QtCore import QPointF, QRectF, Qt
from PyQt5.QtGui import QColor, QPainter, QPalette, QPen
from PyQt5.QtWidgets import QWidget

from .frames import CW, Layout, Motor, layout

__all__ = ["FrameDrawing"]

_CLASS_WORDS = {6: "a helicopter", 8: "a single-rotor copter", 9: "a coaxial copter", 10: "a bicopter",
                11: "a dual helicopter", 13: "a helicopter quad", 15: "a scripted matrix", 16: "a 6DoF scripted frame",
                17: "a scripted matrix"}


class FrameDrawing(QWidget):
    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.frame: tuple[int, int] | None = None
        self.layout_: Layout | None = None
        self.setMinimumSize(260, 260)

    def set_frame(self, frame_class: int | None, frame_type: int | None) -> None:
        frame = None if frame_class is None or frame_type is None else (int(frame_class), int(frame_type))
        if frame != self.frame:
            self.frame = frame
            self.layout_ = layout(*frame) if frame else None
            self.update()

    @property
    def motors(self) -> tuple[Motor, ...] | None:
        return self.layout_.motors if self.layout_ else None

    def missing(self) -> str:
        """Why nothing is drawn ("" when a layout is)."""
        if self.frame is None:
            return "Frame not read yet"
        if self.layout_ is not None:
            return ""
        what = _CLASS_WORDS.get(self.frame[0])
        return (f"No drawing for this frame: FRAME_CLASS {self.frame[0]} is {what}, not a motor matrix" if what else
                f"No drawing for this frame: ArduCopter sets up no motor matrix for FRAME_CLASS {self.frame[0]}, "
                f"FRAME_TYPE {self.frame[1]}")

    def paintEvent(self, _event) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        words = self.palette().color(QPalette.WindowText)          # the theme's text colour, light or dark
        if self.layout_ is None:
            p.setPen(words)
            p.drawText(self.rect(), Qt.AlignCenter | Qt.TextWordWrap, self.missing())
            return
        side = min(self.width(), self.height())
        p.translate(self.width() / 2, self.height() / 2)
        p.setPen(words)
        p.drawText(QRectF(-side / 2, side / 2 - 18, side, 18), Qt.AlignCenter, self.layout_.name)
        p.setPen(QPen(QColor("#999"), 2))
        p.setBrush(QColor("#555"))
        p.drawEllipse(QPointF(0, 0), side * 0.06, side * 0.06)
        p.setPen(QPen(QColor("#e0a030"), 3))                      # the nose
        p.drawLine(QPointF(0, -side * 0.06), QPointF(0, -side * 0.17))
        p.drawText(QRectF(-30, -side * 0.5 + 2, 60, 16), Qt.AlignCenter, "front")
        arms: dict[tuple, list[Motor]] = defaultdict(list)         # motors at one place: a coaxial arm
        for m in self.layout_.motors:
            arms[(round(m.angle), round(m.radius, 2))].append(m)
        longest = max(m.radius for m in self.layout_.motors)
        reach = side * 0.33
        ends = {place: QPointF(math.sin(math.radians(place[0])), -math.cos(math.radians(place[0])))
                * (reach * place[1] / longest) for place in arms}
        gaps = [math.hypot(a.x() - b.x(), a.y() - b.y()) for i, a in enumerate(ends.values())
                for b in list(ends.values())[i + 1:]]
        coaxial = any(len([m for m in motors if not m.servo]) > 1 for motors in arms.values())
        prop = min([side * 0.11] + [gap * (0.26 if coaxial else 0.46) for gap in gaps])
        for (angle, radius), motors in arms.items():
            a = math.radians(angle)
            across = QPointF(math.cos(a), math.sin(a))
            end = ends[(angle, radius)]
            p.setPen(QPen(QColor("#999"), 3))
            p.drawLine(QPointF(0, 0), end)
            servos = [m for m in motors if m.servo]
            rotors = [m for m in motors if not m.servo]
            for servo in servos:
                self._servo(p, end * 0.5, prop, servo)
            if len(rotors) == 1:
                self._rotor(p, end, prop, rotors[0])
            else:                                                  # coaxial: side by side across the arm
                for i, m in enumerate(rotors):
                    offset = (i - (len(rotors) - 1) / 2) * 2 * prop * 1.05
                    self._rotor(p, end + across * offset, prop, m)

    def _rotor(self, p: QPainter, centre: QPointF, prop: float, m: Motor) -> None:
        colour = QColor("#777") if m.spin is None else QColor("#2e7d32") if m.spin == CW else QColor("#1565c0")
        p.setPen(QPen(colour, 3))
        p.setBrush(colour.lighter(170))
        p.drawEllipse(centre, prop, prop)
        if m.spin is not None:                 # an arrowhead on the rim, pointing the way the propeller turns
            tip = QPointF(centre.x(), centre.y() - prop)
            d = 6 if m.spin == CW else -6
            p.drawLine(tip, QPointF(tip.x() - d, tip.y() - 5))
            p.drawLine(tip, QPointF(tip.x() - d, tip.y() + 5))
        p.setPen(Qt.black)
        p.drawText(QRectF(centre.x() - prop - 10, centre.y() - prop, 2 * prop + 20, 2 * prop), Qt.AlignCenter,
                   f"{m.output}\n{self.layout_.letters[m.output]} {m.spin or ''}".strip())

    def _servo(self, p: QPainter, centre: QPointF, prop: float, m: Motor) -> None:
        w, h = prop * 2.2, prop * 1.1
        p.setPen(QPen(QColor("#6a1b9a"), 2))
        p.setBrush(QColor("#e1bee7"))
        box = QRectF(centre.x() - w / 2, centre.y() - h / 2, w, h)
        p.drawRect(box)
        p.setPen(Qt.black)
        p.drawText(box, Qt.AlignCenter, f"{m.output} servo\n{self.layout_.letters[m.output]}")
