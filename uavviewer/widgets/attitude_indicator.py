"""Artificial horizon, pitch ladder, roll arc, heading tape and altitude/speed readouts.

Drawn as the pilot sees it from the cockpit: nose up moves the horizon down,
a right roll turns the horizon to the left (counter-clockwise on screen).
"""
from __future__ import annotations

import math

from PyQt5.QtCore import QPointF, QRectF, Qt
from PyQt5.QtGui import QColor, QFont, QLinearGradient, QPainter, QPainterPath, QPen, QPolygonF
from PyQt5.QtWidgets import QSizePolicy, QWidget
from ..units import fmt as _fmt

__all__ = ["AttitudeIndicator"]

SKY_TOP = QColor(22, 92, 168)
SKY_HORIZON = QColor(86, 160, 230)
GROUND_HORIZON = QColor(150, 100, 55)
GROUND_BOTTOM = QColor(88, 58, 30)
SYMBOL = QColor(255, 196, 0)
PANEL = QColor(10, 14, 20, 190)
TEXT = QColor(235, 240, 245)


class AttitudeIndicator(QWidget):
    """Takes roll/pitch (radians), heading (degrees) and readouts; draws them."""

    VISIBLE_PITCH_DEG = 25.0   # from the centre to the top edge of the horizon area
    HEADING_SPAN_DEG = 90.0    # the whole width of the heading tape

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._roll = 0.0
        self._pitch = 0.0
        self._heading = 0.0
        self._altitude: float | None = None
        self._ground_speed: float | None = None
        self._climb: float | None = None
        self._valid = False
        self._flag = "NO ATTITUDE"
        self.setAttribute(Qt.WA_OpaquePaintEvent)
        self.setMinimumSize(200, 150)          # still readable at 1024×600
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Expanding)

    # -- values in ---------------------------------------------------------------------------
    def set_attitude(self, roll: float, pitch: float, heading_deg: float) -> None:
        """Roll and pitch in radians (right wing down and nose up positive), heading 0..360.

        A roll or pitch that is not a number means the attitude is unknown: the failure flag is shown."""
        if not (math.isfinite(roll) and math.isfinite(pitch)):
            if self._valid:
                self._valid, self._flag = False, "NO ATTITUDE"
                self.update()
            return
        values = [roll, pitch, heading_deg % 360.0 if math.isfinite(heading_deg) else 0.0]
        if values != [self._roll, self._pitch, self._heading] or not self._valid:
            self._roll, self._pitch, self._heading = values
            self._valid = True
            self.update()

    def set_readouts(self, altitude: float | None, ground_speed: float | None, climb: float | None) -> None:
        values = (altitude, ground_speed, climb)
        if values != (self._altitude, self._ground_speed, self._climb):
            self._altitude, self._ground_speed, self._climb = values
            self.update()

    def clear(self, reason: str = "NO ATTITUDE") -> None:
        """No vehicle or no link: the failure flag saying why, and dashes. The next attitude lifts it."""
        self._flag = reason
        self._valid = False
        self._roll = self._pitch = self._heading = 0.0
        self._altitude = self._ground_speed = self._climb = None
        self.update()

    @property
    def values(self) -> dict:
        """What is on display (for tests and tooltips)."""
        return {"roll": self._roll, "pitch": self._pitch, "heading": self._heading, "valid": self._valid,
                "flag": "" if self._valid else self._flag,
                "altitude": self._altitude, "ground_speed": self._ground_speed, "climb": self._climb}

    # -- geometry (public so tests can check pixels against it) -------------------------------
    def horizon_rect(self) -> QRectF:
        """The area of the artificial horizon (above the heading tape)."""
        return QRectF(0, 0, self.width(), self.height() - self._tape_height())

    def pixels_per_degree(self) -> float:
        return self.horizon_rect().height() / 2.0 / self.VISIBLE_PITCH_DEG

    def centre(self) -> QPointF:
        return self.horizon_rect().center()

    def horizon_y_at(self, x: float) -> float:
        """Screen y of the horizon line at screen x."""
        c = self.centre()
        # The horizon is shifted down by pitch in the rolled frame, then rotated counter-clockwise by roll.
        d = math.degrees(self._pitch) * self.pixels_per_degree()
        r = self._roll
        # A point (u, d) of the rolled frame maps to (c.x + u cos r + d sin r, c.y - u sin r + d cos r).
        u = (x - c.x() - d * math.sin(r)) / math.cos(r) if abs(math.cos(r)) > 1e-6 else 0.0
        return c.y() - u * math.sin(r) + d * math.cos(r)

    def _tape_height(self) -> int:
        return max(26, self.height() // 12)

    # -- drawing --------------------------------------------------------------------------------
    def paintEvent(self, event) -> None:  # noqa: N802 (Qt name)
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        p.fillRect(self.rect(), QColor(16, 20, 26))
        area = self.horizon_rect()
        if self._valid:
            p.save()
            p.setClipRect(area)
            self._draw_horizon(p, area)
            self._draw_ladder(p, area)
            p.restore()
            self._draw_roll_arc(p, area)
            self._draw_symbol(p, area)
        else:
            self._draw_failure_flag(p, area)
        self._draw_readouts(p, area)
        self._draw_heading_tape(p, QRectF(0, area.bottom(), self.width(), self.height() - area.height()))
        p.end()

    def _rolled_frame(self, p: QPainter, area: QRectF) -> None:
        p.translate(area.center())
        p.rotate(-math.degrees(self._roll))          # Qt turns clockwise; right roll turns the world left
        p.translate(0, math.degrees(self._pitch) * self.pixels_per_degree())   # nose up: horizon down

    def _draw_horizon(self, p: QPainter, area: QRectF) -> None:
        p.save()
        self._rolled_frame(p, area)
        big = 4.0 * (area.width() + area.height()) + abs(math.degrees(self._pitch)) * self.pixels_per_degree()
        half = area.height() / 2.0
        sky = QLinearGradient(0, -half * 1.5, 0, 0)
        sky.setColorAt(0, SKY_TOP)
        sky.setColorAt(1, SKY_HORIZON)
        sky.setSpread(QLinearGradient.PadSpread)
        ground = QLinearGradient(0, 0, 0, half * 1.5)
        ground.setColorAt(0, GROUND_HORIZON)
        ground.setColorAt(1, GROUND_BOTTOM)
        p.setPen(Qt.NoPen)
        p.fillRect(QRectF(-big, -big, 2 * big, big), sky)
        p.fillRect(QRectF(-big, 0, 2 * big, big), ground)
        p.setPen(QPen(QColor(255, 255, 255), 2))
        p.drawLine(QPointF(-big, 0), QPointF(big, 0))
        p.restore()

    def _draw_ladder(self, p: QPainter, area: QRectF) -> None:
        ppd = self.pixels_per_degree()
        p.save()
        self._rolled_frame(p, area)
        font = QFont(self.font())
        font.setPixelSize(max(10, int(area.height() / 28)))
        p.setFont(font)
        pitch_deg = math.degrees(self._pitch)
        width = area.width()
        for step in range(-90, 91, 5):
            if step == 0 or abs(step - pitch_deg) > self.VISIBLE_PITCH_DEG * 1.2:
                continue
            y = -step * ppd
            half = width * (0.09 if step % 10 == 0 else 0.045)
            p.setPen(QPen(QColor(255, 255, 255, 230), 1.6))
            p.drawLine(QPointF(-half, y), QPointF(half, y))
            if step % 10 == 0:
                label = f"{abs(step)}"
                p.drawText(QRectF(half + 4, y - 10, 40, 20), Qt.AlignLeft | Qt.AlignVCenter, label)
                p.drawText(QRectF(-half - 44, y - 10, 40, 20), Qt.AlignRight | Qt.AlignVCenter, label)
        p.restore()

    def _draw_roll_arc(self, p: QPainter, area: QRectF) -> None:
        c = area.center()
        radius = min(area.width(), area.height()) * 0.42
        p.save()
        p.translate(c)
        p.setPen(QPen(QColor(255, 255, 255, 220), 2))
        p.drawArc(QRectF(-radius, -radius, 2 * radius, 2 * radius), 30 * 16, 120 * 16)
        for tick in (-60, -45, -30, -20, -10, 0, 10, 20, 30, 45, 60):
            p.save()
            p.rotate(tick)
            length = radius * (0.1 if tick % 30 == 0 else 0.06)
            p.drawLine(QPointF(0, -radius), QPointF(0, -radius - length))
            p.restore()
        # Pointer: turns with the world, so on a right roll it swings to the left of the zero mark.
        p.rotate(-math.degrees(self._roll))
        p.setPen(Qt.NoPen)
        p.setBrush(SYMBOL)
        s = radius * 0.07
        p.drawPolygon(QPolygonF([QPointF(0, -radius + 2), QPointF(-s, -radius + 2 + 1.6 * s),
                                 QPointF(s, -radius + 2 + 1.6 * s)]))
        p.restore()

    def _draw_symbol(self, p: QPainter, area: QRectF) -> None:
        c = area.center()
        w = area.width() * 0.12
        p.save()
        p.translate(c)
        pen = QPen(QColor(20, 20, 20), 7, Qt.SolidLine, Qt.RoundCap, Qt.RoundJoin)
        path = QPainterPath()
        path.moveTo(-w * 1.6, 0)
        path.lineTo(-w * 0.55, 0)
        path.lineTo(-w * 0.3, w * 0.22)
        path.moveTo(w * 1.6, 0)
        path.lineTo(w * 0.55, 0)
        path.lineTo(w * 0.3, w * 0.22)
        p.setPen(pen)
        p.drawPath(path)
        p.setPen(QPen(SYMBOL, 4, Qt.SolidLine, Qt.RoundCap, Qt.RoundJoin))
        p.drawPath(path)
        p.setBrush(SYMBOL)
        p.drawEllipse(QPointF(0, 0), 3.5, 3.5)
        p.restore()

    def _readout_box(self, p: QPainter, rect: QRectF, title: str, value: str, unit: str) -> None:
        p.setPen(Qt.NoPen)
        p.setBrush(PANEL)
        p.drawRoundedRect(rect, 5, 5)
        small = QFont(self.font())
        small.setPixelSize(max(9, int(rect.height() * 0.24)))
        big = QFont(self.font())
        big.setPixelSize(max(12, int(rect.height() * 0.44)))
        big.setBold(True)
        p.setPen(QColor(160, 175, 190))
        p.setFont(small)
        p.drawText(rect.adjusted(6, 2, -6, 0), Qt.AlignLeft | Qt.AlignTop, title)
        p.drawText(rect.adjusted(6, 0, -6, -3), Qt.AlignRight | Qt.AlignBottom, unit)
        p.setPen(TEXT)
        p.setFont(big)
        p.drawText(rect.adjusted(6, 0, -6, 0), Qt.AlignCenter, value)

    def readout_rects(self) -> dict[str, QRectF]:
        """Where the SPEED, ALT and CLIMB boxes stand (what sits over the instrument keeps clear of them)."""
        area = QRectF(self.horizon_rect())
        bw = max(70.0, area.width() * 0.15)
        bh = max(36.0, area.height() * 0.12)
        cy = area.center().y()
        right = QRectF(area.right() - 8 - bw, cy - bh / 2, bw, bh)
        return {"SPEED": QRectF(area.left() + 8, cy - bh / 2, bw, bh), "ALT": right,
                "CLIMB": QRectF(right.left(), right.bottom() + 6, bw, bh * 0.8)}

    def _draw_readouts(self, p: QPainter, area: QRectF) -> None:
        boxes = self.readout_rects()
        self._readout_box(p, boxes["SPEED"], "SPEED", _fmt(self._ground_speed), "m/s")
        self._readout_box(p, boxes["ALT"], "ALT", _fmt(self._altitude), "m")
        self._readout_box(p, boxes["CLIMB"], "CLIMB", _fmt(self._climb), "m/s")

    def _draw_failure_flag(self, p: QPainter, area: QRectF) -> None:
        """No attitude known: no horizon at all (a level one would lie), but the avionics red X."""
        p.fillRect(area, QColor(28, 32, 38))
        p.setPen(QPen(QColor(200, 50, 50, 160), 3))
        p.drawLine(area.topLeft(), area.bottomRight())
        p.drawLine(area.topRight(), area.bottomLeft())
        font = QFont(self.font())
        font.setPixelSize(max(12, int(area.height() / 14)))
        font.setBold(True)
        p.setFont(font)
        label = QRectF(0, 0, area.width() * 0.5, font.pixelSize() * 2.0)
        label.moveCenter(area.center())
        p.fillRect(label, QColor(16, 20, 26))
        p.setPen(QColor(230, 80, 80))
        p.drawText(label, Qt.AlignCenter, self._flag)

    def _draw_heading_tape(self, p: QPainter, rect: QRectF) -> None:
        p.fillRect(rect, QColor(12, 16, 22))
        if not self._valid:                           # no scale to read a heading from: only the "---" box
            self._draw_heading_box(p, rect)
            return
        ppd = rect.width() / self.HEADING_SPAN_DEG
        cx = rect.center().x()
        p.setFont(self._tape_font(rect))
        first = int(math.floor(self._heading - self.HEADING_SPAN_DEG / 2)) // 5 * 5
        for deg in range(first, first + int(self.HEADING_SPAN_DEG) + 10, 5):
            x = cx + (deg - self._heading) * ppd
            if not rect.left() - 20 <= x <= rect.right() + 20:
                continue
            major = deg % 30 == 0
            p.setPen(QPen(QColor(200, 210, 220), 1.5))
            p.drawLine(QPointF(x, rect.top()), QPointF(x, rect.top() + rect.height() * (0.35 if major else 0.18)))
            if major and abs(x - cx) > 42:         # the current-heading box covers the middle
                d = deg % 360
                label = {0: "N", 90: "E", 180: "S", 270: "W"}.get(d, f"{d:03d}")
                p.drawText(QRectF(x - 20, rect.top() + rect.height() * 0.35, 40, rect.height() * 0.6),
                           Qt.AlignCenter, label)
        self._draw_heading_box(p, rect)

    def _tape_font(self, rect: QRectF) -> QFont:
        font = QFont(self.font())
        font.setPixelSize(max(10, int(rect.height() * 0.42)))
        return font

    def _draw_heading_box(self, p: QPainter, rect: QRectF) -> None:
        box = QRectF(rect.center().x() - 30, rect.top() + 1, 60, rect.height() - 2)
        p.setPen(QPen(SYMBOL, 1.5))
        p.setBrush(QColor(0, 0, 0, 220))
        p.drawRoundedRect(box, 4, 4)
        p.setPen(TEXT)
        bold = self._tape_font(rect)
        bold.setBold(True)
        p.setFont(bold)
        p.drawText(box, Qt.AlignCenter, f"{self._heading:03.0f}°" if self._valid else "---")
