"""The flying window: instruments, sticks, buttons, telemetry, plots and messages.

It is built from a :class:`driver.api.Drone` and sees the vehicle only through
:class:`DroneAdapter` (snapshots in, non-blocking commands out). Buttons and
sticks follow the vehicle's state as reported, never a local flag.
"""
from __future__ import annotations

import logging
import math
import time
from dataclasses import replace

from PyQt5 import uic
from PyQt5.QtCore import QEvent, QObject, QSettings, Qt
from PyQt5.QtWidgets import QApplication, QDialog, QLabel, QMainWindow, QMessageBox, QWidget

from driver.api import Drone, Limits
from driver.rules import mode_warning, unattended
from driver.state import LinkStatus, SequencePhase, Severity, VehicleState

from . import RESOURCES
from .preferences.dialog import (
    KeysDialog, SettingsDialog, ask, emergency_stop_question, mode_question, takeoff_question,
)
from .camera.controller import CameraController, default_media_folder
from .connect.choice import Choice, Kind, sim_name
from .widgets.dialog_fit import fit_dialog
from .drone_adapter import DroneAdapter
from .flight.arming import Arming
from .flight.timer import FlightTimer
from .flight.phase import (
    NO_VEHICLE, FlightPhase, flight_phase, link_gone_text, no_link_flag, no_vehicle_words, readiness_text, stick_hint,
    takeoff_cancellable, takeoff_progress,
)
from .input.gamepad_input import GamepadInput
from .input.keyboard import ACTION_KEYS, AXIS_KEYS, KeyboardSticks
from .connect.security import signing_unavailable, signing_warning
from .input.selector import Input, InputSelector
from .window.pilot_tools import PilotTools
from .map.controller import MapController, TileSettings
from .plan.controller import PlanController
from .params import ParamsController
from .refresh import INSTRUMENTS_HZ, PLOTS_HZ, TEXT_HZ, Refresh
from .settings import ViewerSettings, default_qsettings, load_settings, load_window, save_settings, save_window
from .input.sticks import Axes, MaxSpeeds, axes_from_pads, combine, pad_labels, pads_from_axes, velocity_from_axes
from .camera.gimbal import KEY_STEP, GimbalController
from .window.layout import fit_restored, fit_screen, show_replay_bar, steady_slots
from .camera.panel import CameraPanel
from .camera.gimbal_bar import GimbalBar
from .input.gamepad_page import GamepadPage

__all__ = ["MainWindow", "load_style"]

