"""The MAVLinkServer core: one ArduCopter vehicle over one MAVLink link.

Two threads do all the work, so no caller ever waits on the network:

* the *reader* opens the link (reopening TCP/serial links that fail), parses
  every byte with pymavlink's codec, and folds messages into the vehicle state;
* the *ticker* sends the GCS heartbeat, supervises the link, streams the
  velocity setpoint (20 Hz, zero after the deadman time), retries unanswered
  commands and republishes link health.

Readers get an immutable :class:`~driver.state.VehicleState` from :meth:`Vehicle.state`.
Commands return :class:`concurrent.futures.Future` objects resolving to a
:class:`~driver.state.CommandResult` carrying the vehicle's own reason on refusal.
"""
from __future__ import annotations

import collections
import logging
import math
import threading
import time
from concurrent.futures import Future
from dataclasses import dataclass, field

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from . import frames
from .api import CEILING, Drone, Limits
from .link import LinkError, Transport, TlogWriter, open_transport, MavutilTransport
from .state import (
    Attitude, Battery, CommandResult, CommandStatus, Environment, GlobalPosition, Gps, LandedState, LinkHealth,
    LinkStatus, LocalPosition, Message, Readiness, SequencePhase, SequenceProgress, Setpoint, Severity, Velocity,
    VehicleState,
)

log = logging.getLogger(__name__)

#: ArduCopter custom_mode numbers by name, from pymavlink's own table.
COPTER_MODES: dict[str, int] = {name: number for number, name in mavutil.mode_mapping_acm.items()}
COPTER_MODE_NAMES: dict[int, str] = dict(mavutil.mode_mapping_acm)

MASK_VELOCITY_YAW_RATE = 1479      # use vx, vy, vz and yaw rate (arducopter.md)
MASK_POSITION = 3576               # use x, y, z only
ARM_FORCE_MAGIC = 21196
_PREARM_BIT = mavlink.MAV_SYS_STATUS_PREARM_CHECK
_EKF_NEEDED = (mavlink.EKF_ATTITUDE | mavlink.EKF_VELOCITY_HORIZ | mavlink.EKF_POS_HORIZ_ABS
               | mavlink.EKF_PRED_POS_HORIZ_ABS)
_MAX_MESSAGES = 200
PUBLISH_INTERVAL = 0.01            # s: state is republished at most at 100 Hz while telemetry streams
_MAX_RESULTS = 100
MIN_TAKEOFF_ALTITUDE = 0.5         # m above home: lower is no takeoff
MAX_ALTITUDE = 120.0               # m above home: no takeoff or go-to target above it (EU open category)


def takeoff_altitude_problem(altitude: float, ceiling: float = MAX_ALTITUDE) -> str | None:
    """Why ``altitude`` cannot be a takeoff target, or None: one rule for the driver, its CLI and console."""
    if frames.finite(altitude) and MIN_TAKEOFF_ALTITUDE <= altitude <= ceiling:
        return None
    return f"altitude must be {MIN_TAKEOFF_ALTITUDE:g} to {ceiling:g} m"


@dataclass(frozen=True)
class VehicleConfig:
    connection: str = "udpin:0.0.0.0:14550"   # any mavutil string, or a .tlog file to replay
    baud: int = 57600
    source_system: int = 255                  # ArduPilot ignores manual control from other ids
    source_component: int = 190               # MAV_COMP_ID_MISSIONPLANNER
    target_system: int = 0                    # 0: the first vehicle heard
    target_component: int = 1
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
    setpoint_rate: float = 20.0               # Hz while the setpoint is not zero
    command_timeout: float = 3.0              # s per attempt (QGC re-sends 3 s apart)
    command_attempts: int = 3
    ready_timeout: float = 60.0               # s the takeoff waits for readiness before trying anyway
    climb_timeout: float = 45.0               # s for the climb to reach 95 % of the target
    mavlink_version: int | None = None        # None: start on 1, follow the vehicle to 2
    battery_cells: int = 4                    # 3DR Solo: 4S
    replay_speed: float = 1.0
    heartbeat_interval: float = 1.0


class _Pending:
    """A COMMAND_LONG waiting for its COMMAND_ACK."""
    __slots__ = ("name", "command", "params", "future", "attempts", "next_send", "message_index",
                 "refused", "refuse_at", "expect_mode", "fallback_sent")

    def __init__(self, name, command, params, future, message_index, expect_mode=None):
        self.name, self.command, self.params, self.future = name, command, params, future
        self.attempts = 0
        self.next_send = 0.0
        self.message_index = message_index
        self.refused: str | None = None
        self.refuse_at = 0.0
        self.expect_mode = expect_mode
        self.fallback_sent = False


class _TakeoffRun:
    """One takeoff sequence: its own abort flag and the commands it issued (cancelled on abort)."""

    def __init__(self, altitude: float):
        self.altitude = altitude
        self.abort = threading.Event()
        self.commands: set[int] = set()
        self.thread: threading.Thread | None = None

    @property
    def alive(self) -> bool:
        return self.thread is not None and self.thread.is_alive()


class ReplayControl:
    """Play/pause/speed of a .tlog being replayed, for the viewer's replay bar."""

    def __init__(self, transport):
        self._t = transport

    def pause(self) -> None:
        self._t.pause()

    def resume(self) -> None:
        self._t.resume()

    @property
    def paused(self) -> bool:
        return self._t.paused

    @property
    def speed(self) -> float:
        return self._t.speed

    @speed.setter
    def speed(self, value: float) -> None:
        self._t.speed = value

    @property
    def position(self) -> float:
        return self._t.position

    @property
    def duration(self) -> float:
        return self._t.duration

    @property
    def finished(self) -> bool:
        return self._t.finished


class _ParamEcho:
    """Waits for the PARAM_VALUE that confirms a PARAM_SET."""

    def __init__(self):
        self._cond = threading.Condition()
        self._values: dict[str, float] = {}

    def update(self, name: str, value: float) -> None:
        with self._cond:
            self._values[name] = value
            self._cond.notify_all()

    def expect(self, name: str) -> None:
        with self._cond:
            self._values.pop(name, None)

    def wait_for(self, name: str, value: float, timeout: float) -> bool:
        deadline = time.monotonic() + timeout
        with self._cond:
            while True:
                v = self._values.get(name)
                if v is not None and abs(v - value) <= 1e-6 * max(1.0, abs(value)):
                    return True
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return False
                self._cond.wait(remaining)


