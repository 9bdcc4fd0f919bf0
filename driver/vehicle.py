"""The MAVLinkServer core: one ArduCopter vehicle over one MAVLink link.

:class:`Vehicle` is the embedded driver behind the viewer and the Ice server, and it puts together parts
that each do one job:

* :mod:`driver.telemetry` folds telemetry into the state (pure, no I/O);
* :mod:`driver.supervision` keeps the link supervised and asks the vehicle for streams, home, parameters;
* :mod:`driver.commands` sends commands with retries and matches each reply to what it answers;
* :mod:`driver.setpoints` streams the velocity setpoint, with the deadman;
* :mod:`driver.takeoff` runs the takeoff sequence against the public :class:`~driver.api.Drone` interface;
* :mod:`driver.store` publishes immutable :class:`~driver.state.VehicleState` snapshots.

Two threads do all the link work, so no caller ever waits on the network: the *reader* opens the link
(reopening TCP/serial links that fail), parses every byte with pymavlink's codec and folds it into the
state; the *ticker* sends the heartbeat, steps the takeoff, streams setpoints, services commands and
supervises the link. Both decide under the state lock and write to the link only after releasing it, so
a slow serial write never stalls the reader or :meth:`Vehicle.set_velocity`. Command results settle on a
small fixed pool (:class:`~driver.commands.Notifier`).
"""
from __future__ import annotations

import collections
import logging
import math
import threading
import time
from concurrent.futures import Future
from dataclasses import dataclass, field, replace

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from . import frames
from .api import CEILING, Drone, Limits
from .commands import CommandSender, Notifier, chain, command_name
from .forwarding import Forwarder
from .payload.control import PAYLOAD_MESSAGES, Payload
from .logs.control import LogControl
from .link import LinkError, ReplayControl, TlogWriter, Transport, open_transport
from .params.cache import ParameterCache
from .params.manager import ParameterManager, param_name
from .params.metadata import metadata_for, set_problem
from .mission.control import MissionControl
from .mission.plan import Plan, PlanKind
from .rules import COPTER_MODES, MAX_ALTITUDE, MIN_TAKEOFF_ALTITUDE, go_to_problem, takeoff_altitude_problem
from .sequence import SequenceSlot
from .setpoints import SetpointStreamer
from .signing import LinkSigning, SigningConfig
from .state import (
    FENCE_PARAMS, Battery, BatteryThresholds, CommandResult, CommandStatus, LinkHealth, LinkStatus, Setpoint,
    Severity, VehicleState,
)
from .store import StateStore
from .supervision import LinkSupervisor
from .takeoff import TakeoffSequence
from .telemetry import COPTER_MODE_NAMES, TELEMETRY, fold_heartbeat

log = logging.getLogger(__name__)

__all__ = ["Vehicle", "VehicleConfig", "ReplayControl", "COPTER_MODES", "COPTER_MODE_NAMES",
           "MIN_TAKEOFF_ALTITUDE", "MAX_ALTITUDE", "takeoff_altitude_problem"]

MASK_VELOCITY_YAW_RATE = 1479      # use vx, vy, vz and yaw rate (arducopter.md)
MASK_POSITION = 3576               # use x, y, z only
MASK_VELOCITY = 3527               # use vx, vy, vz only
YAW_LEAD = 0.5                     # s: old firmware's heading target is this far ahead of a turning nose
YAW_RESEND = 0.2                   # s between those targets
ARM_FORCE_MAGIC = 21196
PUBLISH_INTERVAL = 0.01            # s: state is republished at most at 100 Hz while telemetry streams
LOG_FLUSH_INTERVAL = 1.0           # s: a crash loses at most this much of the flight log


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
    ready_timeout: float = 60.0               # s the takeoff waits for readiness before trying anyway
    climb_timeout: float = 20.0               # s for the climb to 95 % of the target, plus 2 s a metre
    mavlink_version: int | None = None        # None: start on 1, follow the autopilot to 2
    battery_cells: int | None = None          # None: from the vehicle, or inferred from the first voltage
    battery_thresholds: BatteryThresholds = field(default_factory=BatteryThresholds)   # the pilot's own alarm
    replay_speed: float = 1.0
    heartbeat_interval: float = 1.0
    signing: SigningConfig | None = None      # MAVLink 2 signing (driver.signing); None: off until a key is given
    allowed_senders: tuple[str, ...] = ()     # UDP: other addresses read besides the vehicle's ("10.1.1.1")
    param_metadata: str | None = None         # apm.pdef.xml; None: the per-user cache's, else the shipped copy
    param_cache: str | None = ""              # folder of tables per vehicle; "": the per-user cache, None: none
    param_ftp: bool = True                    # read all parameters over MAVLink FTP where the vehicle offers it


