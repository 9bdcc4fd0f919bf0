"""The flying window: it builds itself from the features' parts and wires their signals; the logic is theirs.

It is built from a :class:`driver.api.Drone` and sees the vehicle only through :class:`DroneAdapter`
(snapshots in, non-blocking commands out). Buttons and sticks follow the vehicle's state as reported, never a
local flag. Which part does what: docs/architecture.md.
"""
from __future__ import annotations

import time

from PyQt5 import uic
from PyQt5.QtCore import QEvent, QSettings, Qt
from PyQt5.QtWidgets import QMainWindow, QWidget

from driver.vehicle.api import Drone
from driver.vehicle.state import Severity, VehicleState

from . import RESOURCES
from .camera.controller import CameraController
from .camera.gimbal import GimbalController
from .camera.gimbal_bar import GimbalBar
from .camera.panel import CameraPanel
from .connect.choice import Choice, Kind, sim_name
from .connect.security import signing_unavailable
from .drone_adapter import DroneAdapter
from .fleet.dock import FleetDock
from .flight.commands import FlightCommands
from .flight.timer import FlightTimer
from .input.controller import PilotSticks
from .inspector.controller import InspectorController
from .logs.controller import FlightLogsController
from .input.keys_dialog import KeysDialog
from .map.controller import MapController
from .params import ParamsController
from .setup.controller import SetupController
from .shots.controller import ShotsController
from .plan.controller import PlanController
from .preferences.controller import Preferences
from .refresh import Refresh
from .replay.controls import ReplayControls
from .review.controller import ReviewController
from .settings import ViewerSettings, default_qsettings
from .telemetry.readouts import Readouts
from .window.about import show_about
from .window.closing import Closing
from .window.layout import docks_beside, fit_restored, fit_screen, steady_slots
from .window.pilot_tools import PilotTools
from .window.secondary import SecondaryWindows

__all__ = ["MainWindow", "load_style"]


def load_style() -> str:
    """The dark ground-station style sheet, with icon paths made absolute."""
    qss = (RESOURCES / "style.qss").read_text(encoding="utf-8")
    return qss.replace("@ICONS@", (RESOURCES / "icons").as_posix())


