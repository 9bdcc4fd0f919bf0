"""The MAVLinkServer core: one ArduCopter vehicle over one MAVLink link.

:class:`Vehicle` is the façade of the embedded driver behind the viewer and the Ice server: it holds the
pilot's calls (the :class:`~driver.vehicle.api.Drone` interface) and hands each job to the part that does it:

* :mod:`driver.vehicle.reader`: the reader thread, opening the link, parsing and dispatching what comes in;
* :mod:`driver.vehicle.ticker`: the ticker thread and the one way out (heartbeat, setpoints, every part's sends);
* :mod:`driver.vehicle.telemetry` folds telemetry into the state (pure, no I/O);
* :mod:`driver.vehicle.supervision` keeps the link supervised and asks the vehicle for streams, home, parameters;
* :mod:`driver.vehicle.commands` sends commands with retries and matches each reply to what it answers;
* :mod:`driver.vehicle.setpoints` streams the velocity setpoint, with the deadman;
* :mod:`driver.vehicle.takeoff` runs the takeoff sequence against the public :class:`~driver.vehicle.api.Drone` interface;
* :mod:`driver.vehicle.missions`, :mod:`driver.vehicle.parameters`, :mod:`driver.vehicle.signing_control`,
  :mod:`driver.payload.control`, :mod:`driver.setup.control` and :mod:`driver.logs.control`: plans, parameters,
  signing, the payload, setup and the DataFlash logs, wired to this vehicle;
* :mod:`driver.vehicle.store` publishes immutable :class:`~driver.vehicle.state.VehicleState` snapshots.

Two threads do all the link work, so no caller ever waits on the network. Both decide under the state lock and
write to the link only after releasing it, so a slow serial write never stalls the reader or
:meth:`Vehicle.set_velocity`. Command results settle on a small fixed pool (:class:`~driver.vehicle.commands.Notifier`).
"""
from __future__ import annotations

import logging
import threading
import time
from concurrent.futures import Future
from dataclasses import dataclass, field, replace

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core import frames
from ..core.results import chain
from ..link.forwarding import Forwarder
from ..link.signing import LinkSigning, SigningConfig
from ..link.connection import open_transport
from ..link.tlog import ReplayControl, TlogWriter
from ..mission.plan import Plan, PlanKind
from ..params.manager import ParameterManager
from ..params.setter import SET_RETRY
from ..payload.control import Payload
from ..logs.control import LogControl
from ..setup.control import VehicleSetup
from ..shots.control import ShotControl
from .api import CEILING, Drone, Limits
from .commands import CommandSender, Notifier, command_name
from .missions import MissionControl
from .parameters import Parameters
from .ports import vehicle_ports
from .reader import Reader
from .rules import (
    COPTER_MODES, MAX_ALTITUDE, MIN_TAKEOFF_ALTITUDE, go_to_problem, ground_only, not_in_flight, takeoff_altitude_problem,
)
from .sequence import SequenceSlot
from .setpoints import SetpointStreamer
from .signing_control import SigningControl
from .state import (
    Battery, BatteryThresholds, CommandResult, CommandStatus, LinkHealth, LinkStatus, Setpoint, Severity, VehicleState,
)
from .store import StateStore
from .supervision import LinkSupervisor
from .takeoff import TakeoffSequence
from .telemetry import COPTER_MODE_NAMES
from .ticker import MASK_POSITION, Ticker

log = logging.getLogger("driver.vehicle")       # the façade and its parts log as one

__all__ = ["Vehicle", "VehicleConfig", "ReplayControl", "COPTER_MODES", "COPTER_MODE_NAMES",
           "MIN_TAKEOFF_ALTITUDE", "MAX_ALTITUDE", "takeoff_altitude_problem", "MASK_POSITION"]

ARM_FORCE_MAGIC = 21196


