"""Where home is, seen from the cockpit: an arrow turned relative to the nose, and the distance.

It sits in a corner of the instrument it is given (the attitude indicator), over it but transparent to the mouse,
and follows that instrument's size; it never needs a place of its own in the layout. It keeps clear of the
instrument's readout boxes: on a short indicator (1024×600) "home 0.0 m" covered the ALT box's label, so there the
distance stands left of a smaller dial instead of under it.
"""
from __future__ import annotations

import math

from PyQt5.QtCore import QEvent, QObject, QPointF, QRectF, Qt
from PyQt5.QtGui import QColor, QFont, QPainter, QPen, QPolygonF
from PyQt5.QtWidgets import QWidget

from driver.vehicle.state import LinkStatus, VehicleState

__all__ = ["HomeArrow", "home_direction"]

SIZE = 84                    # the dial's diameter on a roomy indicator; smaller on a small one
MIN = 52                     # under this, the distance goes beside the dial
LEAST = 30                   # the smallest dial, beside its distance
TEXT_H = 18                  # px: the distance's line
TEXT_W = 74                  # px: "home 120 m" beside the dial


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
        self._beside = False                       # the distance left of the dial, not under it
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
        dial = int(max(MIN, min(SIZE, 0.26 * min(parent.width(), parent.height()))))
        boxes = parent.readout_rects() if hasattr(parent, "readout_rects") else {}
        below = [r.top() for r in boxes.values() if r.right() >= parent.width() - SIZE - TEXT_W]
        room = int(min(below)) - 6 - 4 if below else dial + TEXT_H      # above the ALT box, 4 px apart
        self._beside = dial + TEXT_H > room
        if self._beside:
            self._dial = max(LEAST, min(dial, room))
            self.setFixedSize(TEXT_W + self._dial, self._dial)
        else:
            self._dial = dial
            self.setFixedSize(SIZE, self._dial + TEXT_H)       # as wide as the distance needs, the dial centred
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
        left = TEXT_W if self._beside else (SIZE - size) / 2
        dial = QRectF(left + 4, 4, size - 8, size - 8)
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
        if self._beside:
            p.drawText(QRectF(0, 0, TEXT_W, size), Qt.AlignRight | Qt.AlignVCenter, self.text)
        else:
            p.drawText(QRectF(0, size - 2, SIZE, TEXT_H), Qt.AlignCenter, self.text)
        p.end()
