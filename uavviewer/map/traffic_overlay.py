"""ADS-B traffic on the map: each contact the vehicle forwards, where it was last heard, turned to its heading (a
round mark when its heading is unknown: never an arrow pointing a guess), with its callsign, height relative to us
and how long ago it was heard; faded once stale, gone when the driver drops it (driver.traffic); red while its
closest approach comes within the alert limits."""
from __future__ import annotations

from PyQt5.QtCore import QObject, QPointF, Qt
from PyQt5.QtGui import QColor, QFont, QPen

from driver.traffic.model import Contact

__all__ = ["TrafficOverlay", "contact_label"]

AIRCRAFT = QColor("#4fc3f7")
#: Where a contact's label may go from its mark: upper right, lower right, upper left, lower left, further out.
LABEL_SPOTS = [QPointF(10, -10), QPointF(10, 18), QPointF(-10, -10), QPointF(-10, 18), QPointF(10, -26),
               QPointF(10, 34)]
ALERT = QColor("#e53935")


def contact_label(c: Contact) -> str:
    """"N123AB +120 m 3 s": callsign, height above (+) or below (-) us, age."""
    height = "" if c.relative_alt is None else f" {c.relative_alt:+.0f} m"
    return f"{c.label}{height} {c.age:.0f} s"


class TrafficOverlay(QObject):
    """Draws on a :class:`~uavviewer.map.map_view.MapView` (its ``overlays``)."""

    def __init__(self, view, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.view = view
        self.contacts: tuple[Contact, ...] = ()
        self._shown: tuple = ()
        view.overlays.append(self.paint)

    def show_state(self, s) -> None:
        self.contacts = s.traffic.contacts
        key = tuple((c.icao, round(c.lat, 6), round(c.lon, 6), c.stale, c.alert, round(c.age)) for c in self.contacts)
        if key != self._shown:
            self._shown = key
            self.view.update()

    def marks(self) -> list[tuple[float, float, Contact]]:
        """Each contact in view metres (east, north); none before the map has its frame (home)."""
        frame = self.view.frame
        if frame is None:
            return []
        return [(*frame.to_view(c.lat, c.lon), c) for c in self.contacts]

    def paint(self, p, view) -> None:
        p.setFont(QFont(view.font().family(), 8))
        for east, north, c in self.marks():
            at = view.to_screen(east, north)
            colour = QColor(ALERT if c.alert else AIRCRAFT)
            p.setOpacity(0.35 if c.stale else 1.0)
            if c.heading_deg is None:
                _dot(p, at, colour)
            else:
                view._arrow(p, at, c.heading_deg, colour, 0.7)
            view.labels.place(p, at, contact_label(c), LABEL_SPOTS)   # clear of the rings' and each other's
        p.setOpacity(1.0)


def _dot(p, at: QPointF, fill: QColor, radius: float = 4.5) -> None:
    """A contact whose heading is unknown: where it is, pointing nowhere."""
    p.save()
    p.setPen(QPen(Qt.black, 1.5))
    p.setBrush(fill)
    p.drawEllipse(at, radius, radius)
    p.restore()
