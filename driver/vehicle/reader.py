"""The reader thread of a :class:`~driver.vehicle.vehicle.Vehicle`: it opens the link (reopening TCP and serial links
that fail), parses every byte with pymavlink's codec and folds it into the state.

Telemetry is folded once per read (:data:`driver.vehicle.telemetry.TELEMETRY`, newest of each kind); events
(heartbeat, STATUSTEXT, COMMAND_ACK, parameters, missions, fence, FTP) go one by one to the part that owns them.
Everything here runs on the reader thread with the state lock held, and never writes to the link itself.
"""
from __future__ import annotations

import logging
import time
from dataclasses import replace

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core import frames
from ..link.transport import LinkError
from ..mission.progress import fold_restart
from ..params.manager import param_name
from ..payload.control import PAYLOAD_MESSAGES
from ..setup.banner import heard_text, heard_version
from ..setup.control import SETUP_MESSAGES
from .inspector import MessageInspector
from .prearm import PreArmReasons
from .state import FENCE_PARAMS, Severity
from .telemetry import TELEMETRY, fold_heartbeat

log = logging.getLogger("driver.vehicle")

__all__ = ["Reader", "PUBLISH_INTERVAL"]

PUBLISH_INTERVAL = 0.01            # s: state is republished at most at 100 Hz while telemetry streams


