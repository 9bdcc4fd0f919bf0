"""The MAVLinkServer core: one ArduCopter vehicle over one MAVLink link.

:class:`Vehicle` is the façade of the embedded driver behind the viewer and the Ice server: it holds the
pilot's calls (the :class:`~driver.vehicle.api.Drone` interface) and hands each job to the part that does it:

* ``reader`` (the reader thread: open, parse, dispatch to the parts through the ``inbox``), ``ticker`` (the
  ticker thread and the one way out; runs what each part serves), ``peer`` (who the vehicle is on the link),
  ``telemetry`` (folds telemetry, pure), ``supervision`` (the link), ``store`` (the immutable snapshots);
* ``safety`` (the flight rules every message passes), ``command_path`` (every command's one way: the rules, then
  ``commands``: retries, each reply to its own request), ``flight`` (velocity, go-to, yaw, and the ``sequences``:
  takeoff, mission start, land, RTL, Stop), ``setpoints`` (velocity, the deadman);
* ``missions``, ``parameters``, ``signing_control``, :mod:`driver.payload`, :mod:`driver.setup`,
  :mod:`driver.logs`: plans, parameters, signing, the payload, setup and the DataFlash logs.

Each part is handed the ports it uses (:mod:`driver.core.ports`: the state, the outbox, the command path, the
settler, the clock, the firmware profile, the link's round trip), never this vehicle; :meth:`Vehicle._wire`
registers what each hears and serves.

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

from ..core.firmware import FirmwareProfile
from ..core.roundtrip import RoundTrip
from ..link.forwarding import Forwarder
from ..link.signing import LinkSigning, SigningConfig
from ..link.connection import open_transport
from ..link.tlog import ReplayControl, TlogWriter
from ..mission.plan import Plan, PlanKind
from ..params.manager import ParameterManager
from ..params.setter import SET_RETRY
from ..payload.control import PAYLOAD_MESSAGES, Payload
from ..logs.control import LogControl
from ..setup.control import SETUP_MESSAGES, VehicleSetup
from ..shots.control import ShotControl
from .api import Drone, Limits
from .command_path import CommandPath
from .commands import CommandSender, Notifier, command_name
from .inbox import Inbox
from .inspector import MessageInspector
from .missions import MISSION_MESSAGES, MissionControl
from .parameters import Parameters
from .peer import Peer
from .flight import Flight
from .ports import vehicle_ports
from .reader import Reader
from .rules import COPTER_MODES, MAX_ALTITUDE, MIN_TAKEOFF_ALTITUDE, takeoff_altitude_problem
from .safety import ARM_FORCE_MAGIC, FlightRules
from .sequences.slot import SequenceSlot
from .setpoints import SetpointStreamer
from .signing_control import SigningControl
from .state import (
    Battery, BatteryThresholds, CommandResult, CommandStatus, LinkHealth, LinkStatus, Setpoint, Severity, VehicleState,
)
from .store import StateStore
from .supervision import LinkSupervisor
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
        replaying = self._replay is not None
        self._signing = LinkSigning(cfg.signing, self._transport.description)
        self._peer = Peer(cfg.target_system, cfg.target_component, cfg.mavlink_version)   # who we talk to, and how
        self._firmware = FirmwareProfile(lambda: self._peer.mavlink2)   # what its firmware does differently
        self._roundtrip = RoundTrip(initial=cfg.command_timeout / 3)    # the link's round trip, one estimate for all
        self._tlog = TlogWriter(cfg.tlog_path, cfg.tlog_append) if cfg.tlog_path and not self._replay else None
        battery = Battery(cells=cfg.battery_cells, cells_source="configured") if cfg.battery_cells else Battery()
        battery = replace(battery, thresholds=cfg.battery_thresholds)
        self._store = StateStore(VehicleState(link=LinkHealth(address=self._transport.description), battery=battery),
                                 self._transport.wall_time)
        self._lock = self._store.lock
        self._notifier = Notifier()
        self._rules = FlightRules(lambda now, judged: not all(  # the flight rules every message passes (safety)
            self._commands.settled_by_state(c, now, pending=c != judged)
            for c in (mavlink.MAV_CMD_COMPONENT_ARM_DISARM, mavlink.MAV_CMD_DO_MOTOR_TEST)))
        self._commands = CommandSender(self._store, cfg, self._notifier, self._peer.target, self._firmware,
                                       self._rules, self._roundtrip)
        self._link = LinkSupervisor(cfg, self._transport, self._firmware, self._peer.target, clock, self._roundtrip)
        self._params = ParameterManager(self._store, self._notifier, self._peer.target, self._firmware,
                                        self._roundtrip, 2 * cfg.loss_timeout, cfg.param_retry)
        self._params.use_ftp = cfg.param_ftp
        self._setpoints = SetpointStreamer(cfg.deadman, cfg.setpoint_rate)
        self._sequence = SequenceSlot(self._store, self._commands, self._notifier, clock)   # the flight's sequences
        self._wake = threading.Event()
        self._closing = threading.Event()
        self._threads: list[threading.Thread] = []
        self._started = False
        self._path = CommandPath(self._store, self._rules, self._commands, self._sequence, clock, self._wake,
                                 replaying)           # every command's one way (the flight rules, the sender)
        # the parts that do the work, each one job (see the module's docstring)
        self._ticker = Ticker(                         # the ticker thread and the one way out to the link
            config=cfg, clock=clock, transport=self._transport, signing=self._signing, store=self._store,
            link=self._link, rules=self._rules, peer=self._peer, firmware=self._firmware, sequence=self._sequence,
            setpoints=self._setpoints, tlog=self._tlog, closing=self._closing, wake=self._wake,
            reopen=lambda: self._reader.ask_reopen())
        #: the narrow services the parts are handed (driver.core.ports), instead of this vehicle
        self.ports = ports = vehicle_ports(
            clock=clock, store=self._store, ticker=self._ticker, wake=self._wake, peer=self._peer,
            commands=self._path, settler=self._notifier, firmware=self._firmware, roundtrip=self._roundtrip,
            replaying=replaying)
        self._payload = Payload(ports.state, ports.outbox, ports.commands, ports.settler, clock, self._firmware,
                                replaying)            # gimbal, region of interest, camera (driver.payload)
        self._parameters = Parameters(cfg, ports, self._params)   # parameter table, cache, checked writes, metadata
        self._signing_control = SigningControl(self._signing, self._peer, ports)   # keys and SETUP_SIGNING
        self._forwarder = Forwarder(cfg.outputs, cfg.baud, self._ticker.forward_to_vehicle,
                                    lambda text: self._store.add_message(Severity.WARNING, text), self._closing)
        self._missions = MissionControl(cfg, ports, self.set_mode)   # transfers, mission state, AUTO
        self.setup = VehicleSetup(ports.state, ports.outbox, ports.commands, ports.settler, clock, self._firmware)
        self._flight = Flight(cfg, ports, self._path, self._sequence, self._setpoints, self._rules,
                              self._ticker.setpoint_message, self._missions.start_problem)   # velocity, sequences
        self.logs = LogControl(ports)                  # the DataFlash logs (driver.logs)
        self.shots = ShotControl(ports, self._payload, self._setpoints, cfg, self._parameters.set)   # smart shots
        self.inspector = MessageInspector(clock)       # what the link carries: Drone.inspection()
        self._inbox = Inbox()                          # what the vehicle says, to the parts that asked
        self._reader = Reader(                         # the reader thread: parse, fold, dispatch
            config=cfg, clock=clock, transport=self._transport, signing=self._signing, store=self._store,
            link=self._link, peer=self._peer, commands=self._commands, firmware=self._firmware, inbox=self._inbox,
            tlog=self._tlog, forwarder=self._forwarder, inspector=self.inspector, closing=self._closing,
            wake=self._wake, greet=lambda: self._ticker.send(self._ticker.heartbeat_message()))
        self._wire()

    def _wire(self) -> None:
        """Each part hears its messages and does its periodic work, in this order (the reader's and the ticker's)."""
        inbox, serve = self._inbox, self._ticker.serve
        inbox.on(PAYLOAD_MESSAGES, self._payload.on_message, any_component=True)
        inbox.on("HEARTBEAT", self._missions.on_heartbeat)       # arming or disarming: the mission's story
        inbox.on("HEARTBEAT", self._signing_control.on_heartbeat)
        inbox.on_text(self._signing_control.on_text)
        inbox.on_text(self._missions.on_text)
        inbox.on_text(self.logs.on_text)                # 'Disarm for log download'
        inbox.on("PARAM_VALUE", self._parameters.on_param_value)
        inbox.on("PARAM_VALUE", self._missions.on_param_value)
        inbox.on(MISSION_MESSAGES, self._missions.on_message)
        inbox.on(SETUP_MESSAGES, self.setup.on_message)
        inbox.on(("LOG_ENTRY", "LOG_DATA"), self.logs.on_message)
        inbox.on("FILE_TRANSFER_PROTOCOL", self._parameters.on_ftp)
        inbox.on("FILE_TRANSFER_PROTOCOL", self.logs.on_ftp)
        link = self._link
        serve(self._commands.service)
        serve(lambda now, state: self._params.service(now, link.status, link.lost_count))
        for part in (self._payload, self._missions, self.setup, self.logs, self.shots, self._signing_control):
            serve(part.service)

    # -- lifecycle ---------------------------------------------------------------------------------
    @property
    def description(self) -> str:
        return self._transport.description

    @property
    def limits(self) -> Limits:
        return self._flight.limits

    def set_limits(self, limits: Limits) -> Limits:
        return self._flight.set_limits(limits)

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
            self._store.set(link=self._link.health(self._peer.version, LinkStatus.CLOSED))
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

    def _target_ids(self) -> tuple[int, int]:
        return self._peer.target()

    # -- the link, both ways (driver.vehicle.reader, driver.vehicle.ticker) ------------------------
    def ingest(self, data: bytes, publish: bool = False) -> int:
        """Parse raw bytes as if read from the link and fold them into the state; returns messages parsed."""
        return self._reader.ingest(data, publish)

    def _post(self, msg) -> None:
        """Send from the ticker thread: callers (the UI among them) never touch the link themselves."""
        self._ticker.post(msg)

    # -- commands ----------------------------------------------------------------------------------
    # Every command goes through one path (driver.vehicle.command_path: the flight rules, then the command sender)
    # and every message out through the ticker's screen (driver.vehicle.safety).
    def command_long(self, command: int, params=(), name: str | None = None, *, guard=None) -> Future:
        """Send any MAV_CMD as COMMAND_LONG with ACK handling and retries, within the flight rules."""
        name = name or command_name(command)
        return self._path.busy(name) or self._path.long(command, params, name, guard=guard)

    def set_mode(self, name: str) -> Future:
        self.shots.end(f"mode {name}")                # driver.shots: the pilot's mode always wins
        busy = self._path.busy(f"mode {name}")
        if busy:
            return busy
        with self._lock:
            self._sequence.end(f"mode {name.upper()} asked")
        return self._path.mode(name)

    def arm(self, force: bool = False) -> Future:
        return self._path.busy("arm") or self._path.arming(True, force)

    def disarm(self, force: bool = False, emergency: bool = False) -> Future:
        """A disarm on the ground; in the air (or maybe in the air) only the emergency motor stop, which the pilot
        confirmed (``force`` and ``emergency``): the flight rules refuse any other."""
        if emergency and force:                       # the pilot confirmed it: the motors stop, even in the air
            with self._lock:
                self._sequence.end("emergency motor stop")
                self._rules.allow_emergency_stop(self.clock())
            return self._path.long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (0, ARM_FORCE_MAGIC),
                                      "emergency motor stop")
        return self._path.busy("disarm") or self._path.arming(False, force)

    def land(self) -> Future:
        """LAND, always taken: it ends whatever runs (a takeoff, a mission start, a Stop, a smart shot)."""
        self.shots.end("Land")
        return self._flight.land()

    def return_to_launch(self) -> Future:
        """RTL, always taken: it ends whatever runs."""
        self.shots.end("RTL")
        return self._flight.return_to_launch()

    def cancel_takeoff(self) -> Future:
        """The pilot's Cancel: :meth:`stop`, which before liftoff undoes what the takeoff changed."""
        return self.stop()

    def stop(self) -> Future:
        """Hold position, or end a takeoff that has not lifted anything as if it never ran: the vehicle always ends
        holding (GUIDED at zero velocity, BRAKE if GUIDED is refused) or on the ground disarmed, never in a mode
        that needs a throttle stick (driver.vehicle.sequences.stop). It ends a smart shot too."""
        self.shots.end("Stop")
        return self._flight.stop()

    def reboot(self) -> Future:
        return self._path.busy("reboot") or self._path.long(mavlink.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, (1,), "reboot")

    def calibrate_level(self) -> Future:
        """Level (accelerometer trim) calibration; only sensible disarmed on the ground."""
        return self._path.busy("level calibration") or self._path.long(
            mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, (0, 0, 0, 0, 2, 0, 0), "level calibration")

    def parachute(self, action: str) -> Future:
        actions = {"disable": mavlink.PARACHUTE_DISABLE, "enable": mavlink.PARACHUTE_ENABLE,
                   "release": mavlink.PARACHUTE_RELEASE}
        if action not in actions:
            return self._path.answer(f"parachute {action}", CommandStatus.REJECTED, "use enable, disable or release")
        # never blocked by a takeoff: a parachute is the last resort
        return self._path.long(mavlink.MAV_CMD_DO_PARACHUTE, (actions[action],), f"parachute {action}")

    def set_safety(self, on: bool) -> Future:
        """Safety switch on (motors locked) or off, as MAVProxy's ``arm safetyon/safetyoff``."""
        self._post(mavlink.MAVLink_set_mode_message(
            self._target_ids()[0], mavlink.MAV_MODE_FLAG_DECODE_POSITION_SAFETY, 1 if on else 0))
        return self._path.answer(f"safety {'on' if on else 'off'}", CommandStatus.ACCEPTED, "sent (not acknowledged)")

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

    # -- velocity, position and yaw, takeoff (driver.vehicle.flight) -------------------------------
    def set_velocity(self, forward: float, right: float, up: float, yaw_rate: float) -> bool:
        return self._flight.set_velocity(forward, right, up, yaw_rate)

    def go_to(self, north: float, east: float, altitude: float) -> Future:
        return self._flight.go_to(north, east, altitude)

    def set_yaw(self, degrees: float, relative: bool = False, rate_deg_s: float = 30.0) -> Future:
        return self._flight.set_yaw(degrees, relative, rate_deg_s)

    def takeoff(self, altitude: float | None = None) -> Future:
        return self._flight.takeoff(altitude)

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
        return self._flight.start_mission()

    def pause_mission(self) -> Future:
        return self._path.busy("mission pause") or self._missions.pause()

    def resume_mission(self) -> Future:
        return self._path.busy("mission resume") or self._missions.resume()

    def set_mission_item(self, seq: int) -> Future:
        return self._path.busy(f"mission item {seq}") or self._missions.go_to_item(seq)


