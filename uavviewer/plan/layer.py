"""The plan on the map: the mission's path and items, surveys, fences and rally points, drawn over the trail;
in Plan mode it also takes the mouse (a click adds, a drag moves an item or a vertex), and it adds to the
right-click menu (Skip to item N). One of the :class:`MapView`'s ``overlays``, ``menu_parts`` and ``mouse_parts``
(:meth:`PlanLayer.attach`); what a click means is decided by the plan editor and controller.
"""
from __future__ import annotations

import math

from PyQt5.QtCore import QLineF, QObject, QPointF, QRectF, Qt, pyqtSignal
from PyQt5.QtGui import QColor, QFont, QPainter, QPen, QPixmap, QPolygonF

from .checks import FenceCheck
from .model import PlanDocument, is_nav
from .survey import SurveySpec

__all__ = ["PlanLayer", "HIT_PX"]

HIT_PX = 12                                  # a press this near an item or vertex takes it
MARK_PX = 36                                 # the pixmap a marker is drawn into (its halo is 32 px across)
HOME_PX = 9.0                                # the home mark's radius (MapView draws it 8 px)
PATH = QColor("#ffb020")
ITEM = QColor("#ffb020")
SELECTED = QColor("#ffffff")
CURRENT = QColor("#4dff88")
ROI = QColor("#ff7ad9")
SURVEY = QColor(56, 182, 255, 50)
SURVEY_EDGE = QColor("#38b6ff")
INCLUDE = QColor(95, 208, 104, 45)
INCLUDE_EDGE = QColor("#5fd068")
EXCLUDE = QColor(255, 77, 77, 60)
EXCLUDE_EDGE = QColor("#ff4d4d")
RALLY = QColor("#b48cff")
DRAFT = QColor("#ffffff")
TEXT = QColor("#101418")
LABEL_BOX = QColor(20, 26, 34, 200)
BREACH = QColor("#ff2d2d")                   # what of the mission leaves the plan's own fence