class Reader:
    """Reads, parses and dispatches what the vehicle sends; its own state is the incoming codec and what is held
    back for the next fold. Built last by the vehicle: it hands every message to the vehicle's other parts."""

    def __init__(self, vehicle):
        self._v = vehicle
        self.config = vehicle.config
        self._transport, self._signing, self._store = vehicle._transport, vehicle._signing, vehicle._store
        self._lock, self._link, self._commands = vehicle._lock, vehicle._link, vehicle._commands
        self._params, self._payload, self._missions = vehicle._params, vehicle._payload, vehicle._missions
        self._forwarder, self._closing, self._wake = vehicle._forwarder, vehicle._closing, vehicle._wake
        self.codec = self._signing.parser()
        self._parser_generation = self._signing.generation
        self.latest: dict = {}             # newest telemetry message of each type in this read
        self.reopen = False                # the supervisor found a half-open link: reopen it
        self._open_error = ""
        self._gcs_failsafe_warned = False
        self._last_frame: dict[int, bytes] = {}   # each component's last frame: a repeat of it is dropped
        self._prearm = PreArmReasons()     # the vehicle's own reasons for refusing to arm (Readiness.reasons)
        self.inspector = vehicle.inspector = MessageInspector(vehicle.clock)   # what the link carries: Drone.inspection()

    def _new_parser(self, carry=None):
        """A fresh incoming codec, signing as configured now; ``carry``: the old one, whose unparsed bytes
        (half a TCP frame) it takes over."""
        codec = self._signing.parser()
        self._parser_generation = self._signing.generation
        if carry is not None:
            codec.buf = bytearray(carry.buf[carry.buf_index:])
        return codec

    def run(self) -> None:
        backoff = 0.2
        opened = False
        while not self._closing.is_set():
            if not opened:
                try:
                    self._transport.open()
                    opened, backoff = True, 0.2
                    self._open_error = ""
                    self.reopen = False
                    self._v._v2 = self.config.mavlink_version == 2
                    log.info("link open: %s", self._transport.description)
                    self._v._ticker.send(self._v._ticker.heartbeat_message())   # speak first: udpout and serial peers learn of us
                except LinkError as exc:
                    if str(exc) != self._open_error:          # say it once, and again when the reason changes
                        self._open_error = str(exc)
                        self._store.add_message(Severity.WARNING, f"{exc}; retrying")
                    log.info("%s; retrying in %.1f s", exc, backoff)
                    self._closing.wait(backoff)
                    backoff = min(backoff * 2, 3.0)
                    continue
            if self.reopen:                               # lost on a link that can be reopened (half-open TCP)
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
                self.codec = self._new_parser()
                with self._lock:
                    self._link.reset_sequences()
                self._closing.wait(backoff)
                continue
            if data:
                self.ingest(data)
            elif self.latest or self._store.fields:
                with self._lock:                              # traffic paused: publish what is held back
                    self._fold_and_publish()

    def ingest(self, data: bytes, publish: bool = False) -> int:
        """Parse raw bytes as if read from the link and fold them into the state; returns messages parsed.
        ``publish``: fold and publish everything now (a caller feeding the reader itself, on its own clock), not
        at most every PUBLISH_INTERVAL as the reader thread does."""
        if self._parser_generation != self._signing.generation:     # the key changed: check with the new one
            self.codec = self._new_parser(self.codec)
        try:
            msgs = self._parse(data)
        except Exception as exc:                      # robust parsing should catch all; never let it escape
            log.debug("parser reset after %s", exc)
            self.codec = self._new_parser()
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
            if n and (publish or time.monotonic() - self._store.published_at >= PUBLISH_INTERVAL):
                self._fold_and_publish()
        return n

    def _parse(self, data: bytes) -> list | None:
        """pymavlink's parse_buffer(), minus its last call that finds nothing when the read held exactly one
        frame (a UDP datagram from the Solo): about 1 µs of a frame's 12 µs."""
        codec = self.codec
        msg = codec.parse_char(data)
        if msg is None:
            return None
        return [msg] if codec.buf_len() == 0 else [msg, *(codec.parse_buffer(b"") or ())]

    def _fold_and_publish(self) -> None:
        """Fold the newest telemetry of each kind into the state and publish it (caller holds _lock)."""
        latest, self.latest = self.latest, {}
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
            if mtype in self._link.last_heard:
                self._link.last_heard[mtype] = self._v.clock()
        self._follow_boot_and_readiness("SYS_STATUS" in latest)
        store.fields["link"] = self._link.health(self._v._version)   # packet counts as current as the telemetry
        if store.state.rejected_values == 0 and store.fields.get("rejected_values", 0) > 0:   # the first one
            store.add_message_locked(Severity.WARNING, "The vehicle sent impossible telemetry values (NaN, "
                                     "infinity or out of range): ignored, the last good values stay")
        store.publish()

    def _follow_boot_and_readiness(self, sys_status: bool) -> None:
        """After a fold (lock held): a restart seen in the vehicle's clock, and the pre-arm reasons it no longer
        stands by (``sys_status``: a SYS_STATUS came in this fold, its pre-arm bit is news)."""
        store = self._store
        view = store.view()
        if view["boot"].restarts != store.state.boot.restarts and not self._transport.is_replay:
            self._restarted()             # (a replay's clock goes back when the pilot seeks back: no restart)
            view = store.view()
        r = view["readiness"]
        healthy = (r.prearm_ok if r.prearm_reported else None) if sys_status else None
        if self._prearm.checked(healthy, view["armed"], self._v.clock()):
            store.set(readiness=replace(r, reasons=self._prearm.reasons))

    def _restarted(self) -> None:
        """The vehicle started again (lock held): what it held is of its last boot. Its plans are not known any
        more (the viewer reads them again), nor its refusals; said once in Messages."""
        store = self._store
        view = store.view()
        self._prearm.forget()
        store.set(readiness=replace(view["readiness"], reasons=()), mission=fold_restart(view["mission"]))
        store.add_message_locked(Severity.NOTICE, "The vehicle restarted: what it held before (plans, pre-arm "
                                 "reasons) is read again")

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
        self.inspector.seen(msg, header.srcSystem, header.srcComponent, mtype)    # every system's, for the inspector
        if self._v._tlog:
            self._v._tlog.write(bytes(msg.get_msgbuf()))
        system = header.srcSystem
        if system != self._v._target:
            if self._v._target or not (mtype == "HEARTBEAT" and msg.autopilot != mavlink.MAV_AUTOPILOT_INVALID
                                    and msg.type != mavlink.MAV_TYPE_GCS):
                return 0                              # another system (a second GCS), or no vehicle yet
            self._v._target = system
            self._store.set(system_id=system)
            log.info("vehicle found: system %d", system)
        component, seq = header.srcComponent, header.seq
        last = link.last_seq.get(component)           # sequence gaps: packet loss per component (inline: hot)
        if last is not None:
            if seq == last and msg.get_msgbuf() == self._last_frame.get(component):
                link.duplicates += 1                  # the same frame twice (a radio or router repeating it):
                return 0                              # one answer is never taken for two
            gap = (seq - last - 1) & 0xFF
            if gap < 128:                             # larger jumps are a restart, not loss
                link.rx_lost += gap
        link.last_seq[component] = seq
        self._last_frame[component] = msg.get_msgbuf()
        link.rx_count += 1
        if mtype in PAYLOAD_MESSAGES:                 # the gimbal and camera speak from any component
            self._payload.on_message(msg, component)
            return 1
        if component != self._v._autopilot and self._v._autopilot:   # a gimbal, camera or companion computer
            if mtype == "STATUSTEXT":
                self._on_statustext(msg)
            return 1
        if not self._v._v2 and msg.get_msgbuf()[0] == 0xFD and self.config.mavlink_version is None:
            self._v._v2 = True                           # the autopilot's own framing, never another component's
            log.info("vehicle speaks MAVLink 2: following it")
        if mtype in TELEMETRY:
            self.latest[mtype] = msg                 # folded once per read, see ingest()
        else:
            handler = _EVENTS.get(mtype)
            if handler is not None:
                handler(self, msg)
        return 1

    def _on_heartbeat(self, m) -> None:
        if m.autopilot == mavlink.MAV_AUTOPILOT_INVALID:
            return
        store = self._store
        now = self._v.clock()
        self._transport.heard_vehicle()
        self._v._signing_control.settle(self._signing.heartbeat(m))
        view = store.view()
        was_armed = view["armed"]
        changes = fold_heartbeat(view, m)
        store.fields.update(changes)
        self._commands.on_heartbeat(m.custom_mode, changes["armed"], now)
        if changes["armed"] != was_armed:
            self._link.armed_changed(changes["armed"], now)
            self._missions.on_arming(changes["armed"], changes["mode"])
        event = self._link.heartbeat(now)
        if event is None:
            return
        store.set(link=self._link.health(self._v._version))
        self._wake.set()                              # the ticker asks for streams at once
        if event == "recovered":
            self._commands.link_recovered(now)
            store.publish()
            store.add_message_locked(Severity.NOTICE, "Link recovered")
        elif event == "first":
            store.add_message_locked(Severity.INFO, f"Vehicle {self._v._target} connected on {self._v.description}")

    def _on_statustext(self, m) -> None:
        text = m.text.rstrip("\x00").strip() if isinstance(m.text, str) else bytes(m.text).decode("ascii", "replace")
        if text:
            try:
                sev = Severity(m.severity)
            except ValueError:
                sev = Severity.INFO
            self._store.add_message_locked(sev, text, "vehicle")
            if self._prearm.heard(text, self._v.clock()):
                self._store.set(readiness=replace(self._store.view()["readiness"], reasons=self._prearm.reasons))
            self._v._signing_control.settle(self._signing.statustext(text))
            self._missions.on_text(text)
            self._v.logs.on_text(text)                  # 'Disarm for log download'
            autopilot = heard_text(self._store.view()["autopilot"], text)    # the banner: firmware, board
            if autopilot is not None:
                self._store.set(autopilot=autopilot)

    def _on_command_ack(self, m) -> None:
        self._commands.on_ack(m, self._v.clock())
        self._wake.set()

    def _on_autopilot_version(self, m) -> None:
        v = m.flight_sw_version
        major, minor, patch = (v >> 24) & 0xFF, (v >> 16) & 0xFF, (v >> 8) & 0xFF
        self._link.version_known = True
        self._params.ftp_capable = bool(m.capabilities & mavlink.MAV_PROTOCOL_CAPABILITY_FTP)
        self._missions.on_autopilot_version(m)
        self._store.set(autopilot=heard_version(self._store.view()["autopilot"], m))
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
        boot = self._store.view()["boot"]
        counted = boot.heard_param_count(m.param_count)
        if counted is not boot:
            self._store.set(boot=counted)
            if counted.restarts != boot.restarts:
                self._restarted()
        self._params.on_param_value(m, name, self._v.clock())
        if self._params.reasking:
            self._wake.set()                          # the next read goes out now, not on the next tick
        self._link.param_received(name)
        self._missions.on_param(name, m.param_value)
        if name in FENCE_PARAMS:
            self._store.set(fence=self._store.view()["fence"].with_param(name, m.param_value))
        elif name == "BATT_CAPACITY":                   # the charge left is reckoned from it (battery.time_left)
            self._store.set(battery=replace(self._store.view()["battery"], capacity_mah=m.param_value or None))
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
            self._params.on_ftp(m, self._v.clock())
            self._v.logs.on_ftp(m)                       # a log read by FTP (driver.logs)
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


#: Events: every one counts (mode/arming changes, the pilot's messages, command answers).
_EVENTS = {
    "HEARTBEAT": Reader._on_heartbeat,
    "STATUSTEXT": Reader._on_statustext,
    "COMMAND_ACK": Reader._on_command_ack,
    "PARAM_VALUE": Reader._on_param_value,
    "AUTOPILOT_VERSION": Reader._on_autopilot_version,
    "FENCE_STATUS": Reader._on_fence_status,
    "FILE_TRANSFER_PROTOCOL": Reader._on_file_transfer_protocol,
    **{name: Reader._on_mission for name in ("MISSION_CURRENT", "MISSION_ITEM_REACHED", "MISSION_REQUEST",
                                              "MISSION_REQUEST_INT", "MISSION_COUNT", "MISSION_ITEM",
                                              "MISSION_ITEM_INT", "MISSION_ACK", "RALLY_POINT")},
    **{name: (lambda r, m: r._v.setup.on_message(m)) for name in SETUP_MESSAGES},
    **{name: (lambda r, m: r._v.logs.on_message(m)) for name in ("LOG_ENTRY", "LOG_DATA")},
}