@dataclass(frozen=True)
class VehicleConfig:
    connection: str = "udpin:0.0.0.0:14550"   # any mavutil string, or a .tlog file to replay
    baud: int = 57600
    source_system: int = 255                  # ArduPilot ignores manual control from other ids
    source_component: int = 190               # MAV_COMP_ID_MISSIONPLANNER
    target_system: int = 0                    # 0: the first vehicle heard
    target_component: int = 1                 # the autopilot: only it decides mode, arming and framing
    stream_rate: int = 4                      # Hz, MAVProxy's default
    attitude_rate: int = 10                   # Hz for ATTITUDE and VFR_HUD, as QGroundControl
    takeoff_altitude: float = 3.0             # m above home
    max_altitude: float = MAX_ALTITUDE
    max_distance: float = 500.0               # m from home: no go-to target beyond it
    limits: Limits = field(default_factory=Limits)
    tlog_path: str | None = None
    tlog_append: bool = False
    outputs: tuple[str, ...] = ()             # forward to other ground stations, e.g. "udp:127.0.0.1:14551"
    loss_timeout: float = 3.5                 # s without a heartbeat before the link is lost (QGC)
    deadman: float = 0.5                      # s without set_velocity before the setpoint falls to zero
    setpoint_rate: float = 20.0               # Hz while streaming
    command_timeout: float = 3.0              # s per attempt (QGC re-sends 3 s apart)
    command_attempts: int = 3
    param_retry: float = SET_RETRY            # s without a PARAM_VALUE echo before PARAM_SET goes again
    ready_timeout: float = 60.0               # s the takeoff waits for readiness before trying anyway
    climb_timeout: float = 20.0               # s for the climb to 95 % of the target, plus 2 s a metre
    mavlink_version: int | None = None        # None: start on 1, follow the autopilot to 2
    battery_cells: int | None = None          # None: from the vehicle, or inferred from the first voltage
    battery_thresholds: BatteryThresholds = field(default_factory=BatteryThresholds)   # the pilot's own alarm
    replay_speed: float = 1.0
    heartbeat_interval: float = 1.0
    signing: SigningConfig | None = None      # MAVLink 2 signing (driver.link.signing); None: off until a key is given
    allowed_senders: tuple[str, ...] = ()     # UDP: other addresses read besides the vehicle's ("10.1.1.1")
    param_metadata: str | None = None         # apm.pdef.xml; None: the per-user cache's, else the shipped copy
    param_cache: str | None = ""              # folder of tables per vehicle; "": the per-user cache, None: none
    param_ftp: bool = True                    # read all parameters over MAVLink FTP where the vehicle offers it