class PlanLayer(QObject):
    """Draws a :class:`PlanDocument`; in edit mode reports clicks and drags in latitude/longitude."""

    clicked = pyqtSignal(float, float)               # lat, lon: a click on free map (edit mode)
    picked = pyqtSignal(str, int)                    # "mission"/"fence"/"rally", index: a press on it
    dragged = pyqtSignal(str, int, int, float, float)   # layer, index, vertex, lat, lon: while dragging
    contextRequested = pyqtSignal(object, object)    # hit (layer, index, vertex) or None, list to fill

    def __init__(self, doc: PlanDocument, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.editing = False
        self.selected: tuple[str, int] | None = None       # ("mission", entry index), ("fence", shape), ("rally", i)
        self.current: int | None = None                    # the vehicle's current item (its number)
        self.current_entry: int | None = None
        self.home: tuple[float, float] | None = None       # the path starts and RTL ends here
        self.draft: list[tuple[float, float]] = []         # a polygon being drawn
        self.progress = ""                                 # "Item 3 of 7 · 45 m, 9 s to it" while one flies
        self.breaches = FenceCheck()                       # waypoints and survey legs outside the plan's fence
        self._grab: tuple[str, int, int] | None = None     # what a press took: layer, index, vertex
        self._press: QPointF | None = None
        self._view = None
        self._placed: dict[tuple[float, float], tuple[float, float]] = {}   # (lat, lon) -> view metres
        self._placed_for = None                            # ... in this frame
        self._markers: dict[tuple, QPixmap] = {}           # each look of a marker, drawn once
        self._look: tuple = (1.0, "")

    # -- geometry ---------------------------------------------------------------------------------
    def _at(self, view, lat: float, lon: float) -> QPointF:
        """A place on screen; its view metres are worked out once per frame (home) and kept."""
        if self._placed_for is not view.frame:
            self._placed_for, self._placed = view.frame, {}
        where = self._placed.get((lat, lon))
        if where is None:
            if len(self._placed) > 5000:            # places dragged through: start again
                self._placed.clear()
            where = self._placed[(lat, lon)] = view.frame.to_view(lat, lon)
        return view.to_screen(*where)

    def hit(self, view, point: QPointF) -> tuple[str, int, int] | None:
        """The item, survey/fence vertex or rally point nearest ``point`` within HIT_PX."""
        if view.frame is None:
            return None
        best, found = HIT_PX + 0.1, None

        def near(lat: float, lon: float, what: tuple[str, int, int]) -> None:
            nonlocal best, found
            q = self._at(view, lat, lon)
            d = math.hypot(q.x() - point.x(), q.y() - point.y())
            if d <= best:
                best, found = d, what
        for i, entry in enumerate(self.doc.entries):
            if isinstance(entry, SurveySpec):
                for v, (lat, lon) in enumerate(entry.polygon):
                    near(lat, lon, ("mission", i, v))
            elif entry.has_position and (entry.lat or entry.lon):
                near(entry.lat, entry.lon, ("mission", i, 0))
        for i, shape in enumerate(self.doc.fence):
            for v, (lat, lon) in enumerate(shape.vertices):
                near(lat, lon, ("fence", i, v))
        for i, item in enumerate(self.doc.rally):
            near(item.lat, item.lon, ("rally", i, 0))
        return found

    # -- mouse (MapView.mouse_parts) -------------------------------------------------------------------
    def mouse_press(self, view, event) -> bool:
        if event.button() != Qt.LeftButton or view.frame is None:
            return False
        self._press = QPointF(event.pos())
        if not self.editing:
            return False
        self._grab = self.hit(view, QPointF(event.pos()))
        if self._grab is None:
            return False
        self.picked.emit(self._grab[0], self._grab[1])
        return True

    def mouse_move(self, view, event) -> bool:
        if self._grab is None or self._press is None:
            return False
        d = QPointF(event.pos()) - self._press
        if abs(d.x()) + abs(d.y()) >= 3:
            lat, lon = view.frame.to_latlon(*view.view_at(QPointF(event.pos())))
            self.dragged.emit(*self._grab, lat, lon)
        return True

    def mouse_release(self, view, event, clicked: bool) -> bool:
        grabbed, self._grab = self._grab, None
        press, self._press = self._press, None
        if grabbed is not None:
            return True
        if clicked and self.editing and press is not None and view.frame is not None \
                and not view.vehicle_at(QPointF(event.pos())):
            self.clicked.emit(*view.frame.to_latlon(*view.view_at(QPointF(event.pos()))))
            return True
        return False

    def attach(self, view) -> None:
        """Drawn on ``view``, in its right-click menu and first to its mouse."""
        self._view = view
        view.overlays.append(self)
        view.menu_parts.append(self.menu_part)
        view.mouse_parts.append(self)

    def menu_part(self, menu, north: float, east: float) -> None:
        """The right-click menu at a point (view metres): what the controller offers for the item there."""
        view = self._view
        if view is None or view.frame is None:
            return
        actions: list = []
        self.contextRequested.emit(self.hit(view, view.to_screen(east, north)), actions)
        for text, enabled, slot in actions:
            menu.addAction(text, slot).setEnabled(enabled)

    def __call__(self, p, view) -> None:
        """As one of the view's overlays."""
        self.paint(p, view)

    # -- painting ---------------------------------------------------------------------------------
    def paint(self, p, view) -> None:
        if view.frame is None:
            return
        p.save()
        font = QFont(view.font().family(), 8, QFont.Bold)
        p.setFont(font)
        self._look = (view.devicePixelRatioF(), font.key())     # what the cached markers were drawn for
        for i, shape in enumerate(self.doc.fence):
            self._paint_fence(p, view, shape, self.selected == ("fence", i))
        for i, entry in enumerate(self.doc.entries):
            if isinstance(entry, SurveySpec):
                self._paint_survey(p, view, i, entry)
        self._paint_path(p, view)
        self._paint_breaches(p, view)
        self._paint_items(p, view)
        for i, item in enumerate(self.doc.rally):
            self._marker(p, self._at(view, item.lat, item.lon), RALLY, "R", self.selected == ("rally", i))
        if self.draft:
            pts = [self._at(view, lat, lon) for lat, lon in self.draft]
            p.setPen(QPen(DRAFT, 1.5, Qt.DashLine))
            p.setBrush(Qt.NoBrush)
            p.drawPolyline(QPolygonF(pts))
            for q in pts:
                p.drawEllipse(q, 4, 4)
        if self.progress:
            self._paint_progress(p)
        p.restore()

    def _paint_progress(self, p) -> None:
        """The mission's progress in the map's top left corner: seen with Telemetry shown instead of Plan."""
        metrics = p.fontMetrics()
        box = QRectF(metrics.boundingRect(self.progress)).translated(8, 8 + metrics.ascent()).adjusted(-4, -2, 4, 2)
        p.fillRect(box, LABEL_BOX)
        p.setPen(CURRENT)
        p.drawText(box, Qt.AlignCenter, self.progress)

    def _paint_path(self, p, view) -> None:
        if self.home is None:
            return
        pts = [self._at(view, lat, lon) for lat, lon in self.doc.path(self.home)]
        if len(pts) < 2:
            return
        home = pts[0]
        lines = []                              # as separate lines: a long self-crossing polyline strokes slowly
        for a, b in zip(pts, pts[1:]):
            line = QLineF(a, b)
            if line.length() > HOME_PX:         # legs start and end at the home mark's edge: H stays readable
                if a == home:
                    line.setP1(line.pointAt(HOME_PX / line.length()))
                if b == home:
                    line.setP2(line.pointAt(1.0 - HOME_PX / line.length()))
                lines.append(line)
        p.setPen(QPen(PATH, 2))
        p.drawLines(lines)

    def _paint_breaches(self, p, view) -> None:
        """Survey legs that leave the fence in red over the passes; a red ring under each waypoint outside it."""
        if not (self.breaches.legs or self.breaches.points):
            return
        p.setPen(QPen(BREACH, 3))
        p.drawLines([QLineF(self._at(view, *a), self._at(view, *b)) for a, b in self.breaches.legs])
        p.setBrush(Qt.NoBrush)
        for lat, lon in self.breaches.points:
            p.drawEllipse(self._at(view, lat, lon), 14, 14)

    def _paint_items(self, p, view) -> None:
        seq = 0
        shown = QRectF(view.rect()).adjusted(-20, -20, 20, 20)
        for i, entry in enumerate(self.doc.entries):
            if isinstance(entry, SurveySpec):
                seq += len(self.doc.survey_of(entry).items)
                continue
            seq += 1
            if not (entry.has_position and (entry.lat or entry.lon)):
                continue
            at = self._at(view, entry.lat, entry.lon)
            if not shown.contains(at):
                continue
            colour = CURRENT if self.current == seq else ROI if not is_nav(entry) else ITEM
            self._marker(p, at, colour, str(seq), self.selected == ("mission", i), self.current == seq)

    def _paint_survey(self, p, view, i: int, spec: SurveySpec) -> None:
        pts = [self._at(view, lat, lon) for lat, lon in spec.polygon]
        chosen = self.selected == ("mission", i)
        p.setPen(QPen(SURVEY_EDGE, 2 if chosen else 1.2))
        p.setBrush(SURVEY)
        p.drawPolygon(QPolygonF(pts))
        got = self.doc.survey_of(spec)
        current = self.current_entry == i
        p.setPen(QPen(CURRENT if current else SURVEY_EDGE, 1.2, Qt.SolidLine))
        for a, b in got.passes:
            p.drawLine(self._at(view, *a), self._at(view, *b))
        if chosen and self.editing:
            p.setBrush(SURVEY_EDGE)
            for q in pts:
                p.drawRect(QRectF(q.x() - 4, q.y() - 4, 8, 8))

    def _paint_fence(self, p, view, shape, chosen: bool) -> None:
        fill, edge = (INCLUDE, INCLUDE_EDGE) if shape.inclusion else (EXCLUDE, EXCLUDE_EDGE)
        p.setPen(QPen(edge, 2.5 if chosen else 1.5, Qt.DashLine))
        p.setBrush(fill)
        if shape.circle:
            c = self._at(view, *shape.vertices[0])
            r = shape.radius / view.mpp
            p.drawEllipse(c, r, r)
            pts = [c]
        else:
            pts = [self._at(view, lat, lon) for lat, lon in shape.vertices]
            p.drawPolygon(QPolygonF(pts))
        if chosen and self.editing:
            p.setBrush(edge)
            for q in pts:
                p.drawRect(QRectF(q.x() - 4, q.y() - 4, 8, 8))

    def _marker(self, p, at: QPointF, colour: QColor, text: str, chosen: bool, current: bool = False) -> None:
        """A numbered disc (with a halo when current), drawn once into a pixmap and then only copied: a plan of
        hundreds of items repaints with the vehicle."""
        key = (colour.rgba(), text, chosen, current, self._look)
        image = self._markers.get(key)
        if image is None:
            if len(self._markers) > 2000:
                self._markers.clear()
            ratio = self._look[0]
            image = QPixmap(int(MARK_PX * ratio), int(MARK_PX * ratio))
            image.setDevicePixelRatio(ratio)
            image.fill(Qt.transparent)
            q = QPainter(image)
            q.setRenderHint(QPainter.Antialiasing)
            q.setFont(p.font())
            _draw_marker(q, QPointF(MARK_PX / 2, MARK_PX / 2), colour, text, chosen, current)
            q.end()
            self._markers[key] = image
        p.drawPixmap(QPointF(at.x() - MARK_PX / 2, at.y() - MARK_PX / 2), image)


def _draw_marker(p, at: QPointF, colour: QColor, text: str, chosen: bool, current: bool) -> None:
    if current:
        halo = QColor(colour)
        halo.setAlpha(80)
        p.setPen(Qt.NoPen)
        p.setBrush(halo)
        p.drawEllipse(at, 16, 16)
    p.setPen(QPen(SELECTED if chosen else Qt.black, 2.5 if chosen else 1))
    p.setBrush(colour)
    p.drawEllipse(at, 9, 9)
    p.setPen(TEXT)
    p.drawText(QRectF(at.x() - 12, at.y() - 9, 24, 18), Qt.AlignCenter, text)
