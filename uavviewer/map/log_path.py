"""A reviewed flight's path on a :class:`~uavviewer.map.map_view.MapView` (one of its ``overlays``): the track
coloured by flight mode, and a marker where the review's time cursor is."""
from __future__ import annotations

import bisect

from PyQt5.QtCore import QObject, QPointF, Qt, pyqtSignal
from PyQt5.QtGui import QColor, QPen

from .geometry import MapFrame

__all__ = ["LogPathOverlay", "mode_colour"]

_PALETTE = ["#4fc3f7", "#81c784", "#ffb74d", "#e57373", "#ba68c8", "#fff176", "#4db6ac", "#f06292", "#a1887f"]
_FIXED = {"STABILIZE": "#9e9e9e", "ALT_HOLD": "#4fc3f7", "LOITER": "#81c784", "GUIDED": "#ffb74d",
          "AUTO": "#ba68c8", "RTL": "#e57373", "LAND": "#fff176", "POSHOLD": "#4db6ac", "SMART_RTL": "#f06292"}


def mode_colour(mode: str) -> QColor:
    """One colour per flight mode, the same in the map's path and the review's legend."""
    return QColor(_FIXED.get(mode) or _PALETTE[sum(map(ord, mode)) % len(_PALETTE)])


PICK_PX = 12                  # a click this near the path picks its nearest point


class LogPathOverlay(QObject):
    """``set_path(t, lat, lon, modes)`` once; ``set_time(t)`` moves the marker (the nearest earlier fix); a click
    on the path gives that point's time (``timePicked``), so the map moves the review's cursor too."""

    timePicked = pyqtSignal(float)

    def __init__(self, view, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.view = view
        self._times: list[float] = []
        self._points: list[tuple[float, float]] = []
        self._modes: list[str] = []
        self.marker: int | None = None              # index of the fix under the cursor
        self._fitted_to = None                      # the view size the path was fitted to, or "panned"
        self._centre_fitted = None
        view.overlays.append(self.paint)
        view.mouse_parts.append(self)

    def set_path(self, t, lat, lon, modes: list[str]) -> None:
        if len(t) == 0:
            return
        frame = MapFrame(float(lat[0]), float(lon[0]))
        self.view.frame = frame
        self._times = [float(x) for x in t]
        self._points = [frame.to_view(float(a), float(b)) for a, b in zip(lat, lon)]
        self._modes = list(modes)
        self.marker = 0
        self.view.follow = False
        self._fitted_to = self._centre_fitted = None
        self.view.update()

    def _fit(self) -> None:
        """The whole path in view, at the view's size when it is first painted (or resized before a pan)."""
        size = (self.view.width(), self.view.height())
        if self._fitted_to == size or self._fitted_to == "panned":
            return
        self._fitted_to = size
        xs = [p[0] for p in self._points]
        ys = [p[1] for p in self._points]
        self.view.centre = ((max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2)
        self.view.mpp = max(max(xs) - min(xs), 1.0) * 1.15 / max(50, size[0])
        self.view.mpp = max(self.view.mpp, max(max(ys) - min(ys), 1.0) * 1.15 / max(50, size[1]), 0.05)
        self.view.update()                          # the map under the path is drawn again at this scale

    def set_time(self, t: float) -> None:
        if not self._times:
            return
        i = max(0, bisect.bisect_right(self._times, t) - 1)
        if i != self.marker:
            self.marker = i
            self.view.update()

    # -- the map's mouse (MapView.mouse_parts) -------------------------------------------------------------------
    def mouse_press(self, view, event) -> bool:
        return False

    def mouse_move(self, view, event) -> bool:
        return False

    def mouse_release(self, view, event, clicked: bool) -> bool:
        if not clicked or not self._points:
            return False
        at = QPointF(event.pos())
        best, index = PICK_PX, None
        for i, point in enumerate(self._points):
            q = view.to_screen(*point)
            d = abs(q.x() - at.x()) + abs(q.y() - at.y())
            if d <= best:
                best, index = d, i
        if index is None:
            return False
        self.marker = index
        view.update()
        self.timePicked.emit(self._times[index])
        return True

    def marker_place(self) -> tuple[float, float] | None:
        """The marker in view metres (east, north)."""
        return None if self.marker is None else self._points[self.marker]

    def paint(self, p, view) -> None:
        if len(self._points) < 2:
            return
        if self._centre_fitted is not None and self.view.centre != self._centre_fitted:
            self._fitted_to = "panned"                  # the pilot moved the map: leave it where it is
        self._fit()
        self._centre_fitted = self.view.centre
        start = 0
        for i in range(1, len(self._points) + 1):      # one polyline per run of the same mode
            if i == len(self._points) or self._modes[i] != self._modes[start]:
                p.setPen(QPen(mode_colour(self._modes[start]), 3))
                p.drawPolyline(*[view.to_screen(*self._points[k]) for k in range(max(0, start - 1), i)])
                start = i
        if self.marker is not None:
            at = view.to_screen(*self._points[self.marker])
            p.setPen(QPen(Qt.black, 2))
            p.setBrush(QColor("#ffffff"))
            p.drawEllipse(at, 7, 7)
            p.drawEllipse(at, 2, 2)
