"""The vehicle's camera on the map: its footprint and look direction, where it was asked to look (ROI), and
"Look here" / "Stop looking" in the map's right-click menu."""
from __future__ import annotations

from PyQt5.QtCore import QObject, QPointF, Qt, pyqtSignal
from PyQt5.QtGui import QColor, QFont, QPen, QPolygonF

from driver.payload import GimbalControl
from driver.vehicle.state import VehicleState

from .camera_footprint import footprint, look_point

__all__ = ["CameraOverlay", "FOOTPRINT", "ROI"]

FOOTPRINT = QColor(255, 225, 120, 60)
FOOTPRINT_EDGE = QColor("#ffd76a")
ROI = QColor("#ff6ad5")


class CameraOverlay(QObject):
    """Draws on a :class:`~uavviewer.map.map_view.MapView` (its ``overlays``) and adds to its menu
    (``menu_parts``); asks the drone through the window's adapter. Stop looking is the gimbal's to send (it then
    tilts the camera back as it was), as from its bar."""
    stopLookingRequested = pyqtSignal()

    def __init__(self, view, adapter, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.view = view
        self.adapter = adapter
        self.shown: tuple | None = None              # what was last drawn (repaint only on a change)
        self._state: VehicleState | None = None
        self._where: tuple[float, float] | None = None
        view.overlays.append(self.paint)
        view.menu_parts.append(self.add_to_menu)

    # -- state in --------------------------------------------------------------------------------
    def show_state(self, s: VehicleState, where: tuple[float, float] | None) -> None:
        """``where``: the vehicle in view metres (east, north), or None."""
        self._state, self._where = s, where
        g = s.gimbal
        key = (None if where is None else (round(where[0], 1), round(where[1], 1)),
               None if g.pitch_deg is None else round(g.pitch_deg), round(s.heading_deg), round(s.altitude, 1),
               g.roi, g.control)
        if key != self.shown:
            self.shown = key
            self.view.update()

    def geometry(self) -> tuple[list[tuple[float, float]] | None, tuple[float, float, bool] | None]:
        """(footprint corners, look point) in view metres (east, north), from the last state."""
        s, where = self._state, self._where
        if s is None or where is None or s.gimbal.pitch_deg is None:
            return None, None
        g = s.gimbal
        heading = g.yaw_deg if g.yaw_earth and g.yaw_deg is not None else s.heading_deg + (g.yaw_deg or 0.0)
        corners = footprint(s.altitude, s.gimbal.pitch_deg, heading)
        look = look_point(s.altitude, s.gimbal.pitch_deg, heading)
        to_view = [(where[0] + e, where[1] + n) for n, e in corners] if corners else None
        return to_view, (where[0] + look[1], where[1] + look[0], look[2]) if look else None

    def roi_view(self) -> tuple[float, float] | None:
        s = self._state
        if s is None or s.gimbal.roi is None or self.view.frame is None:
            return None
        return self.view.frame.to_view(s.gimbal.roi[0], s.gimbal.roi[1])

    # -- painting (called by the map view inside its paintEvent) ----------------------------------
    def paint(self, p, view) -> None:
        corners, look = self.geometry()
        if corners:
            p.setPen(QPen(FOOTPRINT_EDGE, 1, Qt.DashLine))
            p.setBrush(FOOTPRINT)
            p.drawPolygon(QPolygonF([view.to_screen(e, n) for e, n in corners]))
        if look is not None and self._where is not None:
            p.setPen(QPen(FOOTPRINT_EDGE, 2))
            end = view.to_screen(look[0], look[1])
            p.drawLine(view.to_screen(*self._where), end)
            if look[2]:
                p.drawEllipse(end, 4, 4)
        roi = self.roi_view()
        if roi is not None:
            c = view.to_screen(*roi)
            p.setPen(QPen(ROI, 2))
            p.setBrush(Qt.NoBrush)
            p.drawEllipse(c, 10, 10)
            p.drawEllipse(c, 3, 3)
            if self._where is not None:
                p.setPen(QPen(ROI, 1, Qt.DotLine))
                p.drawLine(view.to_screen(*self._where), c)
            p.setFont(QFont(view.font().family(), 8))
            view._label(p, c + QPointF(13, 4), "looking here")

    # -- the menu -----------------------------------------------------------------------------------
    def add_to_menu(self, menu, north: float, east: float) -> None:
        s = self._state
        if s is None:
            return
        frame = self.view.frame
        look = menu.addAction("Look here (camera)" if frame is not None else "Look here (no home position yet)")
        look.setEnabled(frame is not None and s.connected)
        if frame is not None:
            lat, lon = frame.to_latlon(east, north)
            look.triggered.connect(lambda: self.adapter.send(self.adapter.drone.look_at, lat, lon, 0.0))
        if s.gimbal.roi is not None or s.gimbal.control is GimbalControl.ROI:
            stop = menu.addAction("Stop looking (camera back to the pilot)")
            stop.setEnabled(s.connected)
            stop.triggered.connect(self.stopLookingRequested.emit)
