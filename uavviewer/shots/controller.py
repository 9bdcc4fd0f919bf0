"""The Shots feature: its panel in a dock, the shot on the map and over the video, the sticks while a shot runs.

It asks the drone's ``shots`` (:class:`driver.shots.api.Shots`: the embedded driver's or the Ice client's, the same
calls) through the window's adapter, so no call waits on the network and each answer lands in Messages. While a
shot runs the sticks fly the shot, as on the Solo (:meth:`ShotsController.steer`, called by the pilot's sticks):
their deflections go to the shot, refreshed while held; velocity would end the shot.
"""
from __future__ import annotations

from PyQt5.QtCore import QObject, Qt, QTimer
from PyQt5.QtWidgets import QDockWidget, QFileDialog, QScrollArea

from driver.vehicle.state import VehicleState

from .camera_badge import ShotBadge
from .map_overlay import ShotsOverlay
from .panel import ShotsPanel

__all__ = ["ShotsController", "STICK_REFRESH_MS"]

STICK_REFRESH_MS = 100       # while a stick is held: the driver counts sticks silent for 0.5 s as centred


class ShotsController(QObject):
    """``window``: the main window (its adapter, map, camera panel, View menu and docks)."""

    def __init__(self, window) -> None:
        super().__init__(window)
        self.window = w = window
        self.adapter = w.adapter
        self.panel = ShotsPanel()
        self.dock = QDockWidget("Shots", w)
        self.dock.setObjectName("shotsDock")
        scroll = QScrollArea()                               # the window still fits a 1024x600 screen
        scroll.setWidget(self.panel)
        scroll.setWidgetResizable(True)
        scroll.setFrameShape(QScrollArea.NoFrame)
        self.dock.setWidget(scroll)
        w.addDockWidget(Qt.RightDockWidgetArea, self.dock)
        w.tabifyDockWidget(w.telemetryDock, self.dock)        # beside Telemetry: the map stays in view meanwhile
        w.telemetryDock.raise_()
        w.menuView.addAction(self.dock.toggleViewAction())
        self.overlay = ShotsOverlay(w.map.view, self)
        self.badge = ShotBadge()
        w.camera_panel.add_overlay(self.badge)
        self._axes = None
        self._refresh = QTimer(self)
        self._refresh.setInterval(STICK_REFRESH_MS)
        self._refresh.timeout.connect(self._send_sticks)
        p = self.panel
        a = self.adapter                             # its drone: the vehicle flown now (a fleet's pick changes it)
        p.orbitAsked.connect(self.orbit)
        p.recordAsked.connect(lambda: a.send(a.drone.shots.record_keyframe))
        p.clearAsked.connect(lambda: a.send(a.drone.shots.set_keyframes, ()))
        p.saveAsked.connect(self.save)
        p.loadAsked.connect(self.load)
        p.cableAsked.connect(lambda speed: self._centred() and a.send(a.drone.shots.cable, speed))
        p.selfieAsked.connect(lambda d, r, s: self._centred() and a.send(a.drone.shots.selfie, d, r, s))
        p.followAsked.connect(lambda source, engine: self._centred() and a.send(a.drone.shots.follow, source, engine))
        p.panoAsked.connect(lambda shape, fov, lens, pitch: self._centred()
                            and a.send(a.drone.shots.pano, shape, fov, lens, pitch))
        p.buttonAsked.connect(self.button)
        self.overlay.orbitHere.connect(lambda lat, lon: self._centred() and a.send(
            a.drone.shots.orbit, lat, lon, 0.0, None, self.panel.orbit_speed.value()))
        self.adapter.stateChanged.connect(self.show_state)

    # -- state in ------------------------------------------------------------------------------------------
    def show_state(self, s: VehicleState) -> None:
        can = s.connected and s.armed and s.in_air is True and self.adapter.replay is None
        self.panel.show_shot(s.shot, can)
        where = (s.position.lat, s.position.lon) if s.position is not None else None
        self.overlay.show_state(s.shot, where, can and not s.shot.active)
        self.badge.show_shot(s.shot)
        if not s.shot.active and self._refresh.isActive():
            self._refresh.stop()

    # -- the pilot's asks -----------------------------------------------------------------------------------
    def _centred(self) -> bool:
        """A shot starts from a hover: the sticks are centred first (a held stick's velocity would end it)."""
        self.window.sticks.centre()
        return True

    def orbit(self, radius: float, speed: float, centre: str) -> None:
        self._centred()
        self.adapter.send(self.adapter.drone.shots.orbit, None, None, 0.0, radius or None, speed, centre == "roi")

    def button(self, key: str) -> None:
        a = self.adapter
        if key == "pause":
            a.send(a.drone.shots.pause)
        elif key == "resume":
            a.send(a.drone.shots.resume)
        elif key == "reverse":
            a.send(a.drone.shots.reverse)
        else:
            a.send(a.drone.shots.stop)

    def save(self) -> None:
        path, _ = QFileDialog.getSaveFileName(self.window, "Save the cable", "cable.json", "Cables (*.json)")
        if path:
            self.adapter.send(self.adapter.drone.shots.save_cable, path)

    def load(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self.window, "Load a cable", "", "Cables (*.json)")
        if path:
            self.adapter.send(self.adapter.drone.shots.load_cable, path)

    # -- the sticks ------------------------------------------------------------------------------------------
    def steer(self, axes) -> bool:
        """The pilot's sticks (normalised :class:`~uavviewer.input.sticks.Axes`) while a shot runs: True when
        they went to the shot (the caller then sends no velocity)."""
        if not self.adapter.state.shot.active:
            self._axes = None
            self._refresh.stop()
            return False
        self._axes = axes
        self._send_sticks()
        if axes.is_zero:
            self._refresh.stop()
        elif not self._refresh.isActive():
            self._refresh.start()
        return True

    def _send_sticks(self) -> None:
        a = self._axes
        if a is not None:
            self.adapter.drone.shots.sticks(a.forward, a.right, a.up, a.yaw)
