"""The MAVLinkServer core: one ArduCopter vehicle over one MAVLink link.

:class:`Vehicle` is the façade of the embedded driver behind the viewer and the Ice server: it holds the
pilot's calls (the :class:`~driver.vehicle.api.Drone` interface) and hands each job to the part that does it:

* ``reader`` (the reader thread: open, parse, dispatch), ``ticker`` (the ticker thread and the one way out),
  ``telemetry`` (folds telemetry, pure), ``supervision`` (the link), ``store`` (the immutable snapshots);
* ``safety`` (the flight rules every message passes), ``commands`` (retries, each reply to its own request),
  ``sequences`` (takeoff, mission start, land, RTL, Stop: state machines), ``setpoints`` (velocity, the deadman);
* ``missions``, ``parameters``, ``signing_control``, :mod:`driver.payload`, :mod:`driver.setup`,
  :mod:`driver.logs`: plans, parameters, signing, the payload, setup and the DataFlash logs.

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
from ..core.roundtrip import RoundTrip
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
from .ports import SequencePilot, vehicle_ports
from .reader import Reader
from .rules import (
    COPTER_MODES, MAX_ALTITUDE, MIN_TAKEOFF_ALTITUDE, go_to_problem, takeoff_altitude_problem,
)
from .safety import ARM_FORCE_MAGIC, FlightRules
from .sequences.landing import land_sequence, return_sequence
from .sequences.mission_start import MissionStartSequence
from .sequences.slot import SequenceSlot
from .sequences.stop import StopSequence
from .setpoints import SetpointStreamer
from .signing_control import SigningControl
from .state import (
    Battery, BatteryThresholds, CommandResult, CommandStatus, LinkHealth, LinkStatus, Setpoint, Severity, VehicleState,
)
from .store import StateStore
from .supervision import LinkSupervisor
from .sequences.takeoff import TakeoffSequence
from .telemetry import COPTER_MODE_NAMES
from .ticker import MASK_POSITION, Ticker

log = logging.getLogger("driver.vehicle")       # the façade and its parts log as one

__all__ = ["Vehicle", "VehicleConfig", "ReplayControl", "COPTER_MODES", "COPTER_MODE_NAMES",
           "MIN_TAKEOFF_ALTITUDE", "MAX_ALTITUDE", "takeoff_altitude_problem", "MASK_POSITION"]


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
        self._rules = FlightRules(lambda now, judged: not all(  # the flight rules every message passes (safety)
            self._commands.settled_by_state(c, now, pending=c != judged)
            for c in (mavlink.MAV_CMD_COMPONENT_ARM_DISARM, mavlink.MAV_CMD_DO_MOTOR_TEST)))
        self._roundtrip = RoundTrip(initial=cfg.command_timeout / 3)    # the link's round trip, one estimate for all
        self._commands = CommandSender(self._store, cfg, self._notifier, self._target_ids, self._rules,
                                       self._roundtrip)
        self._link = LinkSupervisor(cfg, self._transport, self._commands.capabilities, self._target_ids, clock)
        self._params = ParameterManager(self._store, self._notifier, self._target_ids, 2 * cfg.loss_timeout,
                                        cfg.param_retry)
        self._params.use_ftp = cfg.param_ftp
        self._setpoints = SetpointStreamer(cfg.deadman, cfg.setpoint_rate)
        self._payload = Payload(self)         # gimbal, region of interest, camera (driver.payload)
        self._sequence = SequenceSlot(self._store, self._commands, self._notifier, clock)   # the flight's sequences
        self._pilot = SequencePilot(                   # what a sequence is handed (driver.vehicle.sequences.machine)
            state=self.state, airborne=lambda: self._rules.may_be_airborne(self.state()), mode=self._set_mode,
            arm=lambda early=False: self._arming(True, early=early),
            disarm=lambda: self._command_long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (0, 0), "disarm"),
            long=self._command_long, retry_interval=lambda: min(cfg.command_timeout, self._roundtrip.timeout()),
            hold=self._hold, quiet=lambda command: self._commands.settled_by_state(command, self.clock()))
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
                                   self._command_long, self._set_mode, self._finish,
                                   lambda command: self._commands.settled_by_state(command, clock()), self._notifier)
        self._parameters = Parameters(self)            # parameter table, cache, checked writes, metadata
        self._signing_control = SigningControl(self)   # keys and SETUP_SIGNING
        self._forwarder = Forwarder(cfg.outputs, cfg.baud, self._ticker.forward_to_vehicle,
                                    lambda text: self._store.add_message(Severity.WARNING, text), self._closing)
        self._missions = MissionControl(self)          # transfers, mission state, AUTO (driver.vehicle.missions)
        self.setup, self.logs = VehicleSetup(self), LogControl(self.ports, lambda: self._params.ftp_capable)
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
            self._sequence.end("driver closed")
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

    def step(self, frames: bool = False) -> list:
        """One pass of the ticker at ``clock()`` on a vehicle not started: what it would send (unsent), for tests
        and a lockstep harness (driver.sim.lockstep); ``frames``: packed as they would go out, signing included."""
        assert not self._started, "a started vehicle's ticker thread steps it"
        out = self._ticker.step(self.clock())
        return [self._ticker.pack(m) for m in out] if frames else out

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
    def ingest(self, data: bytes, publish: bool = False) -> int:
        """Parse raw bytes as if read from the link and fold them into the state; returns messages parsed."""
        return self._reader.ingest(data, publish)

    def _post(self, msg) -> None:
        """Send from the ticker thread: callers (the UI among them) never touch the link themselves."""
        self._ticker.post(msg)

    # -- commands ----------------------------------------------------------------------------------
    # Every command goes through one path (_command_long, _set_mode: the command sender, which checks the flight
    # rules before each attempt) and every message out through the ticker's screen (driver.vehicle.safety).
    def command_long(self, command: int, params=(), name: str | None = None, *, guard=None) -> Future:
        """Send any MAV_CMD as COMMAND_LONG with ACK handling and retries, within the flight rules."""
        name = name or command_name(command)
        return self._busy(name) or self._command_long(command, params, name, guard=guard)

    def _command_long(self, command: int, params=(), name: str | None = None, *, guard=None,
                      retry: float | None = None, early: bool = False, shows_mode: str | None = None) -> Future:
        name = name or command_name(command)
        params = [float(p) for p in (list(params) + [0.0] * 7)[:7]]
        if not frames.finite(*params):
            return self._finish(name, CommandStatus.REJECTED, "parameter is not a finite number")
        if self._replay is not None:
            return self._finish(name, CommandStatus.REJECTED, "replaying a recording: no vehicle to command")
        with self._lock:
            problem = self._rules.command_problem(command, params, self.state(), self.clock())
            if problem:
                return self._finish(name, CommandStatus.REJECTED, problem)
            future = self._commands.submit(name, command, params, self.clock(), guard=guard, tag=self._sequence.tag,
                                           retry=retry, early=early, shows_mode=COPTER_MODES.get(shows_mode or ""))
        self._wake.set()
        return future

    def _finish(self, command: str, status: CommandStatus, reason: str = "") -> Future:
        f: Future = Future()
        f.set_result(self._store.record(command, status, reason))
        return f

    def _busy(self, command: str) -> Future | None:
        """While a takeoff or mission start runs, only Land, Stop and RTL (each of which ends it)."""
        seq = self._sequence.exclusive
        if seq is not None:
            return self._finish(command, CommandStatus.REJECTED, f"{seq.name} in progress: only Land, Stop and RTL")
        return None

    def set_mode(self, name: str) -> Future:
        self.shots.end(f"mode {name}")                # driver.shots: the pilot's mode always wins
        busy = self._busy(f"mode {name}")
        if busy:
            return busy
        with self._lock:
            self._sequence.end(f"mode {name.upper()} asked")
        return self._set_mode(name)

    def _set_mode(self, name: str, *, early: bool = False) -> Future:
        """A mode change through the flight rules, confirmed by the heartbeat."""
        number = COPTER_MODES.get(name.upper())
        if number is None:
            return self._finish(f"mode {name}", CommandStatus.REJECTED,
                                f"unknown mode; known: {', '.join(sorted(COPTER_MODES))}")
        if self._replay is not None:
            return self._finish(f"mode {name.upper()}", CommandStatus.REJECTED,
                                "replaying a recording: no vehicle to command")
        with self._lock:                              # sent even when the state shows it: the vehicle may have left
            s = self.state()                          # it since (a failsafe, its mission's end), the state be older
            problem = self._rules.mode_problem(number, s)
            if problem:
                return self._finish(f"mode {name.upper()}", CommandStatus.REJECTED, problem)
            future = self._commands.submit_mode(f"mode {name.upper()}", number, self.clock(),
                                                tag=self._sequence.tag, early=early)
        self._wake.set()
        return future

    def arm(self, force: bool = False) -> Future:
        return self._busy("arm") or self._arming(True, force)

    def _arming(self, armed: bool, force: bool = False, early: bool = False) -> Future:
        """Sent even when the state shows it done: the vehicle disarms by itself (DISARM_DELAY, a motor test's
        end), and the state may be older than that; ArduCopter accepts an arm of an armed vehicle."""
        name = ("arm" if armed else "disarm") + (" (forced)" if force else "")
        return self._command_long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (1 if armed else 0,
                                  ARM_FORCE_MAGIC if force else 0), name, early=early)

    def disarm(self, force: bool = False, emergency: bool = False) -> Future:
        """A disarm on the ground; in the air (or maybe in the air) only the emergency motor stop, which the pilot
        confirmed (``force`` and ``emergency``): the flight rules refuse any other."""
        if emergency and force:                       # the pilot confirmed it: the motors stop, even in the air
            with self._lock:
                self._sequence.end("emergency motor stop")
                self._rules.allow_emergency_stop(self.clock())
            return self._command_long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (0, ARM_FORCE_MAGIC),
                                      "emergency motor stop")
        return self._busy("disarm") or self._arming(False, force)

    def land(self) -> Future:
        """LAND, always taken: it ends whatever runs (a takeoff, a mission start, a Stop)."""
        self.shots.end("Land")                        # driver.shots: Land always wins
        return self._replace_sequence(land_sequence(self._pilot, self.clock()), "landing")

    def return_to_launch(self) -> Future:
        """RTL, always taken: it ends whatever runs."""
        self.shots.end("RTL")                         # driver.shots: RTL always wins
        return self._replace_sequence(return_sequence(self._pilot, self.clock()), "returning home")

    def cancel_takeoff(self) -> Future:
        """The pilot's Cancel: :meth:`stop`, which before liftoff undoes what the takeoff changed."""
        return self.stop()

    def stop(self) -> Future:
        """Hold position, or end a takeoff that has not lifted anything as if it never ran: the vehicle always ends
        holding (GUIDED at zero velocity, BRAKE if GUIDED is refused) or on the ground disarmed, never in a mode
        that needs a throttle stick (driver.vehicle.sequences.stop)."""
        self.shots.end("Stop")                        # driver.shots: Stop always wins
        if self._replay is not None:
            return self._finish("stop", CommandStatus.REJECTED, "replaying a recording: no vehicle to command")
        with self._lock:
            now = self.clock()
            ended = self._sequence.end("stop")
            interrupted = ended if ended is not None and ended.exclusive else None
            s = self.state()
            airborne = (self._rules.may_be_airborne(s) or (interrupted is not None and interrupted.lifting_sent))
            armed = s.armed or not self._commands.settled_by_state(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, now)
            self._setpoints.stop(now)                 # zeros at once, whatever the mode turns out to be
            self._store.set(setpoint=self._setpoints.setpoint)
            seq = StopSequence(self._pilot, now, interrupted, airborne, armed)
            self._sequence.start(seq)
        self._wake.set()
        return seq.future

    def _hold(self) -> None:
        """Zero velocity from now (lock held): streamed for ArduCopter's GUID_TIMEOUT, then the sticks fly."""
        self._setpoints.stop(self.clock())
        self._store.set(setpoint=self._setpoints.setpoint)
        self._store.publish()

    def _replace_sequence(self, seq, why: str) -> Future:
        """Start ``seq`` in the slot, ending whatever runs there (Land and RTL win over any sequence)."""
        if self._replay is not None:
            return self._finish(seq.name, CommandStatus.REJECTED, "replaying a recording: no vehicle to command")
        with self._lock:
            self._sequence.end(why)
            self._sequence.start(seq)
        self._wake.set()
        return seq.future

    def reboot(self) -> Future:
        return self._busy("reboot") or self._command_long(mavlink.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, (1,), "reboot")

    def calibrate_level(self) -> Future:
        """Level (accelerometer trim) calibration; only sensible disarmed on the ground."""
        return self._busy("level calibration") or self._command_long(
            mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, (0, 0, 0, 0, 2, 0, 0), "level calibration")

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
        if self.state().flying:
            return self._finish("takeoff", CommandStatus.REJECTED, "already flying")
        return self._run_sequence(TakeoffSequence(self._pilot, alt, self.config, self.clock()))

    def _run_sequence(self, seq) -> Future:
        """Start a takeoff or mission start (exclusive: only Land, Stop and RTL meanwhile, and each ends it)."""
        with self._lock:                              # check and start as one step: never two
            if not self._sequence.start(seq):
                running = self._sequence.exclusive
                return self._finish(seq.name, CommandStatus.REJECTED, f"a {running.name} is already running")
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
        problem = ("replaying a recording: no vehicle to command" if self._replay is not None
                   else self._missions.start_problem(self.state()))
        if problem:
            return self._finish("mission start", CommandStatus.REJECTED, problem)
        return self._run_sequence(MissionStartSequence(self._pilot, self.config, self.clock()))

    def pause_mission(self) -> Future:
        return self._busy("mission pause") or self._missions.pause()

    def resume_mission(self) -> Future:
        return self._busy("mission resume") or self._missions.resume()

    def set_mission_item(self, seq: int) -> Future:
        return self._busy(f"mission item {seq}") or self._missions.go_to_item(seq)

    def _end_sequence(self, why: str) -> None:
        """End what runs in the sequence slot (driver.vehicle.sequences), cancelling what it asked."""
        with self._lock:
            self._sequence.end(why)