class Vehicle(Drone):
    """An ArduCopter reached over MAVLink; the embedded driver behind the viewer and the Ice server."""

    def __init__(self, config: VehicleConfig | None = None):
        self.config = cfg = config or VehicleConfig()
        self._transport: Transport = open_transport(cfg.connection, cfg.baud, cfg.source_system,
                                                    cfg.source_component, cfg.replay_speed)
        self._replay = ReplayControl(self._transport) if self._transport.is_replay else None
        self._codec_in = self._new_parser()
        self._codec_out = mavlink.MAVLink(None, srcSystem=cfg.source_system, srcComponent=cfg.source_component)
        self._tx_lock = threading.Lock()
        self._v2 = cfg.mavlink_version == 2
        self._tlog = TlogWriter(cfg.tlog_path, cfg.tlog_append) if cfg.tlog_path and not self._replay else None
        self._outputs: list[MavutilTransport] = []

        # state, guarded by _lock; published as one immutable snapshot
        self._lock = threading.RLock()
        self._changed = threading.Condition(self._lock)
        self._fields: dict = {}
        self._messages: collections.deque[Message] = collections.deque(maxlen=_MAX_MESSAGES)
        self._results: collections.deque[CommandResult] = collections.deque(maxlen=_MAX_RESULTS)
        self._message_index = 0
        self._result_index = 0
        self._state = VehicleState(link=LinkHealth(address=self._transport.description))
        self._target = cfg.target_system
        self._home: GlobalPosition | None = None
        self._prearm_reported = False
        self._last_seq: dict[int, int] = {}         # component -> last sequence number (target system)
        self._rx_count = 0
        self._rx_lost = 0
        self._bad_crc = 0
        self._window: collections.deque[tuple[float, int, int]] = collections.deque(maxlen=6)
        self._last_heartbeat: float | None = None     # transport clock
        self._last_attitude = 0.0
        self._link_status = LinkStatus.WAITING
        self._lost_count = 0
        self._lost_at = 0.0
        self._streams_requested_at: float | None = None
        self._latest: dict = {}                       # newest telemetry message of each type in this read

        # commands and setpoint, guarded by _lock
        self._pending: dict[int, _Pending] = {}
        self._setpoint = Setpoint()
        self._setpoint_time = 0.0
        self._setpoint_sent = 0.0
        self._setpoint_dirty = False
        self._zero_repeats = 0
        self._takeoff_run: _TakeoffRun | None = None
        self._open_error = ""
        self._param_echo = _ParamEcho()

        self._reopen = False                          # set by the ticker: reopen a reconnectable link
        self._published_at = 0.0
        self._limits = cfg.limits.within(CEILING)
        self._outbox: collections.deque = collections.deque()   # messages posted by callers, sent by the ticker
        self._wake = threading.Event()
        self._closing = threading.Event()
        self._threads: list[threading.Thread] = []
        self._started = False

    # ------------------------------------------------------------------------------------------
    # lifecycle
    # ------------------------------------------------------------------------------------------
    @property
    def description(self) -> str:
        return self._transport.description

    @property
    def limits(self) -> Limits:
        return self._limits

    def set_limits(self, limits: Limits) -> Limits:
        self._limits = limits.within(CEILING)         # one reference swap: safe from any thread
        return self._limits

    @property
    def replay(self) -> ReplayControl | None:
        return self._replay

    def start(self) -> "Vehicle":
        """Open the link in the background and begin supervising it. Returns at once."""
        if self._started:
            return self
        self._started = True
        if self._tlog:
            self._add_message(Severity.INFO, f"Recording the flight log to {self._tlog.path}")
        for target, name in ((self._run_reader, "mavlink-reader"), (self._run_ticker, "mavlink-ticker")):
            t = threading.Thread(target=target, name=name, daemon=True)
            t.start()
            self._threads.append(t)
        for out in self.config.outputs:
            t = threading.Thread(target=self._run_output, args=(out,), name=f"mavlink-out {out}", daemon=True)
            t.start()
            self._threads.append(t)
        return self

    def close(self) -> None:
        if self._closing.is_set():
            return
        run = self._takeoff_run
        if run is not None:
            run.abort.set()
        if self._started and not self._setpoint.is_zero:
            self._send_setpoint(Setpoint())          # leave the vehicle hovering, not drifting
        self._closing.set()
        self._wake.set()
        self._transport.close()
        for out in self._outputs:
            out.close()
        for t in self._threads:
            t.join(timeout=2.0)
        with self._lock:
            for p in list(self._pending.values()):
                self._resolve(p, CommandStatus.ABORTED, "driver closed")
            self._set(link=self._link_health(LinkStatus.CLOSED))
            self._publish()
        if self._tlog:
            self._tlog.close()

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.close()

    # ------------------------------------------------------------------------------------------
    # state
    # ------------------------------------------------------------------------------------------
    def state(self) -> VehicleState:
        return self._state

    def wait_for(self, predicate, timeout: float) -> VehicleState | None:
        """Block until ``predicate(state)`` holds; for tests and the console, never the UI thread."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while True:
                s = self._state
                if predicate(s):
                    return s
                remaining = deadline - time.monotonic()
                if remaining <= 0 or self._closing.is_set():
                    return None
                self._changed.wait(min(remaining, 0.2))

    def _set(self, **changes) -> None:
        self._fields.update(changes)

    def _publish(self) -> None:
        """Swap in a new snapshot (caller holds _lock)."""
        self._published_at = time.monotonic()
        self._fields["time"] = time.time()
        self._state = VehicleState(**{**self._state.__dict__, **self._fields})
        self._fields = {}
        self._changed.notify_all()

    def _add_message(self, severity: Severity, text: str, source: str = "driver") -> Message:
        with self._lock:
            self._message_index += 1
            m = Message(self._message_index, self._transport.wall_time(), Severity(severity), text, source)
            self._messages.append(m)
            self._set(messages=tuple(self._messages))
            if source == "driver":
                self._publish()
        log.log(logging.WARNING if severity <= Severity.WARNING else logging.INFO, "%s: %s", source, text)
        return m

    # ------------------------------------------------------------------------------------------
    # sending
    # ------------------------------------------------------------------------------------------
    def _send(self, msg) -> None:
        if self._transport.is_replay:
            return
        with self._tx_lock:
            buf = msg.pack(self._codec_out, force_mavlink1=not self._v2)
            self._codec_out.seq = (self._codec_out.seq + 1) % 256
            self._write(buf)

    def _post(self, msg) -> None:
        """Send from the ticker thread: callers (the UI among them) never touch the link themselves."""
        self._outbox.append(msg)
        self._wake.set()

    def _write(self, buf: bytes) -> None:
        """Whole frames only, one writer at a time (caller holds _tx_lock)."""
        if self._transport.write(buf) and self._tlog:       # the log holds what really went out
            self._tlog.write(buf)

    @property
    def _tsys(self) -> int:
        return self._target or 1

    def _send_heartbeat(self) -> None:
        self._send(mavlink.MAVLink_heartbeat_message(
            mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, mavlink.MAV_STATE_ACTIVE, 3))

    def _request_streams(self) -> None:
        cfg = self.config
        rate = max(1, int(cfg.stream_rate))
        fast = max(rate, int(cfg.attitude_rate))
        for stream, hz in ((mavlink.MAV_DATA_STREAM_EXTENDED_STATUS, rate),
                           (mavlink.MAV_DATA_STREAM_POSITION, rate),
                           (mavlink.MAV_DATA_STREAM_EXTRA1, fast),
                           (mavlink.MAV_DATA_STREAM_EXTRA2, fast),
                           (mavlink.MAV_DATA_STREAM_EXTRA3, max(1, rate // 2)),
                           (mavlink.MAV_DATA_STREAM_RAW_SENSORS, max(1, rate // 2))):
            self._send(mavlink.MAVLink_request_data_stream_message(self._tsys, cfg.target_component, stream, hz, 1))
        for msg_id, hz in ((mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE, rate), (mavlink.MAVLINK_MSG_ID_HOME_POSITION, 0.5)):
            self._send(mavlink.MAVLink_command_long_message(
                self._tsys, cfg.target_component, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                msg_id, 1e6 / hz, 0, 0, 0, 0, 0))
        self._send(mavlink.MAVLink_command_long_message(
            self._tsys, cfg.target_component, mavlink.MAV_CMD_REQUEST_MESSAGE, 0,
            mavlink.MAVLINK_MSG_ID_HOME_POSITION, 0, 0, 0, 0, 0, 0))
        self._streams_requested_at = time.monotonic()

    # ------------------------------------------------------------------------------------------
    # reader thread
    # ------------------------------------------------------------------------------------------
    @staticmethod
    def _new_parser():
        codec = mavlink.MAVLink(None)
        codec.robust_parsing = True
        return codec

    def _run_reader(self) -> None:
        backoff = 0.2
        opened = False
        while not self._closing.is_set():
            if not opened:
                try:
                    self._transport.open()
                    opened, backoff = True, 0.2
                    self._open_error = ""
                    self._reopen = False
                    self._v2 = self.config.mavlink_version == 2
                    log.info("link open: %s", self._transport.description)
                    self._send_heartbeat()            # speak first: udpout and serial peers learn of us
                except LinkError as exc:
                    if str(exc) != self._open_error:          # say it once, and again when the reason changes
                        self._open_error = str(exc)
                        self._add_message(Severity.WARNING, f"{exc}; retrying")
                    log.info("%s; retrying in %.1f s", exc, backoff)
                    self._closing.wait(backoff)
                    backoff = min(backoff * 2, 3.0)
                    continue
            if self._reopen:                               # lost on a link that can be reopened (half-open TCP)
                exc = LinkError("no heartbeat; reopening the link")
            else:
                try:
                    data = self._transport.read(0.05)
                    exc = None
                except LinkError as error:
                    exc = error
            if exc is not None:
                if self._closing.is_set():
                    break
                self._add_message(Severity.WARNING, f"Link error: {exc}; reconnecting")
                self._transport.close()
                opened = False
                self._codec_in = self._new_parser()
                with self._lock:
                    self._last_seq.clear()
                self._closing.wait(backoff)
                continue
            if data:
                self.ingest(data)
            elif self._latest or self._fields:
                with self._lock:                              # traffic paused: publish what is held back
                    self._fold_and_publish()

    def ingest(self, data: bytes) -> int:
        """Parse raw bytes as if read from the link and fold them into the state; returns messages parsed."""
        try:
            msgs = self._parse(data)
        except Exception as exc:                      # robust parsing should catch all; never let it escape
            log.debug("parser reset after %s", exc)
            self._codec_in = self._new_parser()
            msgs = None
        if self._outputs:
            for out in self._outputs:
                out.write(data)
        if not msgs:                                  # part of a frame (TCP, serial): nothing to fold yet
            return 0
        n = 0
        with self._lock:
            for msg in msgs:
                try:
                    n += self._handle(msg)
                except Exception:                     # a malformed field must not stop the reader
                    log.exception("error handling %s", msg.get_type())
            if n and time.monotonic() - self._published_at >= PUBLISH_INTERVAL:
                self._fold_and_publish()
        return n

    def _parse(self, data: bytes) -> list | None:
        """pymavlink's parse_buffer(), minus its last call that finds nothing when the read held exactly one
        frame (a UDP datagram from the Solo): about 1 µs of a frame's 12 µs."""
        codec = self._codec_in
        msg = codec.parse_char(data)
        if msg is None:
            return None
        return [msg] if codec.buf_len() == 0 else [msg, *(codec.parse_buffer(b"") or ())]

    def _fold_and_publish(self) -> None:
        """Fold the newest telemetry of each kind into the state and publish it (caller holds _lock)."""
        latest, self._latest = self._latest, {}
        for mtype, msg in latest.items():             # telemetry: only the newest of each kind matters
            try:
                _TELEMETRY[mtype](self, msg)
            except Exception:
                log.exception("error handling %s", mtype)
        self._publish()

    def _handle(self, msg) -> int:
        """One parsed frame (reader thread, _lock held); the hot path of telemetry ingest."""
        mtype = msg.get_type()
        if mtype == "BAD_DATA":
            if "CRC" in getattr(msg, "reason", ""):
                self._bad_crc += 1
            return 0
        header = msg.get_header()
        if self._tlog:
            self._tlog.write(bytes(msg.get_msgbuf()))
        system = header.srcSystem
        if system != self._target:
            if self._target or not (mtype == "HEARTBEAT" and msg.autopilot != mavlink.MAV_AUTOPILOT_INVALID
                                    and msg.type != mavlink.MAV_TYPE_GCS):
                return 0                              # another system (a second GCS), or no vehicle yet
            self._target = system
            self._set(system_id=system)
            log.info("vehicle found: system %d", system)
        # sequence numbers: packet loss per component
        component, seq = header.srcComponent, header.seq
        last = self._last_seq.get(component)
        if last is not None:
            gap = (seq - last - 1) & 0xFF
            if gap < 128:                             # larger jumps are a restart, not loss
                self._rx_lost += gap
        self._last_seq[component] = seq
        self._rx_count += 1
        if not self._v2 and msg.get_msgbuf()[0] == 0xFD and self.config.mavlink_version is None:
            self._v2 = True
            log.info("vehicle speaks MAVLink 2: following it")
        if mtype in _TELEMETRY:
            self._latest[mtype] = msg                 # folded once per read, see ingest()
        else:
            handler = _EVENTS.get(mtype)
            if handler is not None:
                handler(self, msg)
        return 1

    # -- message handlers (reader thread, _lock held) -------------------------------------------
    def _on_heartbeat(self, m) -> None:
        if m.autopilot == mavlink.MAV_AUTOPILOT_INVALID or (
                self.config.target_component and m.get_srcComponent() != self.config.target_component):
            return                                    # a gimbal, camera or companion computer, not the autopilot
        now = self._transport.clock()
        first = self._last_heartbeat is None
        self._last_heartbeat = now
        mode = COPTER_MODE_NAMES.get(m.custom_mode, f"MODE({m.custom_mode})")
        armed = bool(m.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED)
        self._set(mode=mode, armed=armed, vehicle_type=m.type)
        for p in list(self._pending.values()):
            if p.expect_mode is not None and p.expect_mode == m.custom_mode:
                self._resolve(p, CommandStatus.ACCEPTED)
        if self._link_status is not LinkStatus.OK:
            if not self._transport.is_replay:
                self._request_streams()               # before anyone sees the link up
            recovered = self._link_status is LinkStatus.LOST
            self._link_status = LinkStatus.OK
            self._set(link=self._link_health())
            if recovered:
                self._publish()
                self._add_message(Severity.NOTICE, "Link recovered")
            elif first:
                self._add_message(Severity.INFO, f"Vehicle {self._target} connected on {self.description}")

    def _on_sys_status(self, m) -> None:
        if m.onboard_control_sensors_present & _PREARM_BIT:
            self._prearm_reported = True
        r = self._state.readiness if "readiness" not in self._fields else self._fields["readiness"]
        prearm = bool(m.onboard_control_sensors_health & _PREARM_BIT) if self._prearm_reported else r.ekf_ok and r.gps_ok
        self._set(readiness=Readiness(prearm, r.ekf_ok, r.gps_ok))
        voltage = None if m.voltage_battery in (0, 0xFFFF) else m.voltage_battery / 1000.0
        current = None if m.current_battery < 0 else m.current_battery / 100.0
        self._set_battery(voltage, current, None if m.battery_remaining < 0 else float(m.battery_remaining))

    def _on_battery_status(self, m) -> None:
        cells = [v for v in m.voltages if v not in (0xFFFF, 0)]
        voltage = sum(cells) / 1000.0 if cells else None
        b = self._fields.get("battery", self._state.battery)
        if voltage is None or (len(cells) == 1 and b.voltage is not None):
            voltage = b.voltage                         # one total voltage: SYS_STATUS has it already
        current = None if m.current_battery < 0 else m.current_battery / 100.0
        self._set_battery(voltage, current if current is not None else b.current,
                          None if m.battery_remaining < 0 else float(m.battery_remaining))

    def _set_battery(self, voltage, current, remaining) -> None:
        cells = self.config.battery_cells
        estimated = False
        if remaining is None and voltage is not None:
            remaining, estimated = round(frames.battery_percent_from_cell(voltage / cells), 1), True
        low = (remaining is not None and remaining < 20.0) or (voltage is not None and voltage / cells < 3.7)
        self._set(battery=Battery(voltage, current, remaining, estimated, cells, low))

    def _on_attitude(self, m) -> None:
        self._last_attitude = time.monotonic()
        self._set(attitude=Attitude(m.roll, m.pitch, m.yaw, m.rollspeed, m.pitchspeed, m.yawspeed))

    def _on_global_position(self, m) -> None:
        lat, lon, alt = m.lat * 1e-7, m.lon * 1e-7, m.alt * 1e-3
        rel = m.relative_alt * 1e-3
        fields = dict(position=GlobalPosition(lat, lon, alt), altitude=rel,
                      velocity=Velocity(m.vx / 100.0, m.vy / 100.0, m.vz / 100.0))
        if m.hdg != 0xFFFF:
            fields["heading_deg"] = m.hdg / 100.0
        if self._home is not None:
            north, east = frames.offset_ned(self._home.lat, self._home.lon, lat, lon)
            fields["local"] = LocalPosition(north, east, -rel)
        self._set(**fields)

    def _on_local_position(self, m) -> None:
        if self._home is None:                          # no home yet: the EKF origin is the best we have
            self._set(local=LocalPosition(m.x, m.y, m.z))

    def _on_home_position(self, m) -> None:
        self._home = GlobalPosition(m.latitude * 1e-7, m.longitude * 1e-7, m.altitude * 1e-3)
        self._set(home=self._home)

    def _on_vfr_hud(self, m) -> None:
        env = self._fields.get("environment", self._state.environment)
        self._set(airspeed=m.airspeed, heading_deg=float(m.heading % 360),
                  environment=_env(env, throttle=int(m.throttle)))

    def _on_gps_raw(self, m) -> None:
        r = self._fields.get("readiness", self._state.readiness)
        hdop = None if m.eph == 0xFFFF else m.eph / 100.0
        self._set(gps=Gps(m.fix_type, m.satellites_visible if m.satellites_visible != 255 else 0, hdop),
                  readiness=Readiness(r.prearm_ok, r.ekf_ok, m.fix_type >= 3))

    def _on_ekf_status(self, m) -> None:
        r = self._fields.get("readiness", self._state.readiness)
        ok = (m.flags & _EKF_NEEDED) == _EKF_NEEDED and not (m.flags & mavlink.EKF_UNINITIALIZED)
        self._set(readiness=Readiness(r.prearm_ok, ok, r.gps_ok))

    def _on_extended_sys_state(self, m) -> None:
        try:
            self._set(landed_state=LandedState(m.landed_state))
        except ValueError:
            pass

    def _on_statustext(self, m) -> None:
        text = m.text.rstrip("\x00").strip() if isinstance(m.text, str) else bytes(m.text).decode("ascii", "replace")
        if text:
            try:
                sev = Severity(m.severity)
            except ValueError:
                sev = Severity.INFO
            self._add_message(sev, text, "vehicle")

    def _on_scaled_pressure(self, m) -> None:
        env = self._fields.get("environment", self._state.environment)
        self._set(environment=_env(env, pressure_hpa=float(m.press_abs), temperature_c=m.temperature / 100.0))

    def _on_imu(self, m) -> None:
        env = self._fields.get("environment", self._state.environment)
        # ArduPilot sends RAW_IMU/SCALED_IMU accelerations in milli-g and magnetometer in milligauss
        self._set(environment=_env(env, mag=(int(m.xmag), int(m.ymag), int(m.zmag)),
                                   accel_g=(m.xacc / 1000.0, m.yacc / 1000.0, m.zacc / 1000.0)))

    def _on_wind(self, m) -> None:
        env = self._fields.get("environment", self._state.environment)
        self._set(environment=_env(env, wind_speed=float(m.speed), wind_direction_deg=float(m.direction) % 360))

    def _on_command_ack(self, m) -> None:
        p = self._pending.get(m.command)
        if p is None or getattr(m, "target_system", 0) not in (0, self.config.source_system):
            return                                    # not ours: another ground station's answer
        if m.result == mavlink.MAV_RESULT_ACCEPTED:
            self._resolve(p, CommandStatus.ACCEPTED)
        elif m.result == mavlink.MAV_RESULT_IN_PROGRESS:
            p.next_send = time.monotonic() + self.config.command_timeout * 3   # still working: stop re-sending
        elif p.expect_mode is not None and m.result == mavlink.MAV_RESULT_UNSUPPORTED and not p.fallback_sent:
            # old firmware (stock Solo) without MAV_CMD_DO_SET_MODE: SET_MODE, confirmed by the heartbeat
            p.fallback_sent = True
            self._send(mavlink.MAVLink_set_mode_message(
                self._tsys, mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, p.expect_mode))
        else:
            result = mavlink.enums["MAV_RESULT"].get(m.result)
            p.refused = result.name if result else f"result {m.result}"
            p.refuse_at = time.monotonic() + 0.3     # the STATUSTEXT explaining it may trail the ACK
            self._wake.set()

    # ------------------------------------------------------------------------------------------
    # ticker thread
    # ------------------------------------------------------------------------------------------
    def _run_ticker(self) -> None:
        next_heartbeat = next_health = 0.0
        while not self._closing.is_set():
            now = time.monotonic()
            try:
                if now >= next_heartbeat:
                    next_heartbeat = now + self.config.heartbeat_interval
                    self._send_heartbeat()
                while self._outbox:
                    self._send(self._outbox.popleft())
                with self._lock:
                    self._stream_setpoint(now)
                    self._service_commands(now)
                    if now >= next_health:
                        next_health = now + 0.1
                        self._supervise(now)
            except Exception:                         # heartbeat, setpoints and deadman must outlive any bug
                log.exception("ticker step failed")
            self._wake.wait(min(0.05, 1.0 / self.config.setpoint_rate))
            self._wake.clear()

    def _supervise(self, now: float) -> None:
        """Link health, loss, log failures and stream re-requests; republishes every 100 ms."""
        if self._tlog is not None and self._tlog.error:
            error, self._tlog = self._tlog.error, None
            self._add_message(Severity.WARNING, f"Flight log stopped: {error}")
        if (self._link_status is LinkStatus.LOST and self._transport.reconnectable and self._last_heartbeat
                is not None and self._transport.clock() - self._last_heartbeat > self.config.loss_timeout + 5.0
                and now - self._lost_at > 5.0):
            self._lost_at = now
            self._reopen = True                       # a half-open TCP link never errors: reopen it
        if not self._window or now - self._window[-1][0] >= 1.0:
            self._window.append((now, self._rx_count, self._rx_lost))
        status = self._link_status
        if self._last_heartbeat is not None and status is LinkStatus.OK:
            age = self._transport.clock() - self._last_heartbeat
            if age > self.config.loss_timeout:
                self._link_status = LinkStatus.LOST
                self._lost_at = now
                self._lost_count += 1
                self._set(link=self._link_health())
                self._publish()
                self._add_message(Severity.CRITICAL, f"Link lost: no heartbeat for {age:.1f} s")
                for p in self._pending.values():      # give commands their full retries after recovery
                    p.attempts = min(p.attempts, self.config.command_attempts - 1)
        elif (status is LinkStatus.OK and not self._transport.is_replay and self._streams_requested_at
              and now - self._last_attitude > 3.0 and now - self._streams_requested_at > 5.0):
            self._request_streams()                   # the vehicle rebooted or forgot our rates
        self._set(link=self._link_health())
        self._publish()

    def _link_health(self, status: LinkStatus | None = None) -> LinkHealth:
        age = None if self._last_heartbeat is None else max(0.0, self._transport.clock() - self._last_heartbeat)
        rate = loss = 0.0
        if len(self._window) >= 2:
            (t0, c0, l0), (t1, c1, l1) = self._window[0], self._window[-1]
            if t1 > t0:
                rate = (c1 - c0) / (t1 - t0)
            if (c1 - c0) + (l1 - l0) > 0:
                loss = 100.0 * (l1 - l0) / ((c1 - c0) + (l1 - l0))
        return LinkHealth(status or self._link_status, self._transport.description, age, rate, loss,
                          self._rx_count, self._rx_lost, self._bad_crc, 2 if self._v2 else 1, self._lost_count)

    # ------------------------------------------------------------------------------------------
    # commands
    # ------------------------------------------------------------------------------------------
    def command_long(self, command: int, params=(), name: str | None = None) -> Future:
        """Send any MAV_CMD as COMMAND_LONG with ACK handling and retries."""
        name = name or _command_name(command)
        return self._busy(name) or self._command_long(command, params, name)

    def _command_long(self, command: int, params=(), name: str | None = None, *,
                      expect_mode: int | None = None) -> Future:
        name = name or _command_name(command)
        run = self._takeoff_run
        if run is not None and threading.current_thread() is run.thread:
            run.commands.add(command)                 # cancelled if the pilot aborts the takeoff
        params = [float(p) for p in (list(params) + [0.0] * 7)[:7]]
        if not frames.finite(*params):
            return self._finish(name, CommandStatus.REJECTED, "parameter is not a finite number")
        if self._replay is not None:
            return self._finish(name, CommandStatus.REJECTED, "replaying a recording: no vehicle to command")
        future: Future = Future()
        with self._lock:
            old = self._pending.pop(command, None)
            if old is not None:
                self._resolve(old, CommandStatus.ABORTED, f"superseded by {name}", remove=False)
            self._pending[command] = _Pending(name, command, params, future, self._message_index, expect_mode)
        self._wake.set()
        return future

    def _service_commands(self, now: float) -> None:
        cfg = self.config
        for p in list(self._pending.values()):
            if p.refused is not None:
                if now >= p.refuse_at:
                    texts = [m.text for m in self._messages if m.index > p.message_index and m.source == "vehicle"]
                    reason = "; ".join(texts[-3:]) + f" ({p.refused})" if texts else p.refused
                    self._resolve(p, CommandStatus.REFUSED, reason)
                continue
            if now < p.next_send:
                continue
            if p.attempts >= cfg.command_attempts:
                if p.expect_mode is not None and not p.fallback_sent:
                    p.fallback_sent = True             # no ACK at all: try SET_MODE before giving up
                    self._send(mavlink.MAVLink_set_mode_message(
                        self._tsys, mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, p.expect_mode))
                    p.next_send = now + cfg.command_timeout
                    continue
                self._resolve(p, CommandStatus.TIMED_OUT,
                              f"no answer from the vehicle after {p.attempts} attempts")
                continue
            self._send(mavlink.MAVLink_command_long_message(
                self._tsys, cfg.target_component, p.command, p.attempts, *p.params))
            p.attempts += 1
            p.next_send = now + cfg.command_timeout

    def _resolve(self, p: _Pending, status: CommandStatus, reason: str = "", remove: bool = True) -> None:
        if remove and self._pending.get(p.command) is p:
            del self._pending[p.command]
        if not p.future.done():
            result = self._record(p.name, status, reason, p.attempts)
            self._settle(p.future, result)

    def _settle(self, future: Future, result: CommandResult) -> None:
        """Resolve on a thread of its own, outside _lock and off the link threads: a done-callback that
        takes its time delays neither the link, nor callers, nor other commands' results."""
        def settle():
            if not future.done():
                future.set_result(result)
        threading.Thread(target=settle, name="command-result", daemon=True).start()

    def _record(self, command: str, status: CommandStatus, reason: str = "", attempts: int = 0) -> CommandResult:
        with self._lock:
            self._result_index += 1
            result = CommandResult(command, status, reason, attempts, self._result_index)
            self._results.append(result)
            self._set(results=tuple(self._results))
            self._publish()
        (log.info if result.ok else log.warning)("command %s", result)
        return result

    def _finish(self, command: str, status: CommandStatus, reason: str = "") -> Future:
        f: Future = Future()
        f.set_result(self._record(command, status, reason))
        return f

    def _busy(self, command: str) -> Future | None:
        if self._state.takeoff.active:
            return self._finish(command, CommandStatus.REJECTED, "takeoff in progress: only Land and Stop")
        return None

    def set_mode(self, name: str) -> Future:
        return self._busy(f"mode {name}") or self._set_mode(name)

    def _set_mode(self, name: str) -> Future:
        number = COPTER_MODES.get(name.upper())
        if number is None:
            return self._finish(f"mode {name}", CommandStatus.REJECTED,
                                f"unknown mode; known: {', '.join(sorted(COPTER_MODES))}")
        if self._state.mode == name.upper() and self._state.connected:
            return self._finish(f"mode {name.upper()}", CommandStatus.ACCEPTED, "already in that mode")
        return self._command_long(mavlink.MAV_CMD_DO_SET_MODE,
                                  (mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, number), f"mode {name.upper()}",
                                  expect_mode=number)

    def arm(self, force: bool = False) -> Future:
        return self._busy("arm") or self._arm(force)

    def _arm(self, force: bool = False) -> Future:
        return self._command_long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (1, ARM_FORCE_MAGIC if force else 0),
                                 "arm (forced)" if force else "arm")

    def disarm(self, force: bool = False) -> Future:
        return self._busy("disarm") or self._command_long(
            mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (0, ARM_FORCE_MAGIC if force else 0),
            "disarm (forced)" if force else "disarm")

    def land(self) -> Future:
        self._abort_takeoff("landing")
        return self._set_mode("LAND")

    def return_to_launch(self) -> Future:
        return self._busy("RTL") or self._set_mode("RTL")

    def stop(self) -> Future:
        """Hold position: zero velocity in GUIDED (which also cancels a go-to), BRAKE otherwise."""
        taking_off = self._state.takeoff.active
        self._abort_takeoff("stop")
        s = self._state
        if not s.flying and not s.armed:
            return self._finish("stop", CommandStatus.ACCEPTED,
                                "takeoff aborted" if taking_off else "on the ground: nothing to stop")
        if s.mode == "GUIDED":
            with self._lock:
                self._setpoint = Setpoint()
                self._set(setpoint=self._setpoint)
                self._zero_repeats = 3
                self._setpoint_dirty = True
            self._wake.set()
            return self._finish("stop", CommandStatus.ACCEPTED, "holding position (zero velocity in GUIDED)")
        return self._set_mode("BRAKE")

    def reboot(self) -> Future:
        return self._busy("reboot") or self._command_long(mavlink.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, (1,), "reboot")

    def calibrate_level(self) -> Future:
        """Level (accelerometer trim) calibration; only sensible disarmed on the ground."""
        s = self._state
        if s.armed or s.flying:
            return self._finish("level calibration", CommandStatus.REJECTED, "only when disarmed on the ground")
        return self._busy("level calibration") or self._command_long(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, (0, 0, 0, 0, 2, 0, 0), "level calibration")

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
            self._tsys, mavlink.MAV_MODE_FLAG_DECODE_POSITION_SAFETY, 1 if on else 0))
        return self._finish(f"safety {'on' if on else 'off'}", CommandStatus.ACCEPTED, "sent (not acknowledged)")

    def set_parameter(self, name: str, value: float, timeout: float = 3.0) -> Future:
        """PARAM_SET, confirmed by the PARAM_VALUE echo."""
        if not frames.finite(value) or not name or len(name) > 16:
            return self._finish(f"param {name}", CommandStatus.REJECTED, "bad name or value")
        busy = self._busy(f"param {name}")
        if busy:
            return busy
        future: Future = Future()

        def watch():
            for attempt in range(self.config.command_attempts):
                self._param_echo.expect(name)
                self._send(mavlink.MAVLink_param_set_message(
                    self._tsys, self.config.target_component, name.encode(), float(value),
                    mavlink.MAV_PARAM_TYPE_REAL32))
                if self._param_echo.wait_for(name, value, timeout):
                    future.set_result(self._record(f"param {name}={value:g}", CommandStatus.ACCEPTED, "", attempt + 1))
                    return
                if self._closing.is_set():
                    break
            future.set_result(self._record(f"param {name}={value:g}", CommandStatus.TIMED_OUT,
                                           "no PARAM_VALUE echo", self.config.command_attempts))
        threading.Thread(target=watch, daemon=True, name="param-set").start()
        return future

    # ------------------------------------------------------------------------------------------
    # velocity, position and yaw
    # ------------------------------------------------------------------------------------------
    def set_velocity(self, forward: float, right: float, up: float, yaw_rate: float) -> bool:
        if not frames.finite(forward, right, up, yaw_rate):
            log.warning("velocity refused: not finite (%r, %r, %r, %r)", forward, right, up, yaw_rate)
            return False
        if self._state.takeoff.active:
            return False
        lim = self._limits
        sp = Setpoint(frames.clamp(float(forward), lim.horizontal), frames.clamp(float(right), lim.horizontal),
                      frames.clamp(float(up), lim.vertical), frames.clamp(float(yaw_rate), lim.yaw_rate))
        with self._lock:
            self._setpoint_time = time.monotonic()
            if sp != self._setpoint:
                if sp.is_zero:
                    self._zero_repeats = 3
                self._setpoint = sp
                self._setpoint_dirty = True
                self._set(setpoint=sp)
                self._publish()
                self._wake.set()
        return True

    def _stream_setpoint(self, now: float) -> None:
        sp = self._setpoint
        if not sp.is_zero and now - self._setpoint_time > self.config.deadman:
            self._setpoint = sp = Setpoint()
            self._zero_repeats = 3
            self._setpoint_dirty = True
            self._set(setpoint=sp)
            self._publish()
            log.warning("velocity commands stopped for %.1f s: hovering", self.config.deadman)
        if sp.is_zero and not self._zero_repeats:
            self._setpoint_dirty = False
            return
        if not self._setpoint_dirty and now - self._setpoint_sent < 1.0 / self.config.setpoint_rate - 0.002:
            return
        if self._state.mode == "GUIDED":
            self._send_setpoint(sp)
        self._setpoint_sent = now
        self._setpoint_dirty = False
        if sp.is_zero:
            self._zero_repeats -= 1

    def _send_setpoint(self, sp: Setpoint) -> None:
        self._send(self._setpoint_message(sp))

    def _setpoint_message(self, sp: Setpoint):
        return mavlink.MAVLink_set_position_target_local_ned_message(
            0, self._tsys, self.config.target_component, mavlink.MAV_FRAME_BODY_OFFSET_NED,
            MASK_VELOCITY_YAW_RATE, 0, 0, 0, sp.forward, sp.right, -sp.up, 0, 0, 0, 0, sp.yaw_rate)

    def go_to(self, north: float, east: float, altitude: float) -> Future:
        if not frames.finite(north, east, altitude):
            return self._finish("go to", CommandStatus.REJECTED, "coordinates are not finite numbers")
        name = f"go to N{north:.1f} E{east:.1f} alt {altitude:.1f}"
        cfg = self.config
        if not 1.0 <= altitude <= cfg.max_altitude or math.hypot(north, east) > cfg.max_distance:
            return self._finish(name, CommandStatus.REJECTED, f"outside the limits: 1 to {cfg.max_altitude:g} m "
                                f"above home, at most {cfg.max_distance:g} m from it")
        busy = self._busy(name)
        if busy:
            return busy
        s = self._state
        if s.mode != "GUIDED" or not s.flying:
            return self._finish(name, CommandStatus.REJECTED, f"needs GUIDED and flying (mode {s.mode or '?'})")
        with self._lock:                              # a velocity stream would override the target
            self._setpoint, self._zero_repeats, self._setpoint_dirty = Setpoint(), 0, False
            self._set(setpoint=self._setpoint)
        if self._home is not None:
            lat, lon = frames.offset_latlon(self._home.lat, self._home.lon, north, east)
            self._post(mavlink.MAVLink_set_position_target_global_int_message(
                0, self._tsys, self.config.target_component, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                MASK_POSITION, int(round(lat * 1e7)), int(round(lon * 1e7)), float(altitude), 0, 0, 0, 0, 0, 0, 0, 0))
        else:
            self._post(mavlink.MAVLink_set_position_target_local_ned_message(
                0, self._tsys, self.config.target_component, mavlink.MAV_FRAME_LOCAL_NED,
                MASK_POSITION, north, east, -altitude, 0, 0, 0, 0, 0, 0, 0, 0))
        return self._finish(name, CommandStatus.ACCEPTED, "target sent")

    def set_yaw(self, degrees: float, relative: bool = False, rate_deg_s: float = 30.0) -> Future:
        if not frames.finite(degrees, rate_deg_s):
            return self._finish("yaw", CommandStatus.REJECTED, "angle is not a finite number")
        busy = self._busy("yaw")
        if busy:
            return busy
        if self._state.mode == "GUIDED" and self._setpoint.is_zero:
            # ArduCopter ignores yaw after takeoff until a first movement command
            self._post(self._setpoint_message(Setpoint()))
        direction = (1 if degrees >= 0 else -1) if relative else 0
        angle = abs(degrees) if relative else degrees % 360.0
        return self._command_long(mavlink.MAV_CMD_CONDITION_YAW,
                                 (angle, abs(rate_deg_s), direction, 1 if relative else 0),
                                 f"yaw {'by' if relative else 'to'} {degrees:g}°")

    # ------------------------------------------------------------------------------------------
    # takeoff sequence
    # ------------------------------------------------------------------------------------------
    def takeoff(self, altitude: float | None = None) -> Future:
        alt = self.config.takeoff_altitude if altitude is None else altitude
        problem = takeoff_altitude_problem(alt, self.config.max_altitude)
        if problem:
            return self._finish("takeoff", CommandStatus.REJECTED, problem)
        if self._replay is not None:
            return self._finish("takeoff", CommandStatus.REJECTED, "replaying a recording: no vehicle to command")
        with self._lock:                              # check and start as one step: never two sequences
            run = self._takeoff_run
            if run is not None and run.alive:
                why = "the aborted takeoff is still winding down" if run.abort.is_set() else "a takeoff is already running"
                return self._finish("takeoff", CommandStatus.REJECTED, why)
            if self._state.flying:
                return self._finish("takeoff", CommandStatus.REJECTED, "already flying")
            future: Future = Future()
            run = self._takeoff_run = _TakeoffRun(alt)
            run.thread = threading.Thread(target=self._takeoff_sequence, args=(run, future), name="takeoff",
                                          daemon=True)
            self._progress(run, SequencePhase.WAITING_READY)
            run.thread.start()
        return future

    def _abort_takeoff(self, why: str) -> None:
        """Stop the sequence and cancel what it asked the vehicle, so no retry launches it afterwards."""
        with self._lock:
            run = self._takeoff_run
            if run is None or run.abort.is_set() or not run.alive:
                return
            run.abort.set()
            for command in run.commands:
                p = self._pending.get(command)
                if p is not None:
                    self._resolve(p, CommandStatus.ABORTED, f"takeoff aborted: {why}")
                    if command == mavlink.MAV_CMD_NAV_TAKEOFF and p.attempts:
                        # a command on its way cannot be called back: say so rather than promise the ground
                        self._add_message(Severity.WARNING, "Takeoff aborted after NAV_TAKEOFF went out: if the "
                                          "vehicle got it, it lifts off (Land brings it down)")
            self._progress(run, SequencePhase.ABORTED, f"aborted: {why}")

    def _progress(self, run: _TakeoffRun, phase: SequencePhase, detail: str = "") -> None:
        with self._lock:
            if run is not self._takeoff_run or self._state.takeoff.phase is SequencePhase.ABORTED and run.abort.is_set():
                return                                # an abort is final for its run
            if run.abort.is_set() and phase is not SequencePhase.ABORTED:
                return
            self._set(takeoff=SequenceProgress(phase, detail, run.altitude))
            self._publish()
        log.info("takeoff: %s %s", phase.value, detail)

    def _takeoff_sequence(self, run: _TakeoffRun, future: Future) -> None:
        cfg = self.config
        alt = run.altitude
        aborted = run.abort.is_set

        def end(status: CommandStatus, reason: str, phase: SequencePhase):
            if aborted() and status is not CommandStatus.ABORTED:
                status, reason, phase = CommandStatus.ABORTED, f"aborted by the pilot ({reason})", SequencePhase.ABORTED
            self._progress(run, phase, reason)
            future.set_result(self._record("takeoff", status, reason))

        def wait(predicate, timeout):
            deadline = time.monotonic() + timeout
            while time.monotonic() < deadline and not aborted() and not self._closing.is_set():
                if self.wait_for(predicate, min(0.2, deadline - time.monotonic())) is not None:
                    return True
            return False

        def step(fut: Future) -> CommandResult | None:
            while not fut.done():
                if aborted():
                    return None
                try:
                    fut.result(timeout=0.1)
                except Exception:
                    pass
            return fut.result()

        try:
            if not wait(lambda s: s.connected, cfg.ready_timeout):
                return end(CommandStatus.ABORTED if aborted() else CommandStatus.TIMED_OUT,
                           "aborted" if aborted() else "no vehicle on the link", SequencePhase.FAILED)
            if not self._state.readiness.ready_to_arm:
                self._progress(run, SequencePhase.WAITING_READY, "waiting for GPS, EKF and pre-arm checks")
                wait(lambda s: s.readiness.ready_to_arm, cfg.ready_timeout)   # then let the vehicle decide
            if aborted():
                return end(CommandStatus.ABORTED, "aborted by the pilot", SequencePhase.ABORTED)
            self._progress(run, SequencePhase.SETTING_GUIDED)
            r = step(self._set_mode("GUIDED"))
            if r is None:
                return end(CommandStatus.ABORTED, "aborted by the pilot", SequencePhase.ABORTED)
            if not r.ok:
                return end(CommandStatus.REFUSED if r.status is CommandStatus.REFUSED else r.status,
                           f"GUIDED: {r.reason}", SequencePhase.FAILED)
            if not self._state.armed:
                self._progress(run, SequencePhase.ARMING)
                r = step(self._arm())
                if r is None:
                    return end(CommandStatus.ABORTED, "aborted by the pilot", SequencePhase.ABORTED)
                if not r.ok:
                    return end(r.status, f"arming: {r.reason}", SequencePhase.FAILED)
                if not wait(lambda s: s.armed, cfg.command_timeout * 2):
                    return end(CommandStatus.ABORTED if aborted() else CommandStatus.REFUSED,
                               "the vehicle did not report armed", SequencePhase.FAILED)
            self._progress(run, SequencePhase.TAKING_OFF, f"to {alt:.1f} m")
            r = step(self._command_long(mavlink.MAV_CMD_NAV_TAKEOFF, (0, 0, 0, 0, 0, 0, alt),
                                       f"NAV_TAKEOFF {alt:.1f} m"))
            if r is None:
                return end(CommandStatus.ABORTED, "aborted by the pilot", SequencePhase.ABORTED)
            if not r.ok:
                return end(r.status, f"takeoff command: {r.reason}", SequencePhase.FAILED)
            self._progress(run, SequencePhase.CLIMBING, f"to {alt:.1f} m")
            if not wait(lambda s: s.altitude >= 0.95 * alt or not s.armed, cfg.climb_timeout):
                if aborted():
                    return end(CommandStatus.ABORTED, "aborted by the pilot", SequencePhase.ABORTED)
                return end(CommandStatus.TIMED_OUT, f"did not reach {alt:.1f} m (at {self._state.altitude:.1f} m)",
                           SequencePhase.FAILED)
            if not self._state.armed:
                return end(CommandStatus.REFUSED, "the vehicle disarmed during the climb", SequencePhase.FAILED)
            end(CommandStatus.ACCEPTED, f"reached {self._state.altitude:.1f} m", SequencePhase.DONE)
        except Exception as exc:                      # never leave the future unresolved
            log.exception("takeoff sequence failed")
            if not future.done():
                end(CommandStatus.REJECTED, f"internal error: {exc}", SequencePhase.FAILED)

    # ------------------------------------------------------------------------------------------
    # forwarding to other ground stations
    # ------------------------------------------------------------------------------------------
    def _run_output(self, connection: str) -> None:
        """Forward vehicle traffic to another ground station and its commands back to the vehicle."""
        target = "udpout:" + connection[4:] if connection.startswith("udp:") else connection
        out = MavutilTransport(target, self.config.baud)
        try:
            out.open()
        except LinkError as exc:
            self._add_message(Severity.WARNING, f"Forwarding to {connection} failed: {exc}")
            return
        self._outputs.append(out)
        parser = self._new_parser()                   # whole frames only: the log and the vehicle get no garbage
        while not self._closing.is_set():
            try:
                data = out.read(0.2)
            except LinkError:
                self._closing.wait(0.5)
                continue
            try:
                frames_in = parser.parse_buffer(data) or () if data else ()
            except Exception:
                parser, frames_in = self._new_parser(), ()
            for msg in frames_in:
                if msg.get_type() != "BAD_DATA":
                    with self._tx_lock:
                        self._write(bytes(msg.get_msgbuf()))