def _ground_only(s: VehicleState) -> str | None:
    """Guard for commands that only make sense disarmed on the ground, checked each time one goes out."""
    return "only when disarmed on the ground" if s.armed or s.flying else None


def _not_in_flight(s: VehicleState) -> str | None:
    return "not while flying (the motors would stop in the air)" if s.flying else None


class Vehicle(Drone):
    """An ArduCopter reached over MAVLink; the embedded driver behind the viewer and the Ice server."""

    def __init__(self, config: VehicleConfig | None = None):
        self.config = cfg = config or VehicleConfig()
        self._transport: Transport = open_transport(cfg.connection, cfg.baud, cfg.source_system,
                                                    cfg.source_component, cfg.replay_speed, cfg.allowed_senders)
        self._replay = ReplayControl(self._transport) if self._transport.is_replay else None
        self._signing = LinkSigning(cfg.signing, self._transport.description)
        self._codec_in = self._signing.parser()
        self._parser_generation = self._signing.generation
        self._codec_out = self._new_encoder()
        self._sender_generation = -1          # the encoder is (re)configured for signing on the next send
        self._tx_lock = threading.Lock()
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
        self._link = LinkSupervisor(cfg, self._transport, self._commands.capabilities, self._target_ids)
        self._params = ParameterManager(self._store, self._notifier, self._target_ids, 2 * cfg.loss_timeout)
        self._param_cache = ParameterCache(cfg.param_cache or None) if cfg.param_cache is not None else None
        self._params.on_complete = self._cache_parameters
        self._params.use_ftp = cfg.param_ftp
        self._metadata_warned = False         # the metadata is read by start() in the background (half a second)
        self._metadata_error_told = False
        self._setpoints = SetpointStreamer(cfg.deadman, cfg.setpoint_rate)
        self._payload = Payload(self)         # gimbal, region of interest, camera (driver.payload)
        self._sequence = SequenceSlot(self._store, self._commands, self._notifier)   # takeoff or mission start
        self._yaw_next = 0.0                  # old firmware: next CONDITION_YAW of a held yaw stick
        self._yaw_held = False                # old firmware: the heading is held by CONDITION_YAW
        self._latest: dict = {}               # newest telemetry message of each type in this read
        self._open_error = ""
        self._gcs_failsafe_warned = False
        self._reopen = False
        self._limits = cfg.limits.within(CEILING)
        self._outbox: collections.deque = collections.deque()   # messages posted by callers, sent by the ticker
        self._wake = threading.Event()
        self._closing = threading.Event()
        self._threads: list[threading.Thread] = []
        self._ticker: threading.Thread | None = None
        self._started = False
        self._forwarder = Forwarder(cfg.outputs, cfg.baud, self._forward_to_vehicle,
                                    lambda text: self._store.add_message(Severity.WARNING, text), self._closing)
        self._missions = MissionControl(self)          # driver.mission: transfers, mission state, AUTO
        self.logs = LogControl(self)                   # driver.logs: the vehicle's DataFlash logs

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
        for target, name in ((self._run_reader, "mavlink-reader"), (self._run_ticker, "mavlink-ticker")):
            t = threading.Thread(target=target, name=name, daemon=True)
            t.start()
            self._threads.append(t)
            if name == "mavlink-ticker":
                self._ticker = t
        self._threads += self._forwarder.start()
        threading.Thread(target=self._read_metadata, name="param-metadata", daemon=True).start()
        return self

    def close(self) -> None:
        if self._closing.is_set():
            return
        with self._lock:
            self._sequence.abort("driver closed")
            moving = not self._setpoints.setpoint.is_zero
        if self._started and moving:
            self._send(self._setpoint_message(Setpoint()))   # leave the vehicle hovering, not drifting
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

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.close()

    # ------------------------------------------------------------------------------------------
    # state
    # ------------------------------------------------------------------------------------------
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

    # ------------------------------------------------------------------------------------------
    # sending: decided under the lock, written after it
    # ------------------------------------------------------------------------------------------
    def _send(self, msg) -> None:
        """Pack and write one message; ``bytes`` are a frame packed already (SETUP_SIGNING)."""
        if self._transport.is_replay:
            return
        with self._tx_lock:
            if isinstance(msg, bytes):
                self._write(msg)
                return
            signing, codec = self._signing, self._codec_out
            if self._sender_generation != signing.generation:
                self._sender_generation = signing.generation
                signing.configure_sender(codec, signing.key)
            signing.stamp(codec)
            buf = msg.pack(codec, force_mavlink1=not self._v2)
            codec.seq = (codec.seq + 1) % 256
            signing.note_sent(codec)
            self._write(buf)

    def _new_encoder(self):
        return mavlink.MAVLink(None, srcSystem=self.config.source_system, srcComponent=self.config.source_component)

    def _forward_to_vehicle(self, frame: bytes) -> None:
        with self._tx_lock:
            self._write(frame)

    def _post(self, msg) -> None:
        """Send from the ticker thread: callers (the UI among them) never touch the link themselves."""
        self._outbox.append(msg)
        self._wake.set()

    def _write(self, buf: bytes) -> None:
        """Whole frames only, one writer at a time (caller holds _tx_lock)."""
        if self._transport.write(buf) and self._tlog:       # the log holds what really went out
            self._tlog.write(buf)

    def _heartbeat_message(self):
        return mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0,
                                                 mavlink.MAV_STATE_ACTIVE, 3)

    def _setpoint_message(self, sp: Setpoint):
        system, component = self._target_ids()
        return mavlink.MAVLink_set_position_target_local_ned_message(
            0, system, component, mavlink.MAV_FRAME_BODY_OFFSET_NED,
            MASK_VELOCITY_YAW_RATE, 0, 0, 0, sp.forward, sp.right, -sp.up, 0, 0, 0, 0, sp.yaw_rate)

    def _legacy_setpoint_messages(self, sp: Setpoint, now: float) -> list:
        """Firmware before ArduCopter 3.5 (the stock Solo) reads neither the frame nor the yaw rate of
        SET_POSITION_TARGET_LOCAL_NED ("for future use" in its GCS_Mavlink): body velocities are turned to
        north/east here, with the heading the vehicle reports, and the nose is steered with CONDITION_YAW
        heading targets a little ahead of it (else the vehicle turns its nose to the direction of travel)."""
        system, component = self._target_ids()
        yaw = self._store.state.attitude.yaw
        c, s = math.cos(yaw), math.sin(yaw)
        out = [mavlink.MAVLink_set_position_target_local_ned_message(
            0, system, component, mavlink.MAV_FRAME_LOCAL_NED, MASK_VELOCITY,
            0, 0, 0, c * sp.forward - s * sp.right, s * sp.forward + c * sp.right, -sp.up, 0, 0, 0, 0, 0)]
        if sp.yaw_rate and now >= self._yaw_next:
            target = math.degrees(yaw + sp.yaw_rate * YAW_LEAD) % 360.0
            out.append(mavlink.MAVLink_command_long_message(
                system, component, mavlink.MAV_CMD_CONDITION_YAW, 0, target, math.degrees(abs(sp.yaw_rate)),
                1 if sp.yaw_rate > 0 else -1, 0, 0, 0, 0))
            self._yaw_next, self._yaw_held = now + YAW_RESEND, False
        elif not sp.yaw_rate and not self._yaw_held:          # hold the heading the pilot left it at
            out.append(mavlink.MAVLink_command_long_message(
                system, component, mavlink.MAV_CMD_CONDITION_YAW, 0, math.degrees(yaw) % 360.0, 30, 0, 0, 0, 0, 0))
            self._yaw_held = True
        return out

    # ------------------------------------------------------------------------------------------
    # reader thread
    # ------------------------------------------------------------------------------------------
    def _new_parser(self, carry=None):
        """A fresh incoming codec, signing as configured now; ``carry``: the old one, whose unparsed bytes
        (half a TCP frame) it takes over."""
        codec = self._signing.parser()
        self._parser_generation = self._signing.generation
        if carry is not None:
            codec.buf = bytearray(carry.buf[carry.buf_index:])
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
                    self._send(self._heartbeat_message())   # speak first: udpout and serial peers learn of us
                except LinkError as exc:
                    if str(exc) != self._open_error:          # say it once, and again when the reason changes
                        self._open_error = str(exc)
                        self._store.add_message(Severity.WARNING, f"{exc}; retrying")
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
                self._store.add_message(Severity.WARNING, f"Link error: {exc}; reconnecting")
                self._transport.close()
                opened = False
                self._codec_in = self._new_parser()
                with self._lock:
                    self._link.reset_sequences()
                self._closing.wait(backoff)
                continue
            if data:
                self.ingest(data)
            elif self._latest or self._store.fields:
                with self._lock:                              # traffic paused: publish what is held back
                    self._fold_and_publish()

    def ingest(self, data: bytes) -> int:
        """Parse raw bytes as if read from the link and fold them into the state; returns messages parsed."""
        if self._parser_generation != self._signing.generation:     # the key changed: check with the new one
            self._codec_in = self._new_parser(self._codec_in)
        try:
            msgs = self._parse(data)
        except Exception as exc:                      # robust parsing should catch all; never let it escape
            log.debug("parser reset after %s", exc)
            self._codec_in = self._new_parser()
            msgs = None
        if self._forwarder.outputs:
            self._forwarder.send(data)
        if not msgs:                                  # part of a frame (TCP, serial): nothing to fold yet
            return 0
        n = 0
        with self._lock:
            for msg in msgs:
                try:
                    n += self._handle(msg)
                except Exception:                     # a malformed field must not stop the reader
                    log.exception("error handling %s", msg.get_type())
            if n and time.monotonic() - self._store.published_at >= PUBLISH_INTERVAL:
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
        store = self._store
        view = store.view()
        for mtype, msg in latest.items():             # telemetry: only the newest of each kind matters
            try:
                changes = TELEMETRY[mtype](view, msg)
            except Exception:
                log.exception("error folding %s", mtype)
                continue
            store.fields.update(changes)
            if mtype == "HOME_POSITION" and "home" in changes:
                self._link.home_received()
            elif mtype == "ATTITUDE":
                self._link.last_attitude = time.monotonic()
        store.fields["link"] = self._link.health(self._version)   # packet counts as current as the telemetry
        if store.state.rejected_values == 0 and store.fields.get("rejected_values", 0) > 0:   # the first one
            store.add_message_locked(Severity.WARNING, "The vehicle sent impossible telemetry values (NaN, "
                                     "infinity or out of range): ignored, the last good values stay")
        store.publish()

    def _handle(self, msg) -> int:
        """One parsed frame (reader thread, _lock held); the hot path of telemetry ingest."""
        mtype = msg.get_type()
        link = self._link
        if mtype == "BAD_DATA":
            reason = getattr(msg, "reason", "")
            if "CRC" in reason:
                link.bad_crc += 1
            elif reason == "Invalid signature":
                self._signing.rejected(msg)
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
            self._store.set(system_id=system)
            log.info("vehicle found: system %d", system)
        component, seq = header.srcComponent, header.seq
        last = link.last_seq.get(component)           # sequence gaps: packet loss per component (inline: hot)
        if last is not None:
            gap = (seq - last - 1) & 0xFF
            if gap < 128:                             # larger jumps are a restart, not loss
                link.rx_lost += gap
        link.last_seq[component] = seq
        link.rx_count += 1
        if mtype in PAYLOAD_MESSAGES:                 # the gimbal and camera speak from any component
            self._payload.on_message(msg, component)
            return 1
        if component != self._autopilot and self._autopilot:   # a gimbal, camera or companion computer
            if mtype == "STATUSTEXT":
                self._on_statustext(msg)
            return 1
        if not self._v2 and msg.get_msgbuf()[0] == 0xFD and self.config.mavlink_version is None:
            self._v2 = True                           # the autopilot's own framing, never another component's
            log.info("vehicle speaks MAVLink 2: following it")
        if mtype in TELEMETRY:
            self._latest[mtype] = msg                 # folded once per read, see ingest()
        else:
            handler = _EVENTS.get(mtype)
            if handler is not None:
                handler(self, msg)
        return 1

    # -- events (reader thread, _lock held) ---------------------------------------------------------
    def _on_heartbeat(self, m) -> None:
        if m.autopilot == mavlink.MAV_AUTOPILOT_INVALID:
            return
        store = self._store
        now = time.monotonic()
        self._transport.heard_vehicle()
        self._settle_signing(self._signing.heartbeat(m))
        view = store.view()
        was_armed = view["armed"]
        changes = fold_heartbeat(view, m)
        store.fields.update(changes)
        self._commands.on_mode(m.custom_mode)
        if changes["armed"] != was_armed:
            self._link.armed_changed(changes["armed"], now)
        event = self._link.heartbeat(now)
        if event is None:
            return
        store.set(link=self._link.health(self._version))
        self._wake.set()                              # the ticker asks for streams at once
        if event == "recovered":
            self._commands.link_recovered(now)
            store.publish()
            store.add_message_locked(Severity.NOTICE, "Link recovered")
        elif event == "first":
            store.add_message_locked(Severity.INFO, f"Vehicle {self._target} connected on {self.description}")

    def _on_statustext(self, m) -> None:
        text = m.text.rstrip("\x00").strip() if isinstance(m.text, str) else bytes(m.text).decode("ascii", "replace")
        if text:
            try:
                sev = Severity(m.severity)
            except ValueError:
                sev = Severity.INFO
            self._store.add_message_locked(sev, text, "vehicle")
            self._settle_signing(self._signing.statustext(text))
            self._missions.on_text(text)
            self.logs.on_text(text)

    def _on_command_ack(self, m) -> None:
        self._commands.on_ack(m, time.monotonic())
        self._wake.set()

    def _on_autopilot_version(self, m) -> None:
        v = m.flight_sw_version
        major, minor, patch = (v >> 24) & 0xFF, (v >> 16) & 0xFF, (v >> 8) & 0xFF
        self._link.version_known = True
        self._params.ftp_capable = bool(m.capabilities & mavlink.MAV_PROTOCOL_CAPABILITY_FTP)
        self._missions.on_autopilot_version(m)
        if major:
            self._commands.capabilities.setpoint_yaw = (major, minor) >= (3, 5)
            self._store.set(firmware=f"{major}.{minor}.{patch}")
            if (major, minor) < (3, 5):
                self._store.add_message_locked(
                    Severity.NOTICE, f"Firmware {major}.{minor}.{patch}: velocity goes north/east and the nose is "
                    "steered with CONDITION_YAW (it ignores body frames and yaw rates)")

    def _on_param_value(self, m) -> None:
        if not frames.finite(m.param_value):
            return
        name = param_name(m)
        self._params.on_param_value(m, name, time.monotonic())
        if self._params.reasking:
            self._wake.set()                          # the next read goes out now, not on the next tick
        self._link.param_received(name)
        self._missions.on_param(name, m.param_value)
        if name in FENCE_PARAMS:
            self._store.set(fence=self._store.view()["fence"].with_param(name, m.param_value))
        elif name == "FS_GCS_ENABLE":
            self._store.set(gcs_failsafe=int(m.param_value))
            if int(m.param_value) == 0 and not self._gcs_failsafe_warned:
                self._gcs_failsafe_warned = True
                self._store.add_message_locked(
                    Severity.WARNING, "GCS failsafe is off on the vehicle (FS_GCS_ENABLE=0): if this link is lost "
                    "or you quit in flight, it keeps hovering until its battery failsafe")

    def _on_file_transfer_protocol(self, m) -> None:
        """MAVLink FTP: the parameters' file (driver.params.ftp)."""
        if m.target_system in (0, self.config.source_system) and m.target_component in (0, self.config.source_component):
            self._params.on_ftp(m, time.monotonic())
            self.logs.on_ftp(m)
            self._wake.set()
    def _on_mission(self, m) -> None:
        self._missions.on_message(m)

    def _on_fence_status(self, m) -> None:
        """FENCE_STATUS, sent while the fence is enabled: a new breach is told once, with what it was."""
        fence = self._store.view()["fence"]
        breached = bool(m.breach_status)
        if breached and not fence.breached:
            what = {1: "below the minimum altitude", 2: "above FENCE_ALT_MAX",
                    3: "outside FENCE_RADIUS"}.get(m.breach_type, "outside the fence")
            self._store.add_message_locked(Severity.CRITICAL, f"Fence breached: {what}; the vehicle acts on its own "
                                           "(FENCE_ACTION: RTL or land)")
        if breached != fence.breached:
            self._store.set(fence=replace(fence, breached=breached))

    # ------------------------------------------------------------------------------------------
    # ticker thread
    # ------------------------------------------------------------------------------------------
    def _run_ticker(self) -> None:
        next_heartbeat = next_health = next_flush = 0.0
        while not self._closing.is_set():
            now = time.monotonic()
            out: list = []
            try:
                if now >= next_heartbeat:
                    next_heartbeat = now + self.config.heartbeat_interval
                    out.append(self._heartbeat_message())
                while self._outbox:
                    out.append(self._outbox.popleft())
                with self._lock:
                    self._sequence.step(now)
                    out += self._stream_setpoint(now)
                    out += self._commands.service(now, self._store.state)
                    out += self._params.service(now, self._link.status)
                    out += self._payload.service(now, self._store.state)
                    out += self._missions.service(now, self._store.state)
                    out += self.logs.service(now, self._store.state)
                    if now >= next_health:
                        next_health = now + 0.1
                        out += self._supervise(now)
                        frames_out, settled = self._signing.service(now, self._target_ids(), self._new_encoder)
                        out += frames_out
                        self._settle_signing(settled)
            except Exception:                         # heartbeat, setpoints and deadman must outlive any bug
                log.exception("ticker step failed")
            for msg in out:                           # outside the lock: a slow link stalls nobody else
                self._send(msg)
            if self._tlog is not None and now >= next_flush:
                next_flush = now + LOG_FLUSH_INTERVAL
                self._tlog.flush()
            self._wake.wait(min(0.05, 1.0 / self.config.setpoint_rate))
            self._wake.clear()

    def _supervise(self, now: float) -> list:
        """Link health, loss, log failures and requests to the vehicle; republishes every 100 ms."""
        store = self._store
        if self._tlog is not None and self._tlog.error:
            error, self._tlog = self._tlog.error, None
            store.add_message_locked(Severity.WARNING, f"Flight log stopped: {error}")
        out, event, reopen = self._link.tick(now)
        if reopen:
            self._reopen = True
        store.set(link=self._link.health(self._version), signing=self._signing.snapshot(self._version))
        for ip, port in self._transport.strangers():
            store.add_message_locked(Severity.WARNING, f"Ignored MAVLink from {ip}:{port}: the link is pinned to the "
                                     f"vehicle at {self._link.health(self._version).pinned_to} (--allow {ip} "
                                     "accepts that sender)")
        store.publish()
        if event == "lost":
            age = self._link.health(self._version).heartbeat_age or 0.0
            store.add_message_locked(Severity.CRITICAL, f"Link lost: no heartbeat for {age:.1f} s")
            self._commands.link_lost()
            self._params.link_lost()
        elif event == "finished":
            store.add_message_locked(Severity.NOTICE, "Replay ended: the whole recording has been played")
        return out

    def _stream_setpoint(self, now: float) -> list:
        sp, fired = self._setpoints.tick(now)
        if fired:
            self._store.set(setpoint=self._setpoints.setpoint)
            self._store.publish()
        if not self._setpoints.streaming:
            self._yaw_held = False                    # the next stick movement holds the heading it finds
        if sp is None or self._store.state.mode != "GUIDED":
            return []
        if self._commands.capabilities.setpoint_yaw is False:
            return self._legacy_setpoint_messages(sp, now)
        return [self._setpoint_message(sp)]

    # ------------------------------------------------------------------------------------------
    # commands
    # ------------------------------------------------------------------------------------------
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
            future = self._commands.submit(name, command, params, time.monotonic(), guard=guard,
                                           tag=self._sequence.tag)
        self._wake.set()
        return future

    def _finish(self, command: str, status: CommandStatus, reason: str = "") -> Future:
        f: Future = Future()
        f.set_result(self._store.record(command, status, reason))
        return f

    def _busy(self, command: str) -> Future | None:
        if self._sequence.stepping and threading.current_thread() is self._ticker:
            return None                               # the sequence's own commands
        if self.state().takeoff.active:
            return self._finish(command, CommandStatus.REJECTED, "takeoff in progress: only Land and Stop")
        return None

    def set_mode(self, name: str) -> Future:
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
            future = self._commands.submit_mode(f"mode {name.upper()}", number, time.monotonic(),
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
            problem = _not_in_flight(self.state())
            if problem:
                return self._finish("disarm (forced)", CommandStatus.REJECTED, problem)
        return self._busy("disarm") or self._command_long(
            mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (0, ARM_FORCE_MAGIC if force else 0),
            "disarm (forced)" if force else "disarm", guard=_not_in_flight if force else None)

    def land(self) -> Future:
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
                               guard=_not_in_flight)
            undone.append("disarming")
        if seq.mode_before and s.mode != seq.mode_before:
            self._set_mode(seq.mode_before)
            undone.append(f"back to {seq.mode_before}")
        return self._finish("cancel takeoff", CommandStatus.ACCEPTED,
                            "cancelled before liftoff: " + (", ".join(undone) or "the vehicle was not changed"))

    def return_to_launch(self) -> Future:
        return self._busy("RTL") or self._set_mode("RTL")

    def stop(self) -> Future:
        """Hold position, and the sticks fly again: zero velocity in GUIDED (which also cancels a go-to); in
        flight in another mode (RTL, LOITER, LAND...), GUIDED with zero velocity, where ArduCopter brakes to its
        stopping point and holds it (ModeGuided::init); BRAKE if the vehicle refuses GUIDED (no position).
        During a takeoff that has not left the ground it is :meth:`cancel_takeoff`: the vehicle as it was."""
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
                self._setpoints.stop(time.monotonic())
                self._store.set(setpoint=self._setpoints.setpoint)
                self._store.publish()
            self._wake.set()
            return self._finish("stop", CommandStatus.ACCEPTED, "holding position (zero velocity in GUIDED)")
        return self._hold_in_guided(s.mode)

    def _hold_in_guided(self, was: str) -> Future:
        """Stop outside GUIDED: zeros wait to stream, GUIDED is asked; if refused, BRAKE (the sticks then stay
        inert until GUIDED is possible, and the result says why)."""
        with self._lock:
            self._setpoints.stop(time.monotonic())
            self._store.set(setpoint=self._setpoints.setpoint)

        def guided_answered(r: CommandResult):
            if r.ok:
                return self._store.record("stop", CommandStatus.ACCEPTED,
                                          f"holding position in GUIDED (was {was}): the sticks fly")
            return chain(self._set_mode("BRAKE"), lambda b: self._store.record(
                "stop", b.status, f"GUIDED refused ({r.reason}): BRAKE, {b.reason}"), "stop")
        return chain(self._set_mode("GUIDED"), guided_answered, "stop")

    def reboot(self) -> Future:
        problem = _ground_only(self.state())
        if problem:
            return self._finish("reboot", CommandStatus.REJECTED, problem)
        return self._busy("reboot") or self._command_long(mavlink.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, (1,), "reboot",
                                                          guard=_ground_only)

    def calibrate_level(self) -> Future:
        """Level (accelerometer trim) calibration; only sensible disarmed on the ground."""
        problem = _ground_only(self.state())
        if problem:
            return self._finish("level calibration", CommandStatus.REJECTED, problem)
        return self._busy("level calibration") or self._command_long(
            mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, (0, 0, 0, 0, 2, 0, 0), "level calibration", guard=_ground_only)

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

    # -- parameters (driver.params) ------------------------------------------------------------------------
    def fetch_parameters(self, refresh: bool = False) -> Future:
        """Download every parameter into ``state().parameters`` (driver.params.download)."""
        if self._replay is not None:
            return self._finish("parameters", CommandStatus.REJECTED, "replaying a recording: no vehicle to ask")
        if refresh or self._param_cache is None:
            with self._lock:
                future = self._params.fetch(refresh, time.monotonic(), None)
            self._wake.set()
            return future
        outer: Future = Future()

        def with_cache() -> None:             # the cache is a file: read here, never on the caller's (UI) thread
            s = self.state()
            cached = self._param_cache.load(s.system_id, s.firmware)
            with self._lock:
                inner = self._params.fetch(refresh, time.monotonic(), cached)
            self._wake.set()
            inner.add_done_callback(lambda f: outer.set_result(f.result()))
        threading.Thread(target=with_cache, name="param-cache-read", daemon=True).start()
        return outer

    def _cache_parameters(self, table) -> None:
        """A complete table: kept per vehicle for its next connection (written off the reader's lock)."""
        if self._param_cache is not None:
            s = self._store.view()
            threading.Thread(target=self._param_cache.save, args=(s["system_id"], s["firmware"], table),
                             name="param-cache", daemon=True).start()

    def set_parameter(self, name: str, value: float, allow_out_of_bounds: bool = False) -> Future:
        """PARAM_SET in the parameter's own type, confirmed by the vehicle's echo (driver.params.setter); outside
        ArduPilot's documented bounds only when ``allow_out_of_bounds`` (driver.params.metadata)."""
        name = name.upper() if isinstance(name, str) else ""
        if not name or len(name) > 16 or not name.isascii():
            return self._finish(f"param {name}", CommandStatus.REJECTED, "a parameter name is 1 to 16 ASCII characters")
        if self._replay is not None:
            return self._finish(f"param {name}", CommandStatus.REJECTED, "replaying a recording: no vehicle to command")
        metadata = self._read_metadata(wait=False)      # the caller's (the window's) thread never waits for it
        with self._lock:
            problem = self._params.value_problem(name, float(value))
        problem = problem or set_problem(metadata, name, float(value), allow_out_of_bounds)
        if problem:
            return self._finish(f"param {name}", CommandStatus.REJECTED, problem)
        if metadata is None and not self._metadata_warned:
            self._metadata_warned = True
            self._store.add_message(Severity.WARNING, "No parameter metadata (ArduPilot's apm.pdef.xml): values are "
                                    "written without checking their bounds")
        with self._lock:
            future = self._params.set(name, float(value), time.monotonic())
        self._wake.set()
        return future

    @property
    def parameter_metadata(self):
        return self._read_metadata()

    def _read_metadata(self, wait: bool = True):
        """The metadata (driver.params.metadata.metadata_for); None when there is none or, without ``wait``,
        while it is still being read. Why it could not be read is told once."""
        outcome = metadata_for(self.config.param_metadata, wait)
        if outcome is None:
            return None
        metadata, error = outcome
        if error:
            with self._lock:
                tell, self._metadata_error_told = not self._metadata_error_told, True
            if tell:
                self._store.add_message(Severity.WARNING, f"Parameter metadata not read: {error}")
        return metadata

    # ------------------------------------------------------------------------------------------
    # payload: gimbal, region of interest, camera (driver.payload)
    # ------------------------------------------------------------------------------------------
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

    # ------------------------------------------------------------------------------------------
    # signing (driver.signing)
    # ------------------------------------------------------------------------------------------
    def use_signing_key(self, key: bytes | None, allow_unsigned: bool | None = None) -> CommandResult:
        """Sign with ``key`` from now on, or stop (None), without telling the vehicle; ``allow_unsigned`` lets
        the vehicle's unsigned frames in (a vehicle without the key yet)."""
        if key is not None and len(key) != 32:
            return self._store.record("signing key", CommandStatus.REJECTED, "a signing key is 32 bytes")
        with self._lock:
            self._signing.use_key(key, allow_unsigned)
            self._store.set(signing=self._signing.snapshot(self._version))
            result = self._store.record_locked("signing key", CommandStatus.ACCEPTED,
                                               "signing with the new key" if key else "signing off")
        self._wake.set()
        return result

    @property
    def signing_unavailable(self) -> str:
        return "a recording cannot be signed" if self._replay is not None else ""

    def allow_unsigned(self, on: bool) -> CommandResult:
        """Let the vehicle's unsigned frames in while we sign (a vehicle that has no key yet), or stop."""
        with self._lock:
            self._signing.use_key(self._signing.key, allow_unsigned=on)
            self._store.set(signing=self._signing.snapshot(self._version))
            return self._store.record_locked("signing unsigned", CommandStatus.ACCEPTED,
                                             "the vehicle's unsigned frames are let in" if on else
                                             "the vehicle's unsigned frames are dropped")

    def setup_signing(self, key: bytes) -> Future:
        """Give the vehicle ``key`` with SETUP_SIGNING (in clear: a trusted link only) and sign with it;
        resolves when the vehicle's heartbeats arrive signed with it."""
        if len(key) != 32 or not any(key):
            return self._finish("signing setup", CommandStatus.REJECTED, "a signing key is 32 bytes, not all zero")
        return self._change_signing("signing setup", key)

    def remove_signing(self) -> Future:
        """Tell the vehicle to stop signing (a key of zeros); we stop once its heartbeats arrive unsigned."""
        if self._signing.key is None:
            return self._finish("signing remove", CommandStatus.REJECTED, "no signing key in use")
        return self._change_signing("signing remove", None)

    def _change_signing(self, name: str, key: bytes | None) -> Future:
        s = self.state()
        problem = ("replaying a recording: no vehicle to command" if self._replay is not None else
                   "no vehicle connected" if not s.connected else
                   "the vehicle refuses it while armed: disarm first" if s.armed else
                   "the vehicle speaks MAVLink 1, which cannot be signed" if not self._v2 else None)
        if problem:
            return self._finish(name, CommandStatus.REJECTED, problem)
        future: Future = Future()
        with self._lock:
            if key is not None:
                self._store.add_message_locked(Severity.WARNING, "SETUP_SIGNING carries the key in clear: anyone "
                                               "listening on this link learns it (use USB or a cable)")
            self._settle_signing(self._signing.begin(name, key, future, time.monotonic()))
            self._store.set(signing=self._signing.snapshot(self._version))
            self._store.publish()
        self._wake.set()
        return future

    def _settle_signing(self, settled) -> None:
        """Record a finished SETUP_SIGNING exchange and settle its future (_lock held)."""
        if settled is not None:
            future, name, status, reason = settled
            self._store.set(signing=self._signing.snapshot(self._version))
            self._notifier.settle(future, self._store.record_locked(name, status, reason))

    # ------------------------------------------------------------------------------------------
    # velocity, position and yaw
    # ------------------------------------------------------------------------------------------
    def set_velocity(self, forward: float, right: float, up: float, yaw_rate: float) -> bool:
        sp = SetpointStreamer.clamp(forward, right, up, yaw_rate, self._limits)
        if sp is None:
            log.warning("velocity refused: not finite (%r, %r, %r, %r)", forward, right, up, yaw_rate)
            return False
        if self.state().takeoff.active:
            return False
        with self._lock:
            if self._setpoints.demand(sp, time.monotonic()):
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
            self._post(self._setpoint_message(Setpoint()))
        direction = (1 if degrees >= 0 else -1) if relative else 0
        angle = abs(degrees) if relative else degrees % 360.0
        return self._command_long(mavlink.MAV_CMD_CONDITION_YAW,
                                  (angle, abs(rate_deg_s), direction, 1 if relative else 0),
                                  f"yaw {'by' if relative else 'to'} {degrees:g}°")

    # ------------------------------------------------------------------------------------------
    # takeoff sequence (stepped by the ticker)
    # ------------------------------------------------------------------------------------------
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
            seq = TakeoffSequence(self, alt, self.config, time.monotonic())
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

    # ------------------------------------------------------------------------------------------
    # missions, fences, rally points (driver.mission.control does the work)
    # ------------------------------------------------------------------------------------------
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
        """End a takeoff or mission start in progress (driver.sequence), cancelling what it asked."""
        with self._lock:
            self._sequence.abort(why)


#: Events: every one counts (mode/arming changes, the pilot's messages, command answers).
_EVENTS = {
    "HEARTBEAT": Vehicle._on_heartbeat,
    "STATUSTEXT": Vehicle._on_statustext,
    "COMMAND_ACK": Vehicle._on_command_ack,
    "PARAM_VALUE": Vehicle._on_param_value,
    "AUTOPILOT_VERSION": Vehicle._on_autopilot_version,
    "FENCE_STATUS": Vehicle._on_fence_status,
    "FILE_TRANSFER_PROTOCOL": Vehicle._on_file_transfer_protocol,
    **{name: lambda v, m: v.logs.on_message(m) for name in ("LOG_ENTRY", "LOG_DATA")},
    **{name: Vehicle._on_mission for name in ("MISSION_CURRENT", "MISSION_ITEM_REACHED", "MISSION_REQUEST",
                                              "MISSION_REQUEST_INT", "MISSION_COUNT", "MISSION_ITEM",
                                              "MISSION_ITEM_INT", "MISSION_ACK", "RALLY_POINT")},
}
