"""Where home is, seen from the cockpit: an arrow turned relative to the nose, and the distance.

It sits in a corner of the instrument it is given (the attitude indicator), over it but transparent to the mouse,
and follows that instrument's size; it never needs a place of its own in the layout.
"""
from __future__ import annotations

import math

from PyQt5.QtCore import QEvent, QObject, QPointF, QRectF, Qt
from PyQt5.QtGui import QColor, QFont, QPainter, QPen, QPolygonF
from PyQt5.QtWidgets import QWidget

from driver.vehicle.state import LinkStatus, VehicleState

__all__ = ["HomeArrow", "home_direction"]

SIZE = 84                    # the dial's diameter on a roomy indicator; smaller on a small one, never under MIN
MIN = 52


def home_direction(s: VehicleState) -> tuple[float, float] | None:
    """(degrees to turn right to face home, metres to home) for the vehicle in ``s``; None without a position."""
    if s.local is None:
        return None
    north, east = s.local.north, s.local.east
    distance = s.distance_from_home
    bearing = math.degrees(math.atan2(-east, -north))          # from the vehicle to home, clockwise from north
    return (bearing - s.heading_deg + 180.0) % 360.0 - 180.0, distance


class HomeArrow(QWidget):
    def __init__(self, instrument: QWidget) -> None:
        super().__init__(instrument)
        self.setObjectName("homeArrow")
        self.setAttribute(Qt.WA_TransparentForMouseEvents)
        self._dial = SIZE
        self.relative: float | None = None         # degrees, positive: home is to the right of the nose
        self.distance: float | None = None
        self.stale = False
        self.setToolTip("Home: direction relative to the nose, and distance")
        instrument.installEventFilter(self)
        self._place()

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:  # noqa: N802
        if event.type() == QEvent.Resize:
            self._place()
        return False

    def _place(self) -> None:
        parent = self.parentWidget()
        self._dial = int(max(MIN, min(SIZE, 0.26 * min(parent.width(), parent.height()))))
        self.setFixedSize(SIZE, self._dial + 18)           # as wide as the distance needs, the dial centred
        self.move(max(0, parent.width() - self.width() - 6), 6)
        self.raise_()

    def set_state(self, s: VehicleState) -> None:
        found = home_direction(s)
        stale = s.link.status is not LinkStatus.OK
        relative, distance = found if found is not None else (None, None)
        if found is not None and self.relative is not None and abs(relative - self.relative) < 0.5 and \
                abs(distance - self.distance) < 0.5 and stale == self.stale:
            return                                   # nothing the eye would see
        self.relative, self.distance, self.stale = relative, distance, stale
        self.update()

    @property
    def text(self) -> str:
        if self.distance is None:
            return "home —"
        return f"home {self.distance:.0f} m" if self.distance >= 10 else f"home {self.distance:.1f} m"

    def paintEvent(self, event) -> None:  # noqa: N802
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        colour = QColor("#8a8f98") if self.stale or self.relative is None else QColor("#ffd54f")
        size = self._dial
        dial = QRectF((SIZE - size) / 2 + 4, 4, size - 8, size - 8)
        p.setPen(QPen(QColor(255, 255, 255, 90), 1.5))
        p.setBrush(QColor(0, 0, 0, 110))
        p.drawEllipse(dial)
        centre = dial.center()
        p.setPen(QPen(QColor(255, 255, 255, 160), 2))      # the nose, at the top
        p.drawLine(QPointF(centre.x(), dial.top() + 2), QPointF(centre.x(), dial.top() + 8))
        if self.relative is not None and self.distance is not None and self.distance >= 1.0:
            p.save()
            p.translate(centre)
            p.rotate(self.relative)
            r = dial.width() / 2 - 10
            p.setPen(Qt.NoPen)
            p.setBrush(colour)
            p.drawPolygon(QPolygonF([QPointF(0, -r), QPointF(r * 0.45, r * 0.55), QPointF(0, r * 0.25),
                                     QPointF(-r * 0.45, r * 0.55)]))
            p.restore()
        elif self.relative is not None:                   # over home: a dot, no direction to give
            p.setPen(Qt.NoPen)
            p.setBrush(colour)
            p.drawEllipse(centre, 5, 5)
        p.setPen(colour)
        font = QFont(self.font())
        font.setBold(True)
        font.setPixelSize(11)                              # "home 120 m" fits the corner on any screen
        p.setFont(font)
        p.drawText(QRectF(0, size - 2, SIZE, 18), Qt.AlignCenter, self.text)
        p.end()