log = logging.getLogger(__name__)


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
    """

    def __init__(self, drone: Drone, qsettings: QSettings | None = None,
                 takeoff_altitude: float | None = None, rate_hz: float = 30.0,
                 cameras: list[str] | None = None, default_cameras: list[str] | None = None,
                 tile_cache_dir: str | None = None, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.tile_cache_dir = tile_cache_dir              # None: the per-user cache folder
        uic.loadUi(str(RESOURCES / "ui" / "main_window.ui"), self)
        self._qsettings = qsettings if qsettings is not None else default_qsettings()
        self.settings: ViewerSettings = load_settings(self._qsettings)
        self._takeoff_override = takeoff_altitude
        self.adapter = DroneAdapter(drone, rate_hz=rate_hz, parent=self)
        # every vehicle flown (a fleet's pick, File › Connect) is judged by the pilot's battery thresholds
        self.adapter.droneChanged.connect(lambda _drone: self._set_battery_thresholds())
        self._speeds = MaxSpeeds()
        self.keyboard = KeyboardSticks()
        self.gamepad = GamepadInput(self.settings, parent=self)
        self._inputs = InputSelector()
        self._last_message = -1
        self._shown_results: set[int] = set()
        self._last_result = -1
        self._last_sample_time: float | None = None
        self._plot_gap = False
        self._sticks_live = False
        self._takeoff_box: QMessageBox | None = None
        self._mode_box: QMessageBox | None = None
        self._emergency_box: QMessageBox | None = None
        self.arming = Arming(self)
        self._settings_dialog: SettingsDialog | None = None
        self._quit_box: QMessageBox | None = None
        self._quitting = False                   # closing without asking (answered, or a signal)
        self._vehicle_name = ""
        self._t0 = time.monotonic()
        self.flight_timer = FlightTimer()
        self.adapter.droneChanged.connect(lambda _drone: self.flight_timer.reset())
        self._shown_state: VehicleState | None = None   # the snapshot the views show next (refresh channels)
        # Views redraw at the rate the eye needs and not while minimised (refresh.py); logic follows every snapshot.
        self.refresh = Refresh(self)
        self._instruments = self.refresh.add(INSTRUMENTS_HZ, self._show_instruments)
        self._readouts = self.refresh.add(TEXT_HZ, self._show_readouts)
        self._plots_refresh = self.refresh.add(PLOTS_HZ, self.plots.redraw)

        self.setWindowTitle(f"UavViewerPy — {self.adapter.description}")
        self._signing_unavailable = signing_unavailable(drone)     # a remote drone is signed on its server
        self.telemetry.set_security_unknown(self._signing_unavailable)
        self.camera_panel = CameraPanel()             # video in the reserved camera area; cameras: --camera URIs
        self.instrumentSplitter.replaceWidget(self.instrumentSplitter.indexOf(self.cameraView), self.camera_panel)
        self.cameraView.deleteLater()
        self.camera_panel.show()                      # replaceWidget leaves the newcomer hidden
        self.cameraView = self.camera_panel
        self.camera_view = self.camera_panel.view
        self._default_cameras = list(default_cameras or [])
        self.camera = CameraController(self.camera_panel, list(cameras or self.settings.camera_uris
                                                               or self._default_cameras),
                                       state_fn=lambda: self.adapter.drone.state(),     # the picked vehicle's
                                       drone=lambda: self.adapter.drone,
                                       folder=self.settings.media_folder or None, parent=self)
        self.refresh.shownChanged.connect(self.camera.set_shown)
        self.gimbal_bar = GimbalBar()                 # the camera on the vehicle: tilt, its own photo and video
        self.camera_panel.layout().addWidget(self.gimbal_bar)
        self.camera_panel.add_overlay(self.gimbal_bar.stop_looking_button)
        self.gimbal = GimbalController(self.adapter, self.camera_view, self.gimbal_bar, self)
        self.camera_panel.hud_button.setChecked(self.settings.hud)
        self.menuView.addAction(self.telemetryDock.toggleViewAction())
        self.menuView.addAction(self.plotsDock.toggleViewAction())
        self.menuView.addAction(self.mapDock.toggleViewAction())
        self.map = MapController(self.mapPanel, self.adapter, self, lambda: self.takeoff_altitude, self)
        self.tabifyDockWidget(self.plotsDock, self.mapDock)            # Map and Plots share the lower right
        self.plan = PlanController(self.map, self.adapter, self, self)  # Plan mode, transfers, missions: own dock
        self.mapPanel.offlineCheck.setChecked(self.settings.map_offline)
        self.mapPanel.layerRequested.connect(lambda on: self._remember(map_tiles=on))
        self.mapPanel.offlineRequested.connect(lambda on: self._remember(map_offline=on))
        self.menuView.addAction(self.messagesDock.toggleViewAction())
        self.setCorner(Qt.BottomRightCorner, Qt.RightDockWidgetArea)   # plots run the full height
        self.resizeDocks([self.telemetryDock, self.plotsDock], [390, 560], Qt.Vertical)
        self.resizeDocks([self.telemetryDock], [400], Qt.Horizontal)
        self.resizeDocks([self.messagesDock], [110], Qt.Vertical)     # the latest line is in the status strip
        self.mapDock.raise_()
        self.instrumentSplitter.setStretchFactor(0, 3)
        self.instrumentSplitter.setStretchFactor(1, 2)
        steady_slots(self)                        # nothing moves under the cursor as the state changes
        self.link_status = QLabel()
        self.statusbar.addPermanentWidget(self.link_status)

        self.leftStick.moved.connect(self._sticks_moved)
        self.rightStick.moved.connect(self._sticks_moved)
        fc = self.flightControls
        fc.takeoffRequested.connect(self.request_takeoff)
        fc.landRequested.connect(self.request_land)
        fc.stopRequested.connect(self.request_stop)
        fc.rtlRequested.connect(self.request_rtl)
        fc.armRequested.connect(self.request_arm)
        fc.cancelTakeoffRequested.connect(self.request_cancel_takeoff)
        fc.disarmRequested.connect(self.request_disarm)
        self.modeSelector.modeRequested.connect(self.request_mode)
        self.replayBar.pauseRequested.connect(self._replay_pause)
        self.replayBar.speedRequested.connect(self._replay_speed)
        show_replay_bar(self, self.adapter.replay is not None)
        self.controlsRow.setEnabled(self.adapter.replay is None)     # a recording cannot be flown
        self.actionQuit.triggered.connect(self.close)
        self.actionPreferences.triggered.connect(self.edit_settings)
        self.actionKeys.triggered.connect(self.show_keys)
        self.actionAbout.triggered.connect(self._about)
        self.adapter.stateChanged.connect(self.show_state)
        self.adapter.commandFinished.connect(self._show_result)
        self.gamepad.changed.connect(self._fly)
        self.gamepad.actionPressed.connect(self._key_action)
        self.gamepad.message.connect(self._gamepad_message)
        self.tools = PilotTools(self)                 # connecting, alerts, preflight, guided actions, home arrow
        self.params = ParamsController(self.adapter, self, say=self.log_message)    # docs/parameters.md
        self.params.add_to_menu(self)                       # Vehicle › Parameters…
        self.params.offer_fixes(self.messages)              # a warning naming a parameter: Fix… opens it

        self._apply_settings()
        geometry, state = load_window(self._qsettings)
        if state is not None:
            self.restoreState(state)
            if "preflightDock".encode("utf-16-be") not in bytes(state):   # saved before the dock existed
                self.tools.tab_preflight()
        if geometry is not None:
            self.restoreGeometry(geometry)
            fit_restored(self)                    # saved on a larger screen: it still fits this one
        else:
            fit_screen(self)
        self.setFocusPolicy(Qt.StrongFocus)
        QApplication.instance().installEventFilter(self)
        self.show_state(VehicleState(link=self.adapter.state.link))
        self.adapter.start()

    # -- connecting (File › Connect, Disconnect, Open flight log: uavviewer/window/pilot_tools.py wires them) ----------
    def _connected(self, opened) -> None:
        """A connection opened by File › Connect (:class:`uavviewer.connect.opener.Opened`): a vehicle, or a lab's
        fleet with its Fleet panel."""
        self._leave_fleet()
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
            self.attach_fleet(FleetController(opened.fleet, opened.first, parent=self))
        if self.camera.uris == self._default_cameras and own != self._default_cameras:   # not --camera's
            self._default_cameras = own                                                  # nor Preferences'
            self.camera.set_sources(own)

    def _leave_fleet(self) -> None:
        """Another connection replaces the fleet: its panel goes; the fleet itself is closed by the connections."""
        fleet = getattr(self, "fleet", None)
        if fleet is None:
            return
        fleet.stop()
        self.mapPanel.mapView.vehicleClicked.disconnect(fleet.pick)
        self.map.show_fleet(())
        dock = self.fleet_panel.parentWidget()
        self.removeDockWidget(dock)
        dock.deleteLater()
        fleet.deleteLater()
        self.fleet = None

    def use_connection(self, drone: Drone) -> None:
        """Fly (or watch) ``drone`` from now on: File › Connect, Disconnect, Open flight log. The vehicle left
        behind was sent zero velocity first, so it hovers."""
        self.centre_sticks()
        self.map.cancel()
        self.guided.cancel()
        self._last_message = self._last_result = -1
        self._shown_results.clear()
        self._plot_gap = True
        self.plots.gap(time.monotonic() - self._t0)
        self.adapter.use(drone)
        self._vehicle_name = ""                 # the previous vehicle's name is not this one's (About, the title)
        self.map.use_connection()
        self.setWindowTitle(f"UavViewerPy — {self.adapter.description}")
        self._signing_unavailable = signing_unavailable(drone)
        self.telemetry.set_security_unknown(self._signing_unavailable)
        self._speeds = self._set_limits(self.settings.speeds)
        replay = self.adapter.replay is not None
        show_replay_bar(self, replay)
        self.controlsRow.setEnabled(not replay)
        self.attitude.clear("NO LINK")
        self.show_state(self.adapter.state)

    # -- settings --------------------------------------------------------------------------------
    def _apply_settings(self) -> None:
        left, right = pad_labels(self.settings.mode)
        self.leftStick.set_caption(left)
        self.rightStick.set_caption(right)
        self._speeds = self._set_limits(self.settings.speeds)
        self._set_battery_thresholds()
        self.gamepad.apply_settings(self.settings)
        self.centre_sticks()
        s = self.settings
        self.map.set_tile_settings(TileSettings(s.tile_url.strip(), s.tile_attribution.strip(), int(s.tile_cache_mb),
                                                self.tile_cache_dir))
        if self.settings.map_tiles and self.settings.tile_url:
            self.mapPanel.layerCombo.setCurrentIndex(1)

    def _remember(self, **choice) -> None:
        """A choice made on the window itself (the Map's layer, offline), kept for the next run."""
        self.settings = replace(self.settings, **choice)
        save_settings(self._qsettings, self.settings)

    def _set_limits(self, wish: MaxSpeeds) -> MaxSpeeds:
        """The pilot's maximum speeds become the driver's clamps; the sticks scale by what is in force."""
        drone = self.adapter.drone
        try:
            limits = drone.set_limits(Limits(wish.horizontal, wish.vertical, math.radians(wish.yaw_deg_s)))
        except NotImplementedError:
            limits = drone.limits
        except Exception:                       # noqa: BLE001 - a remote drone may fail; keep its clamps
            log.exception("setting the speed limits failed")
            limits = drone.limits
        if (limits.horizontal, limits.vertical) != (wish.horizontal, wish.vertical) \
                or not math.isclose(limits.yaw_rate, math.radians(wish.yaw_deg_s), abs_tol=1e-4):
            self.log_message(f"Maximum speeds in force: {limits.horizontal:g} m/s, {limits.vertical:g} m/s, "
                             f"{math.degrees(limits.yaw_rate):.0f}°/s", Severity.WARNING)
        return MaxSpeeds(limits.horizontal, limits.vertical, math.degrees(limits.yaw_rate))

    def _set_battery_thresholds(self) -> None:
        """The pilot's battery thresholds become the driver's alarm (a remote drone keeps its own judge)."""
        try:
            self.adapter.drone.set_battery_thresholds(self.settings.battery_thresholds)
        except NotImplementedError:
            pass
        except Exception:                       # noqa: BLE001 - a bad value or a remote failure: keep the alarm
            log.exception("setting the battery thresholds failed")

    @property
    def speeds(self) -> MaxSpeeds:
        """Full-deflection speeds: the limits the drone has in force."""
        return self._speeds

    @property
    def takeoff_altitude(self) -> float:
        """--takeoff-altitude for this run, else the Preferences' value."""
        return self._takeoff_override if self._takeoff_override is not None else self.settings.takeoff_altitude

    def edit_settings(self) -> None:
        """Not modal: Stop, Land and RTL stay one click away while it is open (its opening centres the sticks)."""
        if self._settings_dialog is not None:
            self._settings_dialog.raise_()
            self._settings_dialog.activateWindow()
            return
        shown = self.takeoff_altitude
        dialog = SettingsDialog(replace(self.settings, takeoff_altitude=shown), self,
                                signing_unavailable=self._signing_unavailable)
        dialog.setAttribute(Qt.WA_DeleteOnClose)
        # Link security acts at once, through the adapter (never waiting); its results come back to the page.
        dialog.signingKeyRequested.connect(lambda key: self._command("use_signing_key", key))
        dialog.signingSetupRequested.connect(lambda key: self._command("setup_signing", key))
        dialog.signingRemoveRequested.connect(lambda: self._command("remove_signing"))
        dialog.allowUnsignedRequested.connect(lambda on: self._command("allow_unsigned", on))
        dialog.set_signing(self.adapter.state.signing)
        gamepad = GamepadPage(self.gamepad, self.settings)
        dialog.add_page(gamepad, "Gamepad")
        dialog.accepted.connect(lambda: self._settings_chosen(replace(dialog.chosen(), **gamepad.chosen()), shown))
        # finished, not destroyed: a slot on ``destroyed`` would run while a garbage-collected window is being
        # torn down (its children go with it) and touch a half-deleted wrapper.
        dialog.finished.connect(lambda _result: setattr(self, "_settings_dialog", None))
        self._settings_dialog = dialog
        dialog.show()

    @property
    def settings_dialog(self) -> SettingsDialog | None:
        """Preferences while open."""
        return self._settings_dialog

    def _settings_chosen(self, settings: ViewerSettings, shown_altitude: float) -> None:
        if self._takeoff_override is not None and settings.takeoff_altitude == shown_altitude:
            # --takeoff-altitude was shown and left alone: it stays for this run and is not saved.
            self.set_settings(replace(settings, takeoff_altitude=self.settings.takeoff_altitude),
                              keep_override=True)
        else:
            self.set_settings(settings)

    def set_settings(self, settings: ViewerSettings, keep_override: bool = False) -> None:
        old, self.settings = self.settings, settings
        if not keep_override:
            self._takeoff_override = None        # the pilot has now chosen the altitude in Preferences
        save_settings(self._qsettings, settings)
        self._apply_settings()
        self.camera.folder = settings.media_folder or default_media_folder()
        if settings.hud != old.hud:
            self.camera_panel.hud_button.setChecked(settings.hud)
        if settings.camera_uris != old.camera_uris:          # new sources replace even --camera's
            self.camera.set_sources(settings.camera_uris or self._default_cameras)

    def show_keys(self) -> None:
        dialog = KeysDialog(self)
        dialog.setAttribute(Qt.WA_DeleteOnClose)
        dialog.open()

    def _about(self) -> None:
        """Not modal and no nested event loop: flying goes on while it is open."""
        from PyQt5.QtCore import PYQT_VERSION_STR, QT_VERSION_STR
        from pymavlink import __version__ as pymavlink_version

        from driver.version import __version__
        firmware = self.adapter.state.firmware
        box = QMessageBox(QMessageBox.Information, "About UavViewerPy",
                          f"UavViewerPy {__version__} — fly a MAVLink drone from a laptop.\n\n"
                          f"Vehicle: {self.window_name()}" + (f", ArduCopter {firmware}" if firmware else "") +
                          f"\nPyQt {PYQT_VERSION_STR}, Qt {QT_VERSION_STR}, pymavlink {pymavlink_version}"
                          f"\n\n{self.logs.about_line()}",
                          QMessageBox.Ok, self)
        box.setObjectName("aboutBox")
        box.setWindowModality(Qt.NonModal)
        box.setAttribute(Qt.WA_DeleteOnClose)
        box.show()

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
            self._remember(last_connection=choice.target)

    # -- state in --------------------------------------------------------------------------------
    def show_state(self, s: VehicleState) -> None:
        """Every snapshot: what must follow the vehicle at once (buttons, sticks, questions, messages, the plots'
        data); the views that only show it redraw through their refresh channels."""
        link = s.link
        replay = self.adapter.replay
        finished = replay is not None and replay.finished
        self.linkBanner.set_link(link.status, link.address or self.adapter.description, link.heartbeat_age,
                                 finished, "" if self._signing_unavailable else signing_warning(s.signing))
        if self._settings_dialog is not None:
            self._settings_dialog.set_signing(s.signing)
        if self._emergency_box is not None and not s.armed:
            self._emergency_box.reject()            # the motors have stopped: nothing left to ask
        self.map.show_state(s)                      # cheap; it repaints only on a change it can show
        self.gimbal.show_state(s)                   # its bar sets its texts only on a change
        self.flight_timer.update(s)                 # every arm and disarm, minimised too (shown in the text channel)
        phase = flight_phase(s)
        progress = takeoff_progress(s) if phase is FlightPhase.TAKING_OFF else None
        detail = s.takeoff.phase.value if s.takeoff.active else ""
        self.flightControls.set_vehicle(phase, s.armed, s.connected, progress, detail,
                                        waiting_for=s.readiness.missing if s.connected else (),
                                        cancellable=takeoff_cancellable(s))
        if self._takeoff_box is not None and not self._may_take_off(s):
            self._takeoff_box.reject()              # the question no longer fits the vehicle: withdraw it
        self.modeSelector.set_mode(s.mode)
        self.modeSelector.setEnabled(s.connected)
        self._set_sticks_live(s)
        for m in s.messages_since(self._last_message):
            self.messages.add_message(m.time, m.severity, m.text, m.source)
            self._last_message = m.index
        for r in s.results_since(self._last_result):
            self._last_result = r.index
            if r.index not in self._shown_results:
                self._shown_results.add(r.index)
                self.messages.add_result(r)
        have_vehicle = link.status is not LinkStatus.WAITING and bool(s.mode)
        if link.status is not LinkStatus.OK or (replay is not None and replay.paused):
            if not self._plot_gap:                  # no line drawn across the time nothing came in
                self._plot_gap = True
                self.plots.gap(time.monotonic() - self._t0)
                self._plots_refresh.mark()
        elif have_vehicle and s.time != self._last_sample_time:
            self._plot_gap = False
            self._last_sample_time = s.time
            yaw = s.attitude.yaw
            forward, right, _ = s.velocity.body(yaw)
            self.plots.append(time.monotonic() - self._t0, altitude=s.altitude, forward=forward,
                              right=right, climb=s.velocity.climb, roll=math.degrees(s.attitude.roll),
                              pitch=math.degrees(s.attitude.pitch), heading=s.heading_deg)
            self._plots_refresh.mark()
        self._shown_state = s
        self._instruments.mark()
        self._readouts.mark()

    def _show_instruments(self) -> None:
        """The attitude indicator (INSTRUMENTS_HZ)."""
        s = self._shown_state
        if s is None:
            return
        if s.link.status in (LinkStatus.LOST, LinkStatus.CLOSED):
            if self.attitude.values["flag"] != no_link_flag(s):     # the last attitude is no longer the drone's
                self.attitude.clear(no_link_flag(s))
        elif s.link.status is LinkStatus.WAITING or not s.mode:
            if self.attitude.values["flag"] != NO_VEHICLE.upper():
                self.attitude.clear(NO_VEHICLE.upper())
        else:
            self.attitude.set_attitude(s.attitude.roll, s.attitude.pitch, s.heading_deg)
            self.attitude.set_readouts(s.altitude, s.velocity.ground_speed, s.velocity.climb)

    def _show_readouts(self) -> None:
        """Numbers and status lines (TEXT_HZ): telemetry, the phase line, the status bar, the replay clock."""
        s = self._shown_state
        if s is None:
            return
        link = s.link
        self.telemetry.set_state(s)
        self.statusStrip.set_state(s, self.flight_timer.seconds)
        phase = self._phase_text(s, flight_phase(s))
        if phase != self.phaseLabel.text():
            self.phaseLabel.setText(phase)
            self.phaseLabel.setToolTip(phase)
        replay = self.adapter.replay
        if replay is not None:
            try:
                self.replayBar.set_progress(replay.position, replay.duration, replay.paused, replay.speed,
                                            replay.finished)
            except Exception:               # noqa: BLE001 - a finished replay may drop its file
                log.debug("replay progress unavailable", exc_info=True)
        pps = f"{link.packets_per_s:.0f} pkt/s" if link.status is LinkStatus.OK else link.status.value
        pinned = f"  ·  vehicle at {link.pinned_to}" if link.pinned_to else ""
        self.link_status.setText(f"{self.adapter.description}{pinned}  ·  {pps}")

    @staticmethod
    def _phase_text(s: VehicleState, phase: FlightPhase) -> str:
        if phase is FlightPhase.NO_VEHICLE:
            return no_vehicle_words(s)
        if s.link.status in (LinkStatus.LOST, LinkStatus.CLOSED):
            return link_gone_text(s, {FlightPhase.ON_GROUND: "on the ground", FlightPhase.TAKING_OFF: "taking off",
                                      FlightPhase.FLYING: f"flying in {s.mode}", FlightPhase.LANDING: "landing"}[phase])
        if phase is FlightPhase.TAKING_OFF and s.takeoff.phase is SequencePhase.WAITING_READY:
            return (f"Take off to {s.takeoff.target_altitude:.1f} m when ready — "
                    + (readiness_text(s) if s.connected and s.readiness.missing else "waiting for the vehicle"))
        if phase is FlightPhase.TAKING_OFF and s.takeoff.active:
            return f"Taking off to {s.takeoff.target_altitude:.1f} m — {s.takeoff.phase.value}"
        if phase is FlightPhase.ON_GROUND:
            return "On the ground · " + ("armed" if s.armed else readiness_text(s))
        return {FlightPhase.TAKING_OFF: "Taking off", FlightPhase.FLYING: f"Flying · {s.mode}",
                FlightPhase.LANDING: "Landing"}[phase]

    def _set_sticks_live(self, s: VehicleState) -> None:
        live = s.can_fly_velocity and self.adapter.replay is None
        hint = stick_hint(s) if self.adapter.replay is None else "Replay"
        for pad in (self.leftStick, self.rightStick):
            pad.set_hint(hint)
            if pad.isEnabled() != live:
                pad.setEnabled(live)        # disabling centres the pad
        if live != self._sticks_live:
            self._sticks_live = live
            self.keyboard.clear()           # a key held while inert needs a fresh press to fly
            self.gamepad.release()          # and the gamepad a return to the centre
            self._fly()

    # -- sticks and keys -------------------------------------------------------------------------
    def _sticks_moved(self, *_: float) -> None:
        self._fly()

    def demand(self) -> Axes:
        """The pilot's demand: both pads and the keyboard combined, or the gamepad, whichever the pilot moved
        last (zero if sticks are inert)."""
        if not self._sticks_live:
            self._inputs.reset()
            return Axes()
        pads = axes_from_pads(self.settings.mode, self.leftStick.position, self.rightStick.position,
                              self.settings.shaping)
        return self._inputs.choose(combine(pads, self.keyboard.axes()), self.gamepad.axes())

    def _fly(self) -> None:
        command = velocity_from_axes(self.demand(), self._speeds)
        self.adapter.fly(command)
        self._echo_on_pads()
        self.inputLabel.setText(self._input_text())
        if not command.is_zero:
            self.map.cancel()                   # a stick overrides a go-to
        if command.is_zero:
            self.setpointLabel.setText("Setpoint: hover")
        else:
            self.setpointLabel.setText(         # short enough for the controls' column at 1024×600
                f"fwd {command.forward:+.1f} rt {command.right:+.1f} up {command.up:+.1f} m/s "
                f"yaw {math.degrees(command.yaw_rate):+.0f}°/s")

    def _echo_on_pads(self) -> None:
        """Held keys (or the gamepad, while it flies) move the on-screen knobs: the pilot sees what flies."""
        echo = Axes()
        if self._sticks_live:
            echo = self.gamepad.axes() if self._inputs.owner is Input.GAMEPAD else self.keyboard.axes()
        left, right = pads_from_axes(self.settings.mode, echo)
        self.leftStick.set_echo(*left)
        self.rightStick.set_echo(*right)

    def _input_text(self) -> str:
        """Which input flies now, else which are there (and why the gamepad waits)."""
        pad = self.gamepad.pad
        owner = self._inputs.owner
        if owner is Input.GAMEPAD and pad is not None:
            return f"Flying: gamepad {pad.name}"
        if owner is Input.SCREEN:
            pads_held = self.leftStick.position != (0.0, 0.0) or self.rightStick.position != (0.0, 0.0)
            held = [name for name, on in (("sticks", pads_held), ("keyboard", self.keyboard.active)) if on]
            return "Flying: " + (" + ".join(held) or "sticks")
        text = "Input: sticks, keyboard"
        if pad is not None:
            status = self.gamepad.status
            text += f", gamepad {pad.name}" + (f" ({status})" if status else "")
        return text

    def centre_sticks(self, gamepad: bool = True) -> None:
        """Both pads and every key back to the centre, and (``gamepad``) the gamepad waits for its centre;
        the new demand goes out (zero, unless the gamepad flies on)."""
        self.keyboard.clear()
        self.leftStick.centre()
        self.rightStick.centre()
        if gamepad:
            self.gamepad.release()
        self._fly()

    def _gamepad_message(self, text: str, severity: Severity) -> None:
        self.log_message(text, severity)
        self.statusbar.showMessage(text, 8000)

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:  # noqa: N802
        """Keys fly only when aimed at this window, but a release counts wherever it lands, and a menu,
        popup or dialog opening centres everything (the release would go to it)."""
        kind = event.type()
        if kind == QEvent.KeyRelease and not event.isAutoRepeat() and event.key() in AXIS_KEYS:
            if self.keyboard.release(event.key()):
                self._fly()
        elif kind == QEvent.Show and self._interrupts(watched):
            if isinstance(watched, QDialog):
                fit_dialog(watched)                 # every dialog fits the screen, its buttons in reach
            self.centre_sticks()
            return False
        if kind in (QEvent.KeyPress, QEvent.KeyRelease) and self._owns(watched) and self.adapter.replay is None:
            if QApplication.activeModalWidget() is not None or QApplication.activePopupWidget() is not None:
                return False
            if event.isAutoRepeat():
                return event.key() in ACTION_KEYS or event.key() in AXIS_KEYS   # held: already acted
            if kind == QEvent.KeyPress:
                return self._key_pressed(event.key(), event.modifiers())
            return event.key() in ACTION_KEYS or event.key() in AXIS_KEYS
        return False

    def _interrupts(self, watched: QObject) -> bool:
        """A menu, popup list or dialog is opening: it will take the keys (tooltips do not)."""
        if not isinstance(watched, QWidget) or not watched.isWindow() or watched is self:
            return False
        return isinstance(watched, QDialog) or watched.windowType() in (Qt.Popup, Qt.Dialog)

    def _owns(self, watched: QObject) -> bool:
        return isinstance(watched, QWidget) and watched.window() is self

    def _key_pressed(self, key: int, modifiers) -> bool:
        if modifiers & (Qt.ControlModifier | Qt.AltModifier | Qt.MetaModifier):
            return False
        if self.keyboard.press(key):
            self._fly()
            return True
        action = ACTION_KEYS.get(key)
        if action is None:
            return False
        self._key_action(action[0])
        return True

    def _key_action(self, action: str) -> None:
        """Space, T and L (and the gamepad's buttons) do what their button does, and only while it is enabled."""
        fc = self.flightControls
        if action == "stop":
            fc.stop_button.click()              # click() does nothing on a disabled button
        elif action == "rtl":
            fc.rtl_button.click()
        elif action == "takeoff" and fc.phase is FlightPhase.ON_GROUND:
            fc.main_button.click()
        elif action == "land" and fc.phase in (FlightPhase.TAKING_OFF, FlightPhase.FLYING):
            fc.main_button.click()
        elif action in ("tilt_up", "tilt_down"):      # the vehicle's camera (uavviewer.camera.gimbal)
            self.gimbal.tilt_by(KEY_STEP if action == "tilt_up" else -KEY_STEP)

    def changeEvent(self, event: QEvent) -> None:  # noqa: N802
        # Focus lost or minimised: nobody holds the sticks or keys any more; the gamepad flies on only if the
        # pilot chose "fly in background".
        if event.type() == QEvent.ActivationChange:
            self.gamepad.set_focus(self.isActiveWindow())
            if not self.isActiveWindow():
                self.centre_sticks(gamepad=False)
        elif event.type() == QEvent.WindowStateChange and self.isMinimized():
            self.centre_sticks(gamepad=False)
        super().changeEvent(event)

    def hideEvent(self, event) -> None:  # noqa: N802
        self.centre_sticks()
        super().hideEvent(event)

    # -- commands ---------------------------------------------------------------------------------
    def _command(self, name: str, *args) -> None:
        self.adapter.command(name, *args)

    def request_mode(self, name: str) -> None:
        """Switch at once, or ask first when the driver says the mode needs an RC transmitter in flight."""
        warning = mode_warning(name, self.adapter.state.flying)
        if warning is None:
            self._command("set_mode", name)
            return
        self._mode_box = ask(mode_question(self, name, warning), lambda box: self._mode_answered(box, name))

    def _mode_answered(self, box: QMessageBox, name: str) -> None:
        if box.clickedButton() is box.button(QMessageBox.Yes):
            self._command("set_mode", name)
        box.deleteLater()
        if self._mode_box is box:
            self._mode_box = None

    @property
    def mode_box(self) -> QMessageBox | None:
        return self._mode_box

    def request_takeoff(self) -> None:
        """Ask once, showing the altitude; the answer comes back without blocking."""
        if self._takeoff_box is not None and self._takeoff_box.isVisible():
            return
        altitude = self.takeoff_altitude
        waiting = self.adapter.state.readiness.missing
        wait_limit = getattr(getattr(self.adapter.drone, "config", None), "ready_timeout", 60.0)   # embedded: its own
        self._takeoff_box = ask(takeoff_question(self, altitude, waiting, wait_limit),
                                lambda box: self._takeoff_answered(box, altitude))

    @property
    def takeoff_box(self) -> QMessageBox | None:
        return self._takeoff_box

    def _may_take_off(self, s: VehicleState) -> bool:
        """What the takeoff question assumes: on the ground with the link up."""
        return flight_phase(s) is FlightPhase.ON_GROUND and s.link.status is LinkStatus.OK

    def _takeoff_answered(self, box: QMessageBox, altitude: float) -> None:
        if box.clickedButton() is box.button(QMessageBox.Yes):
            self._take_off_if_still_fits(altitude)
        box.deleteLater()
        if self._takeoff_box is box:
            self._takeoff_box = None

    def request_cancel_takeoff(self) -> None:
        """Cancel a takeoff that has not left the ground: the driver gives the vehicle back as it was."""
        self.centre_sticks()
        self._command("cancel_takeoff")

    def request_arm(self) -> None:
        """Arm only after a question that says what happens next in this mode, or how to get to a mode that arms
        (uavviewer/flight/arming.py)."""
        self.arming.request()

    @property
    def arm_box(self) -> QMessageBox | None:
        return self.arming.box

    def request_disarm(self) -> None:
        """On the ground, a disarm. In the air, disarming stops the motors and the drone falls: the pilot is
        asked every time, and only a confirmed emergency stop is sent."""
        if not self.adapter.state.flying:
            self._command("disarm")
            return
        if self._emergency_box is not None and self._emergency_box.isVisible():
            return
        self._emergency_box = ask(emergency_stop_question(self), self._emergency_answered)

    def _emergency_answered(self, box: QMessageBox) -> None:
        if box.clickedButton() is box.button(QMessageBox.Yes):
            self.centre_sticks()
            self._command("disarm", True, True)          # force and emergency: the motors stop, even in the air
        box.deleteLater()
        if self._emergency_box is box:
            self._emergency_box = None

    @property
    def emergency_box(self) -> QMessageBox | None:
        return self._emergency_box

    def _take_off_if_still_fits(self, altitude: float) -> None:
        """A takeoff the pilot confirmed, sent only if the vehicle is still on the ground with a link."""
        if self._may_take_off(self.adapter.state):
            self._command("takeoff", altitude)
        else:
            self.log_message("Takeoff not sent: the vehicle is no longer on the ground with a link",
                             Severity.WARNING)

    def request_land(self) -> None:
        self.centre_sticks()
        self.map.cancel()
        self._command("land")

    def request_stop(self) -> None:
        """Stop (button, Space, Escape): hover where it is; a go-to in progress ends there."""
        self.centre_sticks()
        self.map.cancel()
        self._command("stop")

    def request_rtl(self) -> None:
        self.map.cancel()
        self._command("return_to_launch")

    def _show_result(self, result) -> None:
        if result.command.startswith("signing") and self._settings_dialog is not None:
            self._settings_dialog.show_signing_result(result)
        if result.index and result.index in self._shown_results:
            return
        if result.index:
            self._shown_results.add(result.index)
        self.messages.add_result(result)
        if not result.ok:
            self.statusbar.showMessage(str(result), 8000)

    def _replay_pause(self, pause: bool) -> None:
        replay = self.adapter.replay
        if replay is not None:
            replay.pause() if pause else replay.resume()

    def _replay_speed(self, speed: float) -> None:
        replay = self.adapter.replay
        if replay is not None:
            replay.speed = speed

    # -- closing ----------------------------------------------------------------------------------
    def quit_without_asking(self) -> None:
        """Ctrl+C or kill in the terminal: close now, even in flight (said in the log)."""
        if flight_phase(self.adapter.state).airborne and self.adapter.replay is None:
            s = self.adapter.state
            log.warning("closing while the vehicle is in the air: %s", unattended(s.mode, s.gcs_failsafe))
        self._quitting = True
        if self._quit_box is not None:
            self._quit_box.reject()
        self.close()

    def _ask_before_leaving_the_air(self) -> bool:
        """Closing with the vehicle in the air: ask (Land / Quit anyway / Cancel) and keep the window."""
        if self._quitting or self.adapter.replay is not None or not flight_phase(self.adapter.state).airborne:
            return False
        if self._quit_box is None:
            s = self.adapter.state
            box = QMessageBox(QMessageBox.Warning, "The vehicle is flying",
                              f"The vehicle is in the air in {s.mode}. Without this window nobody commands it: "
                              f"{unattended(s.mode, s.gcs_failsafe)}.", QMessageBox.NoButton, self)
            box.setObjectName("quitQuestion")
            land = box.addButton("Land", QMessageBox.AcceptRole)
            leave = box.addButton("Quit anyway", QMessageBox.DestructiveRole)
            box.addButton(QMessageBox.Cancel)
            box.setDefaultButton(land)
            self._quit_box = ask(box, lambda box: self._quit_answered(box, land, leave))
        return True

    def _quit_answered(self, box: QMessageBox, land, leave) -> None:
        clicked = box.clickedButton()
        self._quit_box = None
        box.deleteLater()
        if clicked is land:
            self.request_land()
        elif clicked is leave:
            self.quit_without_asking()

    @property
    def quit_box(self) -> QMessageBox | None:
        return self._quit_box

    def closeEvent(self, event) -> None:  # noqa: N802
        if self._ask_before_leaving_the_air() or (not self._quitting and self.plan.ask_before_closing()):
            event.ignore()
            return
        self.centre_sticks()
        self.plan.show_plan(False)                # the docks that stepped out for Plan are saved as they were
        save_settings(self._qsettings, self.settings)
        save_window(self._qsettings, self.saveGeometry(), self.saveState())
        QApplication.instance().removeEventFilter(self)
        self.alerts.close()
        self.gamepad.close()
        self.camera.close(wait=0.5)
        self.adapter.stop()
        super().closeEvent(event)

    # -- fleet (docs/fleet.md): several vehicles; the sticks, keys, buttons and instruments follow the picked one --
    def attach_fleet(self, fleet) -> None:
        """A Fleet dock for ``fleet`` (:class:`uavviewer.fleet.controller.FleetController`), already flying its picked vehicle."""
        from PyQt5.QtWidgets import QDockWidget

        from .fleet.panel import FleetPanel
        self.fleet, self.fleet_box = fleet, None
        self.fleet_panel = FleetPanel()
        dock = QDockWidget("Fleet", self)
        dock.setObjectName("fleetDock")
        dock.setWidget(self.fleet_panel)
        self.addDockWidget(Qt.LeftDockWidgetArea, dock)
        self.resizeDocks([dock], [400], Qt.Horizontal)          # every column in sight, the link age too
        self.menuView.addAction(dock.toggleViewAction())
        self.fleet_panel.vehiclePicked.connect(fleet.pick)
        self.fleet_panel.allRequested.connect(self.request_all)
        fleet.rowsChanged.connect(self.fleet_panel.set_rows)
        fleet.vehiclePicked.connect(self._fly_vehicle)
        fleet.said.connect(self.log_message)
        fleet.resultArrived.connect(self._show_result)
        fleet.vehiclesRead.connect(self.map.show_fleet)                 # the map shows all of them
        self.mapPanel.mapView.vehicleClicked.connect(fleet.pick)         # a click on one there picks it too
        self.map.use_vehicle(fleet.picked)
        self.setWindowTitle(f"UavViewerPy — {fleet.picked} · {fleet.fleet.description}")
        fleet.start()

    def _fly_vehicle(self, name: str, drone: Drone) -> None:
        self.centre_sticks()                    # the vehicle left behind gets zero velocity: it hovers
        if self.map.use_vehicle(name):          # ... and a Fly here on its way ends where it is, as Stop does
            self._command("stop")               # (still the previous vehicle: adapter.use comes below)
        s = drone.state()                       # its log starts from now: older lines were another vehicle's
        self._last_message = s.messages[-1].index if s.messages else -1
        self._last_result = s.results[-1].index if s.results else -1
        self._shown_results.clear()
        self._plot_gap = True
        self.plots.gap(time.monotonic() - self._t0)
        self.adapter.use(drone)
        self.setWindowTitle(f"UavViewerPy — {name} · {self.fleet.fleet.description}")
        if self._default_cameras and self.camera.uris == self._default_cameras:   # not --camera nor Preferences'
            self._default_cameras = [self.fleet.camera_uri(name)]                 # the picked vehicle's own
            self.camera.set_sources(self._default_cameras)

    def request_all(self, command: str) -> None:
        """Take off, land or stop every vehicle, after one confirmation."""
        from .preferences.dialog import all_vehicles_question
        names = [r.name for r in self.fleet.rows]
        if not names or (self.fleet_box is not None and self.fleet_box.isVisible()):
            return
        if command != "takeoff":
            self.centre_sticks()
        self.fleet_box = ask(all_vehicles_question(self, command, names, self.takeoff_altitude),
                             lambda box: self._all_answered(box, command))

    def _all_answered(self, box: QMessageBox, command: str) -> None:
        if box.clickedButton() is box.button(QMessageBox.Yes):
            args = (self.takeoff_altitude,) if command == "takeoff" else ()
            self.fleet.command_all(command, *args, skip=self.fleet.picked)
            # the picked one through the window's own path (a Fly here ends, a takeoff is checked again);
            # its answer is shown once
            {"takeoff": lambda: self._take_off_if_still_fits(*args), "land": self.request_land,
             "stop": self.request_stop}[command]()
        box.deleteLater()
        if self.fleet_box is box:
            self.fleet_box = None

    def log_message(self, text: str, severity: Severity = Severity.INFO) -> None:
        """A line of the viewer's own in Messages (e.g. a refused setting)."""
        self.messages.add_message(time.time(), severity, text, "viewer")

