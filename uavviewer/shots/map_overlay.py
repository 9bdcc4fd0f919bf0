"""The smart shot on the map: the cable with its keyframes and camera looks, the orbit's circle and centre, the
follow target, the selfie's line; and "Orbit here" in the map's right-click menu.

Before a cable plays, the keyframes recorded are drawn as the cable they make (the driver's own spline, so the
preview is the path that will be flown); once it plays, the path the driver planned (``ShotState.path``).
"""
from __future__ import annotations

import math

from PyQt5.QtCore import QObject, QPointF, Qt, pyqtSignal
from PyQt5.QtGui import QColor, QFont, QPen, QPolygonF

from driver.shots.model import ShotKind, ShotState
from driver.shots.spline import Looks, Spline

__all__ = ["ShotsOverlay", "CABLE", "ORBIT", "TARGET"]

CABLE = QColor("#ff9f1a")     # apart from the trail's blue
LOOK = QColor("#ffffff")
ORBIT = QColor("#7dff8a")
TARGET = QColor("#ff5c7a")
LOOK_LENGTH = 18.0           # pixels of a camera look's arrow


class ShotsOverlay(QObject):
    """Draws on a :class:`~uavviewer.map.map_view.MapView` (its ``overlays``) and adds to its menu."""

    orbitHere = pyqtSignal(float, float)         # lat, lon

    def __init__(self, view, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.view = view
        self.shot = ShotState()
        self._preview: tuple | None = None          # (keyframes, points, looks) of the cable not yet played
        self._vehicle: tuple[float, float] | None = None
        self._can_orbit = False
        view.overlays.append(self.paint)
        view.menu_parts.append(self.add_to_menu)

    def show_state(self, shot: ShotState, vehicle: tuple[float, float] | None, can_orbit: bool) -> None:
        """``vehicle``: where it is (lat, lon), for the line to the follow target."""
        self._can_orbit = can_orbit
        if shot is self.shot and vehicle == self._vehicle:
            return
        changed = shot != self.shot
        self.shot, self._vehicle = shot, vehicle
        if changed or shot.kind is ShotKind.FOLLOW:
            self.view.update()

    # -- geometry -------------------------------------------------------------------------------------------
    def cable(self):
        """(points (lat, lon), looks (lat, lon, yaw, pitch), keyframes (lat, lon)) to draw, or None."""
        shot = self.shot
        keys = [(k.lat, k.lon) for k in shot.keyframes]
        if shot.kind in (ShotKind.CABLE, ShotKind.SELFIE) and shot.path:
            return [(p[0], p[1]) for p in shot.path], [(k.lat, k.lon, k.yaw, k.pitch) for k in shot.looks], keys
        if len(shot.keyframes) < 2:
            return None if not keys else ([], [], keys)
        if self._preview is None or self._preview[0] != shot.keyframes:
            self._preview = (shot.keyframes, *self._preview_of(shot))
        return self._preview[1], self._preview[2], keys

    @staticmethod
    def _preview_of(shot: ShotState):
        k0 = shot.keyframes[0]
        scale = 111319.49
        cos = math.cos(math.radians(k0.lat))
        pts = [((k.lat - k0.lat) * scale, (k.lon - k0.lon) * scale * cos, k.alt) for k in shot.keyframes]
        try:
            spline = Spline(pts)
        except ValueError:                          # two keyframes on one spot: straight lines between them
            return [(k.lat, k.lon) for k in shot.keyframes], []
        looks = Looks([(k.pitch, k.yaw) for k in shot.keyframes])
        back = lambda n, e: (k0.lat + n / scale, k0.lon + e / (scale * cos))   # noqa: E731
        points = [back(n, e) for n, e, _ in spline.sample(2.0)]
        marks = sorted(set(list(spline.keyframe_s) + [i * 15.0 for i in range(1, int(spline.length / 15.0) + 1)]))
        out = []
        for s in marks:
            n, e, _ = spline.point(s)
            pitch, yaw = looks.at(float(spline.param(s)))
            out.append((*back(n, e), yaw, pitch))
        return points, out

    # -- painting -----------------------------------------------------------------------------------------
    def paint(self, p, view) -> None:
        frame = view.frame
        if frame is None:
            return
        at = lambda lat, lon: view.to_screen(*frame.to_view(lat, lon))    # noqa: E731
        shot = self.shot
        p.setFont(QFont(view.font().family(), 8))
        cable = self.cable()
        if cable is not None:
            points, looks, keys = cable
            if len(points) >= 2:
                p.setPen(QPen(CABLE, 3))
                p.drawPolyline(QPolygonF([at(*q) for q in points]))
            p.setPen(QPen(LOOK, 2))
            for lat, lon, yaw, pitch in looks:
                c = at(lat, lon)
                reach = LOOK_LENGTH * max(0.3, math.cos(math.radians(pitch)))     # shorter the more it looks down
                end = c + QPointF(reach * math.sin(math.radians(yaw)), -reach * math.cos(math.radians(yaw)))
                p.drawLine(c, end)
                p.drawEllipse(end, 2, 2)
            p.setBrush(QColor(0, 0, 0, 160))
            for i, (lat, lon) in enumerate(keys):
                c = at(lat, lon)
                p.setPen(QPen(CABLE, 2))
                p.drawEllipse(c, 8, 8)
                p.drawText(c + QPointF(-3, 4), str(i + 1))
            p.setBrush(Qt.NoBrush)
        if shot.centre is not None and shot.active:
            c = at(shot.centre[0], shot.centre[1])
            colour = TARGET if shot.kind in (ShotKind.FOLLOW, ShotKind.SELFIE) else ORBIT
            p.setPen(QPen(colour, 2))
            p.drawLine(c + QPointF(-7, 0), c + QPointF(7, 0))
            p.drawLine(c + QPointF(0, -7), c + QPointF(0, 7))
            if shot.kind is ShotKind.ORBIT and (shot.radius_wanted or shot.radius):
                r = (shot.radius_wanted or shot.radius) / view.mpp
                p.setPen(QPen(ORBIT, 2, Qt.DashLine))
                p.drawEllipse(c, r, r)
            if shot.kind is ShotKind.FOLLOW:
                p.drawEllipse(c, 6, 6)
                if self._vehicle is not None:
                    p.setPen(QPen(TARGET, 1, Qt.DotLine))
                    p.drawLine(at(*self._vehicle), c)
                label = "target" + (f" {shot.target_distance:.0f} m" if shot.target_distance is not None else "")
                p.setPen(QPen(TARGET, 1))
                p.drawText(c + QPointF(10, -8), label)
        if shot.kind is ShotKind.PANO and shot.active and self._vehicle is not None:
            p.setPen(QPen(CABLE, 1))
            p.drawText(at(*self._vehicle) + QPointF(14, 18), f"pano {shot.photos}/{shot.photos_total}")

    # -- the menu -----------------------------------------------------------------------------------------
    def add_to_menu(self, menu, north: float, east: float) -> None:
        frame = self.view.frame
        action = menu.addAction("Orbit here (smart shot)")
        action.setEnabled(frame is not None and self._can_orbit)
        if frame is not None:
            lat, lon = frame.to_latlon(east, north)
            action.triggered.connect(lambda: self.orbitHere.emit(lat, lon))