class MainWindow(QMainWindow):
    """Fly one drone. ``qsettings`` lets tests keep their own settings file.

    Cameras: ``cameras`` (--camera) if given, else those saved in Preferences, else ``default_cameras``
    (the mode's own: the simulator's, the Ice server's). ``takeoff_altitude`` (--takeoff-altitude) holds
    for this run only; it is never saved as the Preferences' value. ``tile_cache_dir``: where map tiles are
    cached (tests keep their own).

    Parts: ``preferences``, ``sticks`` (and its ``gamepad``), ``flight`` (the buttons' commands), ``camera``,
    ``gimbal``, ``map``, ``plan``, ``readouts``, ``replay``, ``tools`` (connecting, alerts, preflight, guided),
    ``params``, ``flight_logs``, ``fleet_dock``, ``secondary`` (the other windows' places) and ``closing``.
    """

    def __init__(self, drone: Drone, qsettings: QSettings | None = None,
                 takeoff_altitude: float | None = None, rate_hz: float = 30.0,
                 cameras: list[str] | None = None, default_cameras: list[str] | None = None,
                 tile_cache_dir: str | None = None, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.tile_cache_dir = tile_cache_dir              # None: the per-user cache folder
        uic.loadUi(str(RESOURCES / "ui" / "main_window.ui"), self)
        self._qsettings = qsettings if qsettings is not None else default_qsettings()
        self.adapter = DroneAdapter(drone, rate_hz=rate_hz, parent=self)
        self.preferences = Preferences(self, self._qsettings, takeoff_altitude)
        self.sticks = PilotSticks(self, self.settings)
        self.gamepad = self.sticks.gamepad
        self.flight = FlightCommands(self)
        self._vehicle_name = ""
        self.flight_timer = FlightTimer()
        self.adapter.droneChanged.connect(lambda _drone: self.flight_timer.reset())
        self.refresh = Refresh(self)        # views redraw at the rate the eye needs and not while minimised
        self.readouts = Readouts(self)
        self.closing = Closing(self)
        self.secondary = SecondaryWindows(self, self._qsettings)   # other windows fit, and leave the controls in view

        self.setWindowTitle(f"UavViewerPy — {self.adapter.description}")
        self.signing_unavailable = signing_unavailable(drone)     # a remote drone is signed on its server
        self.telemetry.set_security_unknown(self.signing_unavailable)
        self._build_camera(cameras, default_cameras)
        self.menuView.addAction(self.telemetryDock.toggleViewAction())
        self.menuView.addAction(self.plotsDock.toggleViewAction())
        self.menuView.addAction(self.mapDock.toggleViewAction())
        self.map = MapController(self.mapPanel, self.adapter, self, lambda: self.takeoff_altitude, self)
        self.map.camera.stopLookingRequested.connect(self.gimbal.stop_looking)    # the tilt comes back as from the bar
        self.tabifyDockWidget(self.plotsDock, self.mapDock)            # Map and Plots share the lower right
        self.plan = PlanController(self.map, self.adapter, self, self)  # Plan mode, transfers, missions: own dock
        self.preferences.keep_map_choices(self.mapPanel)
        self.menuView.addAction(self.messagesDock.toggleViewAction())
        self.setCorner(Qt.BottomRightCorner, Qt.RightDockWidgetArea)   # plots run the full height
        self.resizeDocks([self.telemetryDock, self.plotsDock], [390, 560], Qt.Vertical)
        self.resizeDocks([self.telemetryDock], [400], Qt.Horizontal)
        self.mapDock.raise_()
        self.instrumentSplitter.setStretchFactor(0, 3)
        self.instrumentSplitter.setStretchFactor(1, 2)
        steady_slots(self)                        # nothing moves under the cursor as the state changes
        self.replay = ReplayControls(self)
        self.actionQuit.triggered.connect(self.close)
        self.actionKeys.triggered.connect(self.show_keys)
        self.actionAbout.triggered.connect(lambda: show_about(self))
        self.adapter.stateChanged.connect(self.show_state)
        self.tools = PilotTools(self)                 # connecting, alerts, preflight, guided actions, home arrow
        self.shots = ShotsController(self)            # smart shots: the panel, the map, the sticks during a shot
        self.params = ParamsController(self.adapter, self, say=self.log_message)    # docs/parameters.md
        self.params.add_to_menu(self)                       # Vehicle › Parameters…
        self.params.offer_fixes(self.messages)              # a warning naming a parameter: Fix… opens it
        self.plan.notices.fenceOnRequested.connect(lambda: self.params.propose({"FENCE_ENABLE": 1}))
        self.setup = SetupController(self.adapter, self, self.params)    # Vehicle › Setup…: calibrations, radio, motors
        self.setup.add_to_menu(self)
        self.fleet_dock = FleetDock(self)
        self.review = ReviewController(self)                # File › Review a log…: docs/review.md
        self.inspector = InspectorController(self)          # Tools › MAVLink inspector
        self.flight_logs = FlightLogsController(self.adapter, lambda: self.logs.downloads, self.review.open, self,
                                                say=self.log_message)
        self.flight_logs.add_to_menu(self)                  # Logs › Flight logs…: the vehicle's DataFlash logs

        self.preferences.apply()
        self._restore_window()
        self.show_state(VehicleState(link=self.adapter.state.link))
        self.adapter.start()

    def _build_camera(self, cameras: list[str] | None, default_cameras: list[str] | None) -> None:
        """Video in the reserved camera area (--camera URIs), and the vehicle's own camera: tilt, photo, video."""
        self.camera_panel = CameraPanel()
        self.instrumentSplitter.replaceWidget(self.instrumentSplitter.indexOf(self.cameraView), self.camera_panel)
        self.cameraView.deleteLater()
        self.camera_panel.show()                      # replaceWidget leaves the newcomer hidden
        self.cameraView = self.camera_panel
        self.camera_view = self.camera_panel.view
        self.default_cameras = list(default_cameras or [])
        self.camera = CameraController(self.camera_panel, list(cameras or self.settings.camera_uris
                                                               or self.default_cameras),
                                       state_fn=lambda: self.adapter.drone.state(),     # the picked vehicle's
                                       drone=lambda: self.adapter.drone,
                                       folder=self.settings.media_folder or None, parent=self)
        self.refresh.shownChanged.connect(self.camera.set_shown)
        self.gimbal_bar = GimbalBar()
        self.camera_panel.layout().addWidget(self.gimbal_bar)
        self.camera_panel.add_overlay(self.gimbal_bar.stop_looking_button)
        self.gimbal = GimbalController(self.adapter, self.camera_view, self.gimbal_bar, self)
        self.camera_panel.hud_button.setChecked(self.settings.hud)

    def _restore_window(self) -> None:
        geometry, state = self.preferences.restore_window()
        if state is not None:
            self.restoreState(state)
            if "preflightDock".encode("utf-16-be") not in bytes(state):   # saved before the dock existed
                self.tools.tab_preflight()
        docks_beside(self)                        # none under the flight controls (a layout saved so too)
        if geometry is not None:
            self.restoreGeometry(geometry)
            fit_restored(self)                    # saved on a larger screen: it still fits this one
        else:
            fit_screen(self)
        self.setFocusPolicy(Qt.StrongFocus)

    @property
    def settings(self) -> ViewerSettings:
        return self.preferences.settings

    @property
    def takeoff_altitude(self) -> float:
        """--takeoff-altitude for this run, else the Preferences' value."""
        return self.preferences.takeoff_altitude

    # -- connecting (File › Connect, Disconnect, Replay a flight: uavviewer/window/pilot_tools.py wires them) ----
    def _connected(self, opened) -> None:
        """A connection opened by File › Connect (:class:`uavviewer.connect.opener.Opened`): a vehicle, or a lab's
        fleet with its Fleet panel."""
        self.fleet_dock.leave()
        self.use_connection(opened.drone)
        if opened.sim is not None:                                 # not a raw tcp:127.0.0.1:port, as with --sim
            self.name_vehicle(sim_name(opened.sim.config.speedup))
        self.actionDisconnect.setEnabled(self.connections.connected)
        own = ["sim"] if opened.sim is not None else []            # the new vehicle's own camera, if we know it
        if opened.fleet is not None:                               # its cameras through the registry, as app.py
            from driver.ice import camera_source as ice_source
            from driver.ice.client import fleet_properties

            from .fleet.controller import FleetController
            ice_source.use_client_properties(fleet_properties(opened.choice.target, self.connections.certs))
            own = [FleetController.camera_uri(opened.first)]
            self.fleet_dock.attach(FleetController(opened.fleet, opened.first, parent=self))
        if self.camera.uris == self.default_cameras and own != self.default_cameras:   # not --camera's
            self.default_cameras = own                                                   # nor Preferences'
            self.camera.set_sources(own)

    def use_connection(self, drone: Drone) -> None:
        """Fly (or watch) ``drone`` from now on: File › Connect, Disconnect, Replay a flight. The vehicle left
        behind was sent zero velocity first, so it hovers."""
        self.sticks.centre()
        self.map.cancel()
        self.guided.cancel()
        self.readouts.follow(None)
        self.adapter.use(drone)
        self._vehicle_name = ""                 # the previous vehicle's name is not this one's (About, the title)
        self.map.use_connection()
        self.setWindowTitle(f"UavViewerPy — {self.adapter.description}")
        self.signing_unavailable = signing_unavailable(drone)
        self.telemetry.set_security_unknown(self.signing_unavailable)
        self.sticks.set_limits(self.settings.speeds)
        self.replay.use()
        self.attitude.clear("NO LINK")
        self.show_state(self.adapter.state)

    def name_vehicle(self, name: str) -> None:
        """A name for the title and About in place of the raw connection string (--sim: the built-in one)."""
        self._vehicle_name = name
        self.setWindowTitle(f"UavViewerPy — {name}")

    def window_name(self) -> str:
        return self._vehicle_name or self.adapter.description

    def remember_last_connection(self, choice: Choice) -> None:
        """A vehicle answered on ``choice`` (the command line's or File › Connect's: ConnectionController.confirm,
        never before, so a typo never becomes the default): a MAVLink link is the next run's default."""
        if choice.kind is Kind.MAVLINK and choice.target != self.settings.last_connection:
            self.preferences.remember(last_connection=choice.target)

    def show_keys(self) -> None:
        """Help › Keys, not modal: the flight controls stay in reach while it is read."""
        dialog = KeysDialog(self)
        dialog.setAttribute(Qt.WA_DeleteOnClose)
        dialog.show()

    # -- state in --------------------------------------------------------------------------------
    def show_state(self, s: VehicleState) -> None:
        """Every snapshot: what must follow the vehicle at once (buttons, sticks, questions, messages, the plots'
        data); the views that only show it redraw through their refresh channels."""
        self.preferences.show_state(s)              # the signing state in an open Preferences
        self.map.show_state(s)                      # cheap; it repaints only on a change it can show
        self.gimbal.show_state(s)                   # its bar sets its texts only on a change
        self.flight_timer.update(s)                 # every arm and disarm, minimised too (shown in the text channel)
        self.flight.show_state(s)
        self.sticks.show_state(s)
        self.readouts.show_state(s)

    def log_message(self, text: str, severity: Severity = Severity.INFO) -> None:
        """A line of the viewer's own in Messages (e.g. a refused setting)."""
        self.messages.add_message(time.time(), severity, text, "viewer")

    # -- focus, minimising and closing -------------------------------------------------------------
    def changeEvent(self, event: QEvent) -> None:  # noqa: N802
        if event.type() in (QEvent.ActivationChange, QEvent.WindowStateChange):
            self.sticks.window_changed(event)     # focus lost or minimised: nobody holds the sticks any more
        super().changeEvent(event)

    def hideEvent(self, event) -> None:  # noqa: N802
        self.sticks.centre()
        super().hideEvent(event)

    def quit_without_asking(self) -> None:
        """Ctrl+C or kill in the terminal: close now, even in flight (said in the log)."""
        self.closing.quit_without_asking()

    def closeEvent(self, event) -> None:  # noqa: N802
        if self.closing.keeps_open():             # the vehicle flies, or a plan is unsaved: the pilot answers
            event.ignore()
            return
        self.sticks.centre()
        self.plan.show_plan(False)                # the docks that stepped out for Plan are saved as they were
        self.preferences.save(self.saveGeometry(), self.saveState())
        self.sticks.close()
        self.secondary.close()
        self.alerts.close()
        self.review.close()
        self.inspector.close()
        self.camera.close(wait=0.5)
        self.adapter.stop()
        super().closeEvent(event)