class Vehicle(Drone):
    """An ArduCopter reached over MAVLink; the embedded driver behind the viewer and the Ice server. ``clock`` (s) times
    all it does (link loss, retries, deadman, takeoff, transfers): real by default; a test's own, with :meth:`step`."""

    def __init__(self, config: VehicleConfig | None = None, clock=time.monotonic):
        self.config = cfg = config or VehicleConfig()
        self.clock = clock
        self._transport = open_transport(cfg.connection, cfg.baud, cfg.source_system,
                                         cfg.source_component, cfg.replay_speed, cfg.allowed_senders)
        self._replay = ReplayControl(self._transport) if self._transport.is_replay else None
        self._signing = LinkSigning(cfg.signing, self._transport.description)
        self._v2 = cfg.mavlink_version == 2
        self._tlog = TlogWriter(cfg.tlog_path, cfg.tlog_append) if cfg.tlog_path and not self._replay else None
        battery = Battery(cells=cfg.battery_cells, cells_source="configured") if cfg.battery_cells else Battery()
        battery = replace(battery, thresholds=cfg.battery_thresholds)
        self._store = StateStore(VehicleState(link=LinkHealth(address=self._transport.description), battery=battery),
                                 self._transport.wall_time)
        self._lock = self._store.lock
        self._target = cfg.target_system
        self._autopilot = cfg.target_component       # 0: any component speaks for the vehicle
        self._notifier = Notifier()
        self._commands = CommandSender(self._store, cfg, self._notifier, self._target_ids)
        self._link = LinkSupervisor(cfg, self._transport, self._commands.capabilities, self._target_ids, clock)
        self._params = ParameterManager(self._store, self._notifier, self._target_ids, 2 * cfg.loss_timeout,
                                        cfg.param_retry)
        self._params.use_ftp = cfg.param_ftp
        self._setpoints = SetpointStreamer(cfg.deadman, cfg.setpoint_rate)
        self._payload = Payload(self)         # gimbal, region of interest, camera (driver.payload)
        self._sequence = SequenceSlot(self._store, self._commands, self._notifier)   # takeoff or mission start
        self._limits = cfg.limits.within(CEILING)
        self._wake = threading.Event()
        self._closing = threading.Event()
        self._threads: list[threading.Thread] = []
        self._ticker_thread: threading.Thread | None = None
        self._started = False
        # the parts that do the work, each one job (see the module's docstring)
        self._ticker = Ticker(self)                    # the ticker thread and the one way out to the link
        #: the narrow services the parts are handed (driver.core.ports), instead of this vehicle
        self.ports = vehicle_ports(clock, self._store, self._ticker, self._wake, self._target_ids, lambda: self._v2,
                                   self._command_long, self._set_mode, self._finish, self._notifier)
        self._parameters = Parameters(self)            # parameter table, cache, checked writes, metadata
        self._signing_control = SigningControl(self)   # keys and SETUP_SIGNING
        self._forwarder = Forwarder(cfg.outputs, cfg.baud, self._ticker.forward_to_vehicle,
                                    lambda text: self._store.add_message(Severity.WARNING, text), self._closing)
        self._missions = MissionControl(self)          # transfers, mission state, AUTO (driver.vehicle.missions)
        self.setup, self.logs = VehicleSetup(self), LogControl(self)     # calibrations, motor test, traffic; logs
        self.shots = ShotControl(self.ports, self._payload, self._setpoints, cfg, self._parameters.set)   # smart shots
        self._reader = Reader(self)                    # the reader thread: parse, fold, dispatch (built last)

    # -- lifecycle ---------------------------------------------------------------------------------
    @property
    def description(self) -> str:
        return self._transport.description

    @property
    def limits(self) -> Limits:
        return self._limits

    def set_limits(self, limits: Limits) -> Limits:
        self._limits = limits.within(CEILING)         # one reference swap: safe from any thread
        return self._limits

    def set_battery_thresholds(self, thresholds: BatteryThresholds) -> BatteryThresholds:
        problem = thresholds.problem()
        if problem:
            raise ValueError(problem)
        with self._lock:
            self._store.set(battery=replace(self._store.view()["battery"], thresholds=thresholds))
            self._store.publish()
        return thresholds

    @property
    def replay(self) -> ReplayControl | None:
        return self._replay

    def start(self) -> "Vehicle":
        """Open the link in the background and begin supervising it. Returns at once."""
        if self._started:
            return self
        self._started = True
        if self._tlog:
            self._store.add_message(Severity.INFO, f"Recording the flight log to {self._tlog.path}")
        for target, name in ((self._reader.run, "mavlink-reader"), (self._ticker.run, "mavlink-ticker")):
            t = threading.Thread(target=target, name=name, daemon=True)
            t.start()
            self._threads.append(t)
        self._ticker_thread = self._threads[-1]
        self._threads += self._forwarder.start()
        threading.Thread(target=self._parameters.metadata, name="param-metadata", daemon=True).start()
        return self

    def close(self) -> None:
        if self._closing.is_set():
            return
        with self._lock:
            self._sequence.abort("driver closed")
            moving = not self._setpoints.setpoint.is_zero
        if self._started and moving:
            self._ticker.send(self._ticker.setpoint_message(Setpoint()))   # leave it hovering, not drifting
        self._closing.set()
        self._wake.set()
        self._transport.close()
        self._forwarder.close()
        for t in self._threads:
            t.join(timeout=2.0)
        self._missions.close()
        self.logs.close()
        with self._lock:
            self._commands.abort_all("driver closed")
            self._params.abort_all("driver closed")
            self._store.set(link=self._link.health(self._version, LinkStatus.CLOSED))
            self._store.publish()
        self._notifier.close()
        self._signing.save()
        if self._tlog:
            self._tlog.close()

    def step(self) -> list:
        """One pass of the ticker at ``clock()`` on a vehicle not started: what it would send (unsent), for tests."""
        assert not self._started, "a started vehicle's ticker thread steps it"
        return self._ticker.step(self.clock())

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.close()

    # -- state -------------------------------------------------------------------------------------
    def state(self) -> VehicleState:
        return self._store.state

    def wait_for(self, predicate, timeout: float) -> VehicleState | None:
        """Block until ``predicate(state)`` holds; for tests and the console, never the UI thread."""
        return self._store.wait_for(predicate, timeout, self._closing)

    @property
    def _version(self) -> int:
        return 2 if self._v2 else 1

    def _target_ids(self) -> tuple[int, int]:
        return self._target or 1, self.config.target_component

    # -- the link, both ways (driver.vehicle.reader, driver.vehicle.ticker) ------------------------
    def ingest(self, data: bytes) -> int:
        """Parse raw bytes as if read from the link and fold them into the state; returns messages parsed."""
        return self._reader.ingest(data)

    def _post(self, msg) -> None:
        """Send from the ticker thread: callers (the UI among them) never touch the link themselves."""
        self._ticker.post(msg)

    # -- commands ----------------------------------------------------------------------------------
    def command_long(self, command: int, params=(), name: str | None = None, *, guard=None) -> Future:
        """Send any MAV_CMD as COMMAND_LONG with ACK handling and retries."""
        name = name or command_name(command)
        return self._busy(name) or self._command_long(command, params, name, guard=guard)

    def _command_long(self, command: int, params=(), name: str | None = None, *, guard=None) -> Future:
        name = name or command_name(command)
        params = [float(p) for p in (list(params) + [0.0] * 7)[:7]]
        if not frames.finite(*params):
            return self._finish(name, CommandStatus.REJECTED, "parameter is not a finite number")
        if self._replay is not None:
            return self._finish(name, CommandStatus.REJECTED, "replaying a recording: no vehicle to command")
        with self._lock:
            future = self._commands.submit(name, command, params, self.clock(), guard=guard,
                                           tag=self._sequence.tag)
        self._wake.set()
        return future

    def _finish(self, command: str, status: CommandStatus, reason: str = "") -> Future:
        f: Future = Future()
        f.set_result(self._store.record(command, status, reason))
        return f

    def _busy(self, command: str) -> Future | None:
        if self._sequence.stepping and threading.current_thread() is self._ticker_thread:
            return None                               # the sequence's own commands
        if self.state().takeoff.active:
            return self._finish(command, CommandStatus.REJECTED, "takeoff in progress: only Land and Stop")
        return None

    def set_mode(self, name: str) -> Future:
        self.shots.end(f"mode {name}")                # driver.shots: the pilot's mode always wins
        return self._busy(f"mode {name}") or self._set_mode(name)

    def _set_mode(self, name: str) -> Future:
        number = COPTER_MODES.get(name.upper())
        if number is None:
            return self._finish(f"mode {name}", CommandStatus.REJECTED,
                                f"unknown mode; known: {', '.join(sorted(COPTER_MODES))}")
        if self._replay is not None:
            return self._finish(f"mode {name.upper()}", CommandStatus.REJECTED,
                                "replaying a recording: no vehicle to command")
        if self.state().mode == name.upper() and self.state().connected:
            return self._finish(f"mode {name.upper()}", CommandStatus.ACCEPTED, "already in that mode")
        with self._lock:
            future = self._commands.submit_mode(f"mode {name.upper()}", number, self.clock(),
                                                tag=self._sequence.tag)
        self._wake.set()
        return future

    def arm(self, force: bool = False) -> Future:
        return self._busy("arm") or self._command_long(
            mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (1, ARM_FORCE_MAGIC if force else 0),
            "arm (forced)" if force else "arm")

    def disarm(self, force: bool = False, emergency: bool = False) -> Future:
        if emergency and force:                       # the pilot confirmed it: the motors stop, even in the air
            self._abort_takeoff("emergency motor stop")
            return self._command_long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (0, ARM_FORCE_MAGIC),
                                      "emergency motor stop")
        if force:                                     # forced disarm in the air stops the motors: a crash
            problem = not_in_flight(self.state())
            if problem:
                return self._finish("disarm (forced)", CommandStatus.REJECTED, problem)
        return self._busy("disarm") or self._command_long(
            mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (0, ARM_FORCE_MAGIC if force else 0),
            "disarm (forced)" if force else "disarm", guard=not_in_flight if force else None)

    def land(self) -> Future:
        self.shots.end("Land")                        # driver.shots: Land always wins
        self._abort_takeoff("landing")
        return self._set_mode("LAND")

    def cancel_takeoff(self) -> Future:
        """The pilot's Cancel before liftoff: the sequence ends, and what it changed is undone (disarm if it
        armed, back to the mode it left); once NAV_TAKEOFF went out it is Stop (hold where it is). Never LAND."""
        seq = self._sequence.current
        if seq is None or not seq.nothing_flown:
            return self.stop()
        self._abort_takeoff("cancelled before liftoff")
        if seq.takeoff_sent:                          # NAV_TAKEOFF went out meanwhile: hold, never disarm
            return self.stop()
        s = self.state()
        undone = []
        if s.armed and not seq.armed_before:
            self._command_long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (0, 0), "disarm (takeoff cancelled)",
                               guard=not_in_flight)
            undone.append("disarming")
        # GUIDED asked: the vehicle may be in it before its heartbeat says so; asking for the mode it is in is harmless
        if seq.mode_before and (s.mode != seq.mode_before or (seq.guided_sent and seq.mode_before != "GUIDED")):
            self._set_mode(seq.mode_before)
            undone.append(f"back to {seq.mode_before}")
        return self._finish("cancel takeoff", CommandStatus.ACCEPTED,
                            "cancelled before liftoff: " + (", ".join(undone) or "the vehicle was not changed"))

    def return_to_launch(self) -> Future:
        self.shots.end("RTL")                         # driver.shots: RTL always wins
        return self._busy("RTL") or self._set_mode("RTL")

    def stop(self) -> Future:
        """Hold position, and the sticks fly again: zero velocity in GUIDED (which also cancels a go-to); in
        flight in another mode (RTL, LOITER, LAND...), GUIDED with zero velocity, where ArduCopter brakes to its
        stopping point and holds it (ModeGuided::init); BRAKE if the vehicle refuses GUIDED (no position).
        During a takeoff that has not left the ground it is :meth:`cancel_takeoff`: the vehicle as it was."""
        self.shots.end("Stop")                        # driver.shots: Stop always wins
        seq = self._sequence.current
        if seq is not None and seq.nothing_flown:
            return self.cancel_takeoff()
        taking_off = self.state().takeoff.active
        self._abort_takeoff("stop")
        s = self.state()
        if not s.flying and not s.armed:
            return self._finish("stop", CommandStatus.ACCEPTED,
                                "takeoff aborted" if taking_off else "on the ground: nothing to stop")
        if s.mode == "GUIDED":
            with self._lock:
                self._setpoints.stop(self.clock())
                self._store.set(setpoint=self._setpoints.setpoint)
                self._store.publish()
            self._wake.set()
            return self._finish("stop", CommandStatus.ACCEPTED, "holding position (zero velocity in GUIDED)")
        return self._hold_in_guided(s.mode)

    def _hold_in_guided(self, was: str) -> Future:
        """Stop outside GUIDED: zeros wait to stream, GUIDED is asked; if refused, BRAKE (the sticks then stay
        inert until GUIDED is possible, and the result says why)."""
        with self._lock:
            self._setpoints.stop(self.clock())
            self._store.set(setpoint=self._setpoints.setpoint)

        def guided_answered(r: CommandResult):
            if r.ok:
                return self._store.record("stop", CommandStatus.ACCEPTED,
                                          f"holding position in GUIDED (was {was}): the sticks fly")
            return chain(self._set_mode("BRAKE"), lambda b: self._store.record(
                "stop", b.status, f"GUIDED refused ({r.reason}): BRAKE, {b.reason}"), "stop")
        return chain(self._set_mode("GUIDED"), guided_answered, "stop")

    def reboot(self) -> Future:
        problem = ground_only(self.state())
        if problem:
            return self._finish("reboot", CommandStatus.REJECTED, problem)
        return self._busy("reboot") or self._command_long(mavlink.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, (1,), "reboot",
                                                          guard=ground_only)

    def calibrate_level(self) -> Future:
        """Level (accelerometer trim) calibration; only sensible disarmed on the ground."""
        problem = ground_only(self.state())
        if problem:
            return self._finish("level calibration", CommandStatus.REJECTED, problem)
        return self._busy("level calibration") or self._command_long(
            mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, (0, 0, 0, 0, 2, 0, 0), "level calibration", guard=ground_only)

    def parachute(self, action: str) -> Future:
        actions = {"disable": mavlink.PARACHUTE_DISABLE, "enable": mavlink.PARACHUTE_ENABLE,
                   "release": mavlink.PARACHUTE_RELEASE}
        if action not in actions:
            return self._finish(f"parachute {action}", CommandStatus.REJECTED, "use enable, disable or release")
        # never blocked by a takeoff: a parachute is the last resort
        return self._command_long(mavlink.MAV_CMD_DO_PARACHUTE, (actions[action],), f"parachute {action}")

    def set_safety(self, on: bool) -> Future:
        """Safety switch on (motors locked) or off, as MAVProxy's ``arm safetyon/safetyoff``."""
        self._post(mavlink.MAVLink_set_mode_message(
            self._target_ids()[0], mavlink.MAV_MODE_FLAG_DECODE_POSITION_SAFETY, 1 if on else 0))
        return self._finish(f"safety {'on' if on else 'off'}", CommandStatus.ACCEPTED, "sent (not acknowledged)")

    # -- parameters (driver.vehicle.parameters) ----------------------------------------------------
    def fetch_parameters(self, refresh: bool = False) -> Future:
        """Download every parameter into ``state().parameters`` (driver.params.download)."""
        return self._parameters.fetch(refresh)

    def set_parameter(self, name: str, value: float, allow_out_of_bounds: bool = False) -> Future:
        """PARAM_SET in the parameter's own type, confirmed by the vehicle's echo (driver.params.setter); outside
        ArduPilot's documented bounds only when ``allow_out_of_bounds`` (driver.params.metadata)."""
        return self._parameters.set(name, value, allow_out_of_bounds)

    @property
    def parameter_metadata(self):
        return self._parameters.metadata()

    # -- payload: gimbal, region of interest, camera (driver.payload) ------------------------------
    def point_gimbal(self, pitch_deg: float, yaw_deg: float | None = None) -> Future:
        return self._payload.point(pitch_deg, yaw_deg)

    def gimbal_rate(self, pitch_deg_s: float, yaw_deg_s: float = 0.0) -> Future:
        return self._payload.rate(pitch_deg_s, yaw_deg_s)

    def look_at(self, lat: float, lon: float, alt: float = 0.0) -> Future:
        return self._payload.look_at(lat, lon, alt)

    def stop_looking(self) -> Future:
        return self._payload.stop_looking()

    def take_photo(self) -> Future:
        return self._payload.take_photo()

    def record_video(self, on: bool) -> Future:
        return self._payload.record_video(on)

    # -- signing (driver.vehicle.signing_control) --------------------------------------------------
    def use_signing_key(self, key: bytes | None, allow_unsigned: bool | None = None) -> CommandResult:
        """Sign with ``key`` from now on, or stop (None), without telling the vehicle; ``allow_unsigned`` lets
        the vehicle's unsigned frames in (a vehicle without the key yet)."""
        return self._signing_control.use_key(key, allow_unsigned)

    @property
    def signing_unavailable(self) -> str:
        return "a recording cannot be signed" if self._replay is not None else ""

    def allow_unsigned(self, on: bool) -> CommandResult:
        return self._signing_control.allow_unsigned(on)

    def setup_signing(self, key: bytes) -> Future:
        """Give the vehicle ``key`` with SETUP_SIGNING (in clear: a trusted link only) and sign with it."""
        return self._signing_control.setup(key)

    def remove_signing(self) -> Future:
        return self._signing_control.remove()

    # -- velocity, position and yaw ----------------------------------------------------------------
    def set_velocity(self, forward: float, right: float, up: float, yaw_rate: float) -> bool:
        sp = SetpointStreamer.clamp(forward, right, up, yaw_rate, self._limits)
        if sp is None:
            log.warning("velocity refused: not finite (%r, %r, %r, %r)", forward, right, up, yaw_rate)
            return False
        if self.state().takeoff.active:
            return False
        with self._lock:
            if self._setpoints.demand(sp, self.clock()):
                self._store.set(setpoint=sp)
                self._store.publish()
                self._wake.set()
        return True

    def go_to(self, north: float, east: float, altitude: float) -> Future:
        if not frames.finite(north, east, altitude):
            return self._finish("go to", CommandStatus.REJECTED, "coordinates are not finite numbers")
        name = f"go to N{north:.1f} E{east:.1f} alt {altitude:.1f}"
        cfg = self.config
        problem = (go_to_problem(north, east, altitude, cfg.max_altitude, cfg.max_distance)
                   or self.state().fence.destination_problem(north, east, altitude))
        if problem:
            return self._finish(name, CommandStatus.REJECTED, problem)
        busy = self._busy(name)
        if busy:
            return busy
        s = self.state()
        if s.mode != "GUIDED" or not s.flying:
            return self._finish(name, CommandStatus.REJECTED, f"needs GUIDED and flying (mode {s.mode or '?'})")
        if s.home is None:
            return self._finish(name, CommandStatus.REJECTED, "the vehicle has not sent its home position yet")
        with self._lock:                              # a velocity stream would override the target
            self._setpoints.silence()
            self._store.set(setpoint=self._setpoints.setpoint)
        # latitude/longitude from home, altitude above home: never the EKF origin's frame
        lat, lon = frames.offset_latlon(s.home.lat, s.home.lon, north, east)
        system, component = self._target_ids()
        self._post(mavlink.MAVLink_set_position_target_global_int_message(
            0, system, component, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            MASK_POSITION, int(round(lat * 1e7)), int(round(lon * 1e7)), float(altitude), 0, 0, 0, 0, 0, 0, 0, 0))
        return self._finish(name, CommandStatus.ACCEPTED, "target sent")

    def set_yaw(self, degrees: float, relative: bool = False, rate_deg_s: float = 30.0) -> Future:
        if not frames.finite(degrees, rate_deg_s):
            return self._finish("yaw", CommandStatus.REJECTED, "angle is not a finite number")
        busy = self._busy("yaw")
        if busy:
            return busy
        if self.state().mode == "GUIDED" and self._setpoints.setpoint.is_zero:
            with self._lock:                          # zeros carry a yaw rate of 0, which would cancel the turn
                self._setpoints.silence()
            # ArduCopter ignores yaw after takeoff until a first movement command
            self._post(self._ticker.setpoint_message(Setpoint()))
        direction = (1 if degrees >= 0 else -1) if relative else 0
        angle = abs(degrees) if relative else degrees % 360.0
        return self._command_long(mavlink.MAV_CMD_CONDITION_YAW,
                                  (angle, abs(rate_deg_s), direction, 1 if relative else 0),
                                  f"yaw {'by' if relative else 'to'} {degrees:g}°")

    # -- takeoff sequence (stepped by the ticker) --------------------------------------------------
    def takeoff(self, altitude: float | None = None) -> Future:
        alt = self.config.takeoff_altitude if altitude is None else altitude
        problem = takeoff_altitude_problem(alt, self.config.max_altitude)
        if problem:
            return self._finish("takeoff", CommandStatus.REJECTED, problem)
        if self._replay is not None:
            return self._finish("takeoff", CommandStatus.REJECTED, "replaying a recording: no vehicle to command")
        with self._lock:                              # check and start as one step: never two sequences
            if self._sequence.current is not None:
                return self._finish("takeoff", CommandStatus.REJECTED, "a takeoff is already running")
            if self.state().flying:
                return self._finish("takeoff", CommandStatus.REJECTED, "already flying")
            seq = TakeoffSequence(self, alt, self.config, self.clock())
            self._sequence.start(seq)
        self._wake.set()
        return seq.future

    def _run_sequence(self, seq: TakeoffSequence, name: str) -> Future:
        """Step ``seq`` (a takeoff-like sequence: driver.mission's MissionStart) in the takeoff's place: only
        Land and Stop meanwhile, and Land aborts it."""
        with self._lock:
            if not self._sequence.start(seq):
                return self._finish(name, CommandStatus.REJECTED, "a takeoff or mission start is already running")
        self._wake.set()
        return seq.future

    # -- missions, fences, rally points (driver.vehicle.missions does the work) --------------------
    def upload_plan(self, plan: Plan) -> Future:
        return self._missions.upload(plan)

    def download_plan(self, kind: PlanKind) -> Future:
        return self._missions.download(kind)

    def clear_plan(self, kind: PlanKind) -> Future:
        return self._missions.clear(kind)

    def cancel_transfer(self, kind: PlanKind) -> None:
        self._missions.cancel(kind)

    def start_mission(self) -> Future:
        return self._busy("mission start") or self._missions.start()

    def pause_mission(self) -> Future:
        return self._busy("mission pause") or self._missions.pause()

    def resume_mission(self) -> Future:
        return self._busy("mission resume") or self._missions.resume()

    def set_mission_item(self, seq: int) -> Future:
        return self._busy(f"mission item {seq}") or self._missions.go_to_item(seq)

    def _abort_takeoff(self, why: str) -> None:
        """End a takeoff or mission start in progress (driver.vehicle.sequence), cancelling what it asked."""
        with self._lock:
            self._sequence.abort(why)

