"""Guided actions from the window and the map: Change altitude, Circle a point.

Both go through the drone's own calls (driver.guided): a change of altitude is a go-to where the vehicle is; a
circle flies to the circle's edge, faces the centre and switches to ArduCopter's CIRCLE mode. The questions are
not modal: Stop, Land and RTL stay one click away, and Stop (or Escape) ends a circle still on its way.
"""
from __future__ import annotations

import math

from PyQt5.QtCore import QObject, QPointF, Qt, pyqtSignal
from PyQt5.QtGui import QColor, QPen
from PyQt5.QtWidgets import QAction, QInputDialog, QMenu, QWidget

from driver.vehicle.guided import MAX_CIRCLE_RADIUS, MIN_CIRCLE_RADIUS
from driver.vehicle.rules import MAX_ALTITUDE, MIN_GOTO_ALTITUDE
from driver.vehicle.state import VehicleState

__all__ = ["GuidedController"]

CIRCLE_COLOUR = QColor("#4fc3f7")


class GuidedController(QObject):
    asked = pyqtSignal(object)               # the question just opened (a QInputDialog): tests answer it
    view_changed = pyqtSignal()              # the circle drawn on the map came or went

    def __init__(self, adapter, window: QWidget, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.adapter = adapter
        self._window = window
        self._circle = None                  # the circle's Future while it is on its way
        self._circle_wanted: tuple[float, float, float] | None = None   # ... and the circle it asked
        self.circling: tuple[float, float, float] | None = None   # north, east, radius of the circle being flown
        self._circle_seen = False                                  # the vehicle has reported CIRCLE since
        self.question: QInputDialog | None = None
        self.change_altitude_action = QAction("Change &altitude…", window)
        self.change_altitude_action.setObjectName("actionChangeAltitude")
        self.change_altitude_action.triggered.connect(lambda: self.ask_altitude())
        self.circle_action = QAction("&Circle ahead…", window)
        self.circle_action.setObjectName("actionCircle")
        self.circle_action.setToolTip("ArduCopter's CIRCLE mode: around a point ahead of the nose")
        self.circle_action.triggered.connect(lambda: self.ask_circle(None))
        self.update_actions(VehicleState())

    # -- what is possible now ----------------------------------------------------------------------------
    @staticmethod
    def why_not(s: VehicleState) -> str:
        """Why guided actions cannot be sent now ("" when they can)."""
        if not s.connected:
            return "no link to the vehicle"
        if not s.flying:
            return "the vehicle is not flying"
        if s.mode != "GUIDED":
            return f"only in GUIDED (mode is {s.mode})"
        if s.local is None:
            return "the vehicle has not sent its position"
        return ""

    def update_actions(self, s: VehicleState) -> None:
        if self.circling is not None and s.mode == "CIRCLE":
            self._circle_seen = True                    # the vehicle reports the circle: from now on, leaving it
        elif self.circling is not None and self._circle_seen and s.mode:   # (a snapshot older than the mode
            self.circling = None                        # change says nothing) takes the circle off the map
            self._circle_seen = False
            self.view_changed.emit()
        why = self.why_not(s) if self.adapter.replay is None else "a recording cannot be flown"
        for action, what in ((self.change_altitude_action, "Climb or descend where it is"),
                             (self.circle_action, "Circle a point ahead of the nose (CIRCLE mode)")):
            if action.isEnabled() != (not why):
                action.setEnabled(not why)
            tip = f"{what}: {why}" if why else what
            if action.toolTip() != tip:
                action.setToolTip(tip)
                action.setStatusTip(tip)

    def add_map_items(self, menu: QMenu, north: float, east: float) -> None:
        """The map's right-click menu: Change altitude, and Circle here (centre at the click)."""
        why = self.why_not(self.adapter.state)
        altitude = menu.addAction("Change altitude…")
        altitude.setEnabled(not why)
        altitude.triggered.connect(lambda: self.ask_altitude())
        circle = menu.addAction("Circle here…")
        circle.setEnabled(not why)
        circle.triggered.connect(lambda: self.ask_circle((north, east)))

    # -- questions -------------------------------------------------------------------------------------------
    def _open(self, dialog: QInputDialog, answered) -> None:
        if self.question is not None:
            self.question.reject()
        dialog.setWindowModality(Qt.NonModal)             # Stop stays in reach
        dialog.setAttribute(Qt.WA_DeleteOnClose)
        dialog.doubleValueSelected.connect(answered)
        dialog.finished.connect(lambda _r: setattr(self, "question", None) if self.question is dialog else None)
        self.question = dialog
        dialog.show()
        self.asked.emit(dialog)

    def ask_altitude(self) -> None:
        s = self.adapter.state
        dialog = QInputDialog(self._window)
        dialog.setObjectName("changeAltitudeQuestion")
        dialog.setWindowTitle("Change altitude")
        dialog.setLabelText(f"Climb or descend where it is, to this altitude above home (now {s.altitude:.1f} m):")
        dialog.setInputMode(QInputDialog.DoubleInput)
        dialog.setDoubleRange(MIN_GOTO_ALTITUDE, MAX_ALTITUDE)
        dialog.setDoubleDecimals(1)
        dialog.setDoubleValue(round(max(MIN_GOTO_ALTITUDE, s.altitude)))
        dialog.setOkButtonText("Change altitude")
        self._open(dialog, self.change_altitude)

    def ask_circle(self, centre: tuple[float, float] | None) -> None:
        """``centre``: (north, east) from home; None: ahead of the nose by the radius (CIRCLE mode's own)."""
        s = self.adapter.state
        dialog = QInputDialog(self._window)
        dialog.setObjectName("circleQuestion")
        dialog.setWindowTitle("Circle")
        where = "the point ahead of the nose" if centre is None else \
            f"the point {self._distance(s, centre):.0f} m away"
        dialog.setLabelText(f"Circle {where} clockwise at {s.altitude:.1f} m, in CIRCLE mode, with this radius (m).\n"
                            "It first flies to the circle and faces the centre; Stop ends it.")
        dialog.setInputMode(QInputDialog.DoubleInput)
        dialog.setDoubleRange(MIN_CIRCLE_RADIUS, MAX_CIRCLE_RADIUS)
        dialog.setDoubleDecimals(0)
        dialog.setDoubleValue(10.0 if centre is None else
                              min(MAX_CIRCLE_RADIUS, max(MIN_CIRCLE_RADIUS, round(self._distance(s, centre)))))
        dialog.setOkButtonText("Circle")
        self._open(dialog, lambda radius: self.circle(centre, radius))

    @staticmethod
    def _distance(s: VehicleState, centre: tuple[float, float]) -> float:
        here = (s.local.north, s.local.east) if s.local is not None else (0.0, 0.0)
        return math.hypot(centre[0] - here[0], centre[1] - here[1])

    # -- commands -------------------------------------------------------------------------------------------
    def change_altitude(self, altitude: float) -> None:
        self.adapter.send(self.adapter.drone.change_altitude, float(altitude))

    def circle(self, centre: tuple[float, float] | None, radius: float) -> None:
        s = self.adapter.state
        if centre is None:                              # ahead of the nose, as CIRCLE mode itself would put it
            here = (s.local.north, s.local.east) if s.local is not None else (0.0, 0.0)
            yaw = math.radians(s.heading_deg)
            centre = (here[0] + radius * math.cos(yaw), here[1] + radius * math.sin(yaw))
        wanted = (centre[0], centre[1], float(radius))
        self.circling = None
        self._circle_seen = False
        self._circle_wanted = wanted
        self._circle = self.adapter.send(self.adapter.drone.circle, *wanted,
                                         then=lambda result: self._circle_answered(result, wanted))

    def _circle_answered(self, result, wanted: tuple[float, float, float]) -> None:
        """The vehicle took the circle (and it is still the one asked), so the map draws it."""
        if result.ok and self._circle is not None and wanted == self._circle_wanted:
            self.circling = wanted
            self.view_changed.emit()

    def paint_circle(self, p, view) -> None:
        """The map: the circle being flown (CIRCLE mode entered through Circle), its centre marked."""
        if self.circling is None:
            return
        north, east, radius = self.circling
        centre = view.to_screen(east, north)
        r = abs(view.to_screen(east + radius, north).x() - centre.x())
        p.setPen(QPen(CIRCLE_COLOUR, 2, Qt.DashLine))
        p.setBrush(Qt.NoBrush)
        p.drawEllipse(centre, r, r)
        p.setPen(QPen(CIRCLE_COLOUR, 2))
        p.drawLine(centre + QPointF(-5, 0), centre + QPointF(5, 0))
        p.drawLine(centre + QPointF(0, -5), centre + QPointF(0, 5))

    def cancel(self) -> None:
        """Stop, Escape, Land, RTL: a circle on its way to the edge ends there."""
        if self._circle is not None:
            self._circle.cancel()
            self._circle = None
        if self.question is not None:
            self.question.reject()
