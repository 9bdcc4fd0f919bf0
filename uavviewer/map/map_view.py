"""The map canvas: vehicle, home, trail, go-to target, fence, rings, scale and north, over tiles or a grid.

Everything is placed in view metres (:class:`uavviewer.map.geometry.MapFrame`: east/north of home); the canvas only
turns them into pixels. It pans with the mouse, zooms with the wheel about the cursor, and offers
"Fly here" on a right click; what flying there means is decided elsewhere. In a fleet it also draws the
other vehicles (:class:`VehicleMark`), smaller and in their own colour, and says which one was clicked.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from PyQt5.QtCore import QPointF, QRectF, Qt, pyqtSignal
from PyQt5.QtGui import QColor, QFont, QFontMetricsF, QPainter, QPainterPath, QPen, QPolygonF
from PyQt5.QtWidgets import QMenu, QSizePolicy, QWidget

from .geometry import MAX_ZOOM, MapFrame, nice_scale, tile_zoom_for, tiles_covering
from .labels import LABEL_BOX, LABEL_TEXT, Labels
from ..units import fmt

__all__ = ["MapView", "VehicleMark", "TRAIL_BANDS"]

MIN_MPP, MAX_MPP = 0.05, 5000.0      # metres a pixel: street level to a whole region
TRAIL_BANDS = 8                      # the trail is drawn in this many bands, older ones fainter
BACKGROUND = QColor("#1b222b")
GRID = QColor(255, 255, 255, 28)
RING = QColor(255, 255, 255, 90)
RING_ON_TILES = QColor(0, 0, 0, 140)
TRAIL = QColor("#38b6ff")
FENCE = QColor("#ff4d4d")
TARGET = QColor("#ffb020")
HOME = QColor("#5fd068")
VEHICLE = QColor("#ffffff")
PICKED = QColor("#ffe14d")                   # the ring around the vehicle the sticks fly, in a fleet
PICKED_HALO = QColor(255, 225, 77, 70)
OTHER = QColor("#b48cff")                    # the fleet's other vehicles
STALE = QColor("#7f8791")                    # a vehicle whose state may be old: as the Fleet panel greys it
HIT_PX = 16                                  # a click this near another vehicle's icon picks it


@dataclass(frozen=True)
class VehicleMark:
    """Another vehicle of the fleet: where it is (view metres), its heading, its name; stale ones are greyed."""
    name: str
    east: float
    north: float
    heading: float
    stale: bool = False


class MapView(QWidget):
    """Paints what it is given; pans, zooms and asks to fly somewhere."""

    flyHereRequested = pyqtSignal(float, float)     # north, east: metres from home
    followChanged = pyqtSignal(bool)                # the pilot panned (False) or re-centred (True)
    vehicleClicked = pyqtSignal(str)                # a click on another vehicle of the fleet: its name

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Expanding)
        self.setMinimumSize(200, 136)             # beside the Plan list at 1024×600: room to aim a click
        self.setMouseTracking(False)
        self.setFocusPolicy(Qt.ClickFocus)
        self.frame: MapFrame | None = None           # None: no home with a latitude yet (metres only)
        self.mpp = 0.5                               # metres per pixel
        self.centre = (0.0, 0.0)                     # view metres (east, north) at the widget's centre
        self.follow = True
        self.vehicle: tuple[float, float, float] | None = None    # east, north, heading degrees
        self._shown: tuple[float, float, float] | None = None     # ... as last painted
        self.vehicle_name = ""                       # in a fleet: the picked vehicle's name, written beside it
        self.vehicle_stale = False
        self.others: tuple[VehicleMark, ...] = ()    # the fleet's other vehicles
        self.home_visible = False
        self.target: tuple[float, float] | None = None
        self.fence_radius: float | None = None
        self.fence_breached = False                  # drawn solid and thick while the vehicle is outside it
        self.fence_ceiling: float | None = None      # written beside the circle
        self.tiles = None                            # a TileSource, or None for the offline grid
        self.attribution = ""
        self.fly_here_text = ""                      # "Fly here at 5 m", or why not: "" hides the item
        self.fly_here_enabled = False
        self._bands: list[list[QPointF]] = [[] for _ in range(TRAIL_BANDS)]   # view metres, oldest band first
        self._drag: QPointF | None = None
        self._dragged = False                        # the press became a pan: its release is no click
        # parts that may take the mouse first (the plan in Plan mode: uavviewer/plan/layer.py): mouse_press,
        # mouse_move(view, event) and mouse_release(view, event, clicked) return True when they took it
        self.mouse_parts: list = []
        self._drag_centre = self.centre
        self.paints = 0                              # paint events so far (tests see the UI keeps painting)
        self.drawn_tiles = 0                         # tiles drawn in the last paint
        self.overlays: list = []                     # parts drawing over the map: f(painter, view) (camera_overlay)
        self.menu_parts: list = []                   # parts adding to the right-click menu: f(menu, north, east)
        self.labels = Labels()                       # the paint's labels, none over another (traffic_overlay)

    # -- what to show ---------------------------------------------------------------------------
    def set_vehicle(self, where: tuple[float, float, float] | None) -> None:
        """East, north (view metres) and heading; repainted only when that shows (half a pixel, half a degree)."""
        old, self.vehicle = self._shown, where
        if where is not None and self.follow:
            self.centre = (where[0], where[1])
        if (old is None) != (where is None) or where is not None and (
                math.hypot(where[0] - old[0], where[1] - old[1]) >= 0.5 * self.mpp
                or abs((where[2] - old[2] + 180.0) % 360.0 - 180.0) >= 0.5):
            self._shown = where
            self.update()

    def set_fleet(self, name: str, stale: bool, others: tuple[VehicleMark, ...]) -> None:
        """The picked vehicle's name and staleness, and the other vehicles; repainted only when that changed."""
        if (name, stale, others) != (self.vehicle_name, self.vehicle_stale, self.others):
            self.vehicle_name, self.vehicle_stale, self.others = name, stale, others
            self.update()

    def vehicle_at(self, point: QPointF) -> str:
        """The other vehicle whose icon is under a widget point ("" for none): the nearest within HIT_PX."""
        near = [(math.hypot(q.x() - point.x(), q.y() - point.y()), m.name)
                for m in self.others for q in [self.to_screen(m.east, m.north)]]
        best = min(near, default=(HIT_PX + 1.0, ""))
        return best[1] if best[0] <= HIT_PX else ""

    def set_trail(self, bands: list[list[tuple[float, float]]]) -> None:
        """Trail points in view metres, in TRAIL_BANDS lists from the oldest to the newest."""
        self._bands = [[QPointF(e, n) for e, n in band] for band in bands]
        self.update()

    @property
    def trail_points(self) -> int:
        return sum(len(b) for b in self._bands)

    def set_tiles(self, source, attribution: str = "") -> None:
        if self.tiles is not None:
            self.tiles.tileReady.disconnect(self._tile_ready)
        self.tiles = source
        self.attribution = attribution
        if source is not None:
            source.tileReady.connect(self._tile_ready)
        self.update()

    def set_follow(self, follow: bool) -> None:
        if follow != self.follow:
            self.follow = follow
            if follow and self.vehicle is not None:
                self.centre = (self.vehicle[0], self.vehicle[1])
            self.followChanged.emit(follow)
            self.update()

    def zoom_to(self, mpp: float, about: QPointF | None = None) -> None:
        """Metres per pixel, keeping the view metre under ``about`` (a widget point) where it is."""
        mpp = min(MAX_MPP, max(MIN_MPP, mpp))
        if about is not None and not self.follow:
            e, n = self.view_at(about)
            self.mpp = mpp
            e2, n2 = self.view_at(about)
            self.centre = (self.centre[0] + e - e2, self.centre[1] + n - n2)
        self.mpp = mpp
        self.update()

    # -- geometry -------------------------------------------------------------------------------
    def to_screen(self, east: float, north: float) -> QPointF:
        return QPointF(self.width() / 2.0 + (east - self.centre[0]) / self.mpp,
                       self.height() / 2.0 - (north - self.centre[1]) / self.mpp)

    def view_at(self, point: QPointF) -> tuple[float, float]:
        return (self.centre[0] + (point.x() - self.width() / 2.0) * self.mpp,
                self.centre[1] - (point.y() - self.height() / 2.0) * self.mpp)

    def visible_tiles(self):
        """The tiles the view needs now, centre first ([] without a tile source or a latitude)."""
        if self.tiles is None or self.frame is None:
            return []
        w, n = self.view_at(QPointF(0, 0))
        e, s = self.view_at(QPointF(self.width(), self.height()))
        z = tile_zoom_for(self.mpp, self.frame.lat, MAX_ZOOM)
        return tiles_covering(self.frame, w, n, e, s, z, limit=64)

    # -- mouse ----------------------------------------------------------------------------------
    def mousePressEvent(self, event) -> None:  # noqa: N802
        if any(part.mouse_press(self, event) for part in self.mouse_parts):
            return
        if event.button() == Qt.LeftButton:
            self._drag = QPointF(event.pos())
            self._drag_centre = self.centre
            self._dragged = False
        super().mousePressEvent(event)

    def mouseMoveEvent(self, event) -> None:  # noqa: N802
        if any(part.mouse_move(self, event) for part in self.mouse_parts):
            return
        if self._drag is not None:
            d = QPointF(event.pos()) - self._drag
            self._dragged = self._dragged or abs(d.x()) + abs(d.y()) >= 3
            if self._dragged or not self.follow:
                self.set_follow(False)
                self.centre = (self._drag_centre[0] - d.x() * self.mpp, self._drag_centre[1] + d.y() * self.mpp)
                self.update()

    def mouseReleaseEvent(self, event) -> None:  # noqa: N802
        clicked = event.button() == Qt.LeftButton and self._drag is not None and not self._dragged
        self._drag = None
        if any(part.mouse_release(self, event, clicked) for part in self.mouse_parts):
            return
        name = self.vehicle_at(QPointF(event.pos())) if clicked else ""
        if name:
            self.vehicleClicked.emit(name)

    def wheelEvent(self, event) -> None:  # noqa: N802
        steps = event.angleDelta().y() / 120.0
        if steps:
            self.zoom_to(self.mpp * 2 ** (-steps / 2.0), QPointF(event.pos()))

    def contextMenuEvent(self, event) -> None:  # noqa: N802
        if not self.fly_here_text and not self.menu_parts:
            return
        east, north = self.view_at(QPointF(event.pos()))
        menu = QMenu(self)
        menu.setAttribute(Qt.WA_DeleteOnClose)            # one per right click: gone once closed
        menu.setObjectName("mapMenu")
        if self.fly_here_text:
            action = menu.addAction(self.fly_here_text)
            action.setEnabled(self.fly_here_enabled)
            action.triggered.connect(lambda: self.flyHereRequested.emit(north, east))
        for part in self.menu_parts:
            part(menu, north, east)
        if menu.isEmpty():
            menu.deleteLater()
            return
        menu.popup(event.globalPos())

    def _tile_ready(self, key) -> None:
        self.update()

    # -- painting -------------------------------------------------------------------------------
    def paintEvent(self, event) -> None:  # noqa: N802
        self.paints += 1
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        p.fillRect(self.rect(), BACKGROUND)
        self.labels.clear()
        self.drawn_tiles = self._paint_tiles(p)
        if not self.drawn_tiles:
            self._paint_grid(p)
        self._paint_rings(p)
        if self.fence_radius:
            p.setPen(QPen(FENCE, 4, Qt.SolidLine) if self.fence_breached else QPen(FENCE, 2, Qt.DashLine))
            p.setBrush(Qt.NoBrush)
            self._circle(p, self.fence_radius)
            text = f"fence {_distance(self.fence_radius)}" + (
                f", ceiling {_distance(self.fence_ceiling)}" if self.fence_ceiling else "") + (
                " — BREACHED" if self.fence_breached else "")
            p.setFont(QFont(self.font().family(), 8))
            self._label(p, self.to_screen(0.0, -self.fence_radius) + QPointF(4, 12), text)
        self._paint_trail(p)
        if self.home_visible:
            self._paint_home(p)
        if self.target is not None:
            self._paint_target(p)
        for mark in self.others:
            self._paint_other(p, mark)
        for overlay in self.overlays:
            overlay(p, self)
        if self.vehicle is not None:
            self._paint_vehicle(p)
        if self.vehicle_name or self.others:
            self._paint_names(p)
        self._paint_scale(p)
        self._paint_north(p)
        if self.attribution and self.drawn_tiles:
            self._paint_attribution(p)
        p.end()

    def _paint_tiles(self, p: QPainter) -> int:
        wanted = self.visible_tiles()
        if not wanted:
            return 0
        self.tiles.want([key for key, _ in wanted])
        drawn = 0
        for key, near in wanted:
            image = self.tiles.image(key)
            if image is None:
                continue
            w, n, e, s = self.frame.tile_rect(key, near)
            p.drawImage(QRectF(self.to_screen(w, n), self.to_screen(e, s)), image)
            drawn += 1
        return drawn

    def _paint_grid(self, p: QPainter) -> None:
        step = nice_scale(self.mpp, 90)
        if step <= 0:
            return
        w, n = self.view_at(QPointF(0, 0))
        e, s = self.view_at(QPointF(self.width(), self.height()))
        p.setPen(QPen(GRID, 1))
        x = math.floor(w / step) * step
        while x <= e:
            p.drawLine(self.to_screen(x, n), self.to_screen(x, s))
            x += step
        y = math.floor(s / step) * step
        while y <= n:
            p.drawLine(self.to_screen(w, y), self.to_screen(e, y))
            y += step

    def _circle(self, p: QPainter, radius: float) -> None:
        c = self.to_screen(0.0, 0.0)
        r = radius / self.mpp
        p.drawEllipse(c, r, r)

    def _paint_rings(self, p: QPainter) -> None:
        """Distance rings around home, labelled, every nice step that gives three to five of them."""
        step = nice_scale(self.mpp, min(self.width(), self.height()) / 5.0)
        if step <= 0:
            return
        p.setFont(QFont(self.font().family(), 8))
        for i in range(1, 6):
            p.setPen(QPen(RING if not self.drawn_tiles else RING_ON_TILES, 1, Qt.DotLine))
            p.setBrush(Qt.NoBrush)
            self._circle(p, i * step)
            self._label(p, self.to_screen(0.0, i * step) + QPointF(3, -3), _distance(i * step))

    def _paint_trail(self, p: QPainter) -> None:
        for i, band in enumerate(self._bands):
            if len(band) < 2:
                continue
            colour = QColor(TRAIL)
            colour.setAlpha(int(50 + 205 * (i + 1) / TRAIL_BANDS))
            p.setPen(QPen(colour, 2))
            p.drawPolyline(QPolygonF([self.to_screen(q.x(), q.y()) for q in band]))

    def _paint_home(self, p: QPainter) -> None:
        c = self.to_screen(0.0, 0.0)
        p.setPen(QPen(Qt.black, 1))
        p.setBrush(HOME)
        p.drawEllipse(c, 8, 8)
        p.setPen(Qt.black)
        p.setFont(QFont(self.font().family(), 8, QFont.Bold))
        p.drawText(QRectF(c.x() - 8, c.y() - 8, 16, 16), Qt.AlignCenter, "H")

    def _paint_target(self, p: QPainter) -> None:
        c = self.to_screen(*self.target)
        p.setPen(QPen(TARGET, 2))
        p.setBrush(Qt.NoBrush)
        p.drawEllipse(c, 9, 9)
        p.drawLine(c + QPointF(-13, 0), c + QPointF(13, 0))
        p.drawLine(c + QPointF(0, -13), c + QPointF(0, 13))
        if self.vehicle is not None:
            p.setPen(QPen(TARGET, 1, Qt.DashLine))
            p.drawLine(self.to_screen(self.vehicle[0], self.vehicle[1]), c)

    def _paint_vehicle(self, p: QPainter) -> None:
        east, north, heading = self.vehicle
        at = self.to_screen(east, north)
        if self.vehicle_name:                   # a fleet: a halo says which one the sticks fly
            p.setPen(QPen(PICKED, 2))
            p.setBrush(PICKED_HALO)
            p.drawEllipse(at, 19, 19)
        self._arrow(p, at, heading, STALE if self.vehicle_stale else VEHICLE, 1.0)

    def _paint_other(self, p: QPainter, mark: VehicleMark) -> None:
        self._arrow(p, self.to_screen(mark.east, mark.north), mark.heading, STALE if mark.stale else OTHER, 0.75)

    def name_boxes(self) -> list[tuple[QRectF, str, bool]]:
        """Where each vehicle's name goes (box, text, stale), the picked one's first and always; another name tries
        the right, left, below and above of its arrow, and is left out where it would cover a name or an arrow."""
        names = [(self.to_screen(m.east, m.north), m.name, False, m.stale, 12.0) for m in self.others]
        if self.vehicle is not None and self.vehicle_name:
            names.insert(0, (self.to_screen(self.vehicle[0], self.vehicle[1]), "▶ " + self.vehicle_name, True,
                             self.vehicle_stale, 21.0))
        arrows = [QRectF(at.x() - r, at.y() - r, 2 * r, 2 * r) for at, _, _, _, r in names]
        out: list[tuple[QRectF, str, bool]] = []
        for i, (at, text, picked, stale, r) in enumerate(names):
            metrics = QFontMetricsF(self._name_font(picked))
            w, h = metrics.horizontalAdvance(text) + 6.0, metrics.height() + 2.0
            sides = [QRectF(at.x() + r, at.y() - h / 2, w, h), QRectF(at.x() - r - w, at.y() - h / 2, w, h),
                     QRectF(at.x() - w / 2, at.y() + r, w, h), QRectF(at.x() - w / 2, at.y() - r - h, w, h)]
            free = [box for box in sides if not any(box.intersects(o) for o, _, _ in out)
                    and not any(box.intersects(a) for j, a in enumerate(arrows) if j != i)]
            box = free[0] if free else sides[0] if picked else None
            if box is not None:
                out.append((box, text, stale))
        return out

    def _name_font(self, picked: bool) -> QFont:
        return QFont(self.font().family(), 9 if picked else 8, QFont.Bold if picked else QFont.Normal)

    def _paint_names(self, p: QPainter) -> None:
        for box, text, stale in self.name_boxes():
            p.setFont(self._name_font(text.startswith("▶ ")))
            p.fillRect(box, LABEL_BOX)
            p.setPen(STALE if stale else LABEL_TEXT)
            p.drawText(box, Qt.AlignCenter, text)

    @staticmethod
    def _arrow(p: QPainter, at: QPointF, heading: float, fill: QColor, size: float) -> None:
        p.save()
        p.translate(at)
        p.rotate(heading)                       # clockwise on screen, like a heading
        p.scale(size, size)
        arrow = QPainterPath()
        arrow.moveTo(0, -14)
        arrow.lineTo(9, 10)
        arrow.lineTo(0, 5)
        arrow.lineTo(-9, 10)
        arrow.closeSubpath()
        p.setPen(QPen(Qt.black, 1.5))
        p.setBrush(fill)
        p.drawPath(arrow)
        p.restore()

    def _paint_scale(self, p: QPainter) -> None:
        length = nice_scale(self.mpp, self.width() / 4.0)
        if length <= 0:
            return
        px = length / self.mpp
        x0, y0 = 12.0, self.height() - 14.0
        p.setPen(QPen(Qt.black, 4))
        p.drawLine(QPointF(x0, y0), QPointF(x0 + px, y0))
        p.setPen(QPen(QColor("#e6ebf0"), 2))
        p.drawLine(QPointF(x0, y0), QPointF(x0 + px, y0))
        p.drawLine(QPointF(x0, y0 - 5), QPointF(x0, y0))
        p.drawLine(QPointF(x0 + px, y0 - 5), QPointF(x0 + px, y0))
        p.setFont(QFont(self.font().family(), 8))
        self._label(p, QPointF(x0 + 4, y0 - 5), _distance(length))

    def _paint_north(self, p: QPainter) -> None:
        x, y = self.width() - 22.0, 26.0
        p.setPen(QPen(Qt.black, 1))
        p.setBrush(QColor("#e6ebf0"))
        p.drawPolygon(QPolygonF([QPointF(x, y - 14), QPointF(x + 7, y + 6), QPointF(x, y + 2), QPointF(x - 7, y + 6)]))
        p.setFont(QFont(self.font().family(), 8, QFont.Bold))
        self._label(p, QPointF(x - 4, y + 18), "N")

    def _label(self, p: QPainter, at: QPointF, text: str) -> None:
        self.labels.draw(p, at, text)

    def _paint_attribution(self, p: QPainter) -> None:
        p.setFont(QFont(self.font().family(), 7))
        metrics = p.fontMetrics()
        w = metrics.horizontalAdvance(self.attribution) + 8
        box = QRectF(self.width() - w, self.height() - metrics.height() - 2, w, metrics.height() + 2)
        p.fillRect(box, QColor(255, 255, 255, 190))
        p.setPen(Qt.black)
        p.drawText(box, Qt.AlignCenter, self.attribution)


def _distance(metres: float) -> str:
    return f"{metres / 1000:g} km" if metres >= 1000 else f"{fmt(metres, 0)} m" if metres >= 1 else f"{metres:g} m"