def _env(env: Environment, **changes) -> Environment:
    return Environment(**{**env.__dict__, **changes})


def _command_name(command: int) -> str:
    entry = mavlink.enums["MAV_CMD"].get(command)
    return entry.name.replace("MAV_CMD_", "") if entry else f"command {command}"


def _on_param_value(self: Vehicle, m) -> None:
    name = m.param_id.rstrip("\x00") if isinstance(m.param_id, str) else bytes(m.param_id).decode(errors="replace")
    self._param_echo.update(name, m.param_value)



#: Pure telemetry: state follows the newest message of each type, so a read folds only the last one.
_TELEMETRY = {
    "SYS_STATUS": Vehicle._on_sys_status,
    "BATTERY_STATUS": Vehicle._on_battery_status,
    "ATTITUDE": Vehicle._on_attitude,
    "GLOBAL_POSITION_INT": Vehicle._on_global_position,
    "LOCAL_POSITION_NED": Vehicle._on_local_position,
    "HOME_POSITION": Vehicle._on_home_position,
    "VFR_HUD": Vehicle._on_vfr_hud,
    "GPS_RAW_INT": Vehicle._on_gps_raw,
    "EKF_STATUS_REPORT": Vehicle._on_ekf_status,
    "EXTENDED_SYS_STATE": Vehicle._on_extended_sys_state,
    "SCALED_PRESSURE": Vehicle._on_scaled_pressure,
    "RAW_IMU": Vehicle._on_imu,
    "SCALED_IMU": Vehicle._on_imu,
    "SCALED_IMU2": Vehicle._on_imu,
    "WIND": Vehicle._on_wind,
}

#: Events: every one counts (mode/arming changes, the pilot's messages, command answers).
_EVENTS = {
    "HEARTBEAT": Vehicle._on_heartbeat,
    "STATUSTEXT": Vehicle._on_statustext,
    "COMMAND_ACK": Vehicle._on_command_ack,
    "PARAM_VALUE": _on_param_value,
}
