"""The ticker thread of a :class:`~driver.vehicle.vehicle.Vehicle`, and the one way out to the link.

Every tick it sends the heartbeat, steps the takeoff or mission start, streams the velocity setpoint, and lets
every part that :meth:`Ticker.serve` registered (the command sender, the parameters, the payload, the missions,
setup, the logs, signing) say what it wants sent. All of it is decided under the state lock and written after
releasing it, so a slow serial write stalls nobody. Callers on other threads (the UI) only :meth:`Ticker.post`:
the ticker writes for them.
"""
from __future__ import annotations

import collections
import logging
import math
import threading

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .state import Setpoint, Severity

log = logging.getLogger("driver.vehicle")

__all__ = ["Ticker", "MASK_VELOCITY_YAW_RATE", "MASK_POSITION", "MASK_VELOCITY"]

MASK_VELOCITY_YAW_RATE = 1479      # use vx, vy, vz and yaw rate (arducopter.md)
MASK_POSITION = 3576               # use x, y, z only
MASK_VELOCITY = 3527               # use vx, vy, vz only
YAW_LEAD = 0.5                     # s: old firmware's heading target is this far ahead of a turning nose
YAW_RESEND = 0.2                   # s between those targets
LOG_FLUSH_INTERVAL = 1.0           # s: a crash loses at most this much of the flight log
WRITE_GROUP = 4096                 # bytes of whole frames written at once to a byte-stream link (TCP, serial)


class Ticker:
    """Sends for the vehicle: the outbox, the encoder (signing as configured now) and the periodic work."""

    def __init__(self, *, config, clock, transport, signing, store, link, rules, peer, firmware, sequence, setpoints,
                 tlog, closing, wake, reopen):
        self.config = config
        self._clock = clock
        self._transport, self._signing, self._store = transport, signing, store
        self._lock, self._link, self._rules = store.lock, link, rules
        self._peer, self._firmware, self._sequence, self._setpoints = peer, firmware, sequence, setpoints
        self._tlog = tlog                     # the flight log (driver.link.tlog), None when not recording
        self._tlog_told = False
        self._closing, self._wake, self._reopen = closing, wake, reopen
        self._services: list = []             # every part's (now, state) -> messages, in the order served
        self._codec_out = self.new_encoder()
        self._sender_generation = -1          # the encoder is (re)configured for signing on the next send
        self._tx_lock = threading.Lock()
        self._outbox: collections.deque = collections.deque()   # messages posted by callers, sent by the ticker
        self._yaw_next = 0.0                  # old firmware: next CONDITION_YAW of a held yaw stick
        self._yaw_held = False                # old firmware: the heading is held by CONDITION_YAW
        self._next_heartbeat = self._next_health = -1e9   # due at the first step, whatever the clock's origin
        self._soon: float | None = None       # s: the next tick wanted sooner than the usual wait (tick_within)

    def serve(self, service) -> None:
        """``service(now, state)`` runs every tick with the state lock held and returns the messages its part wants
        sent, after the setpoint and in the order registered (MAVSDK's call-every)."""
        self._services.append(service)

    def send(self, msg) -> None:
        """Pack and write one message; ``bytes`` are a frame packed already (SETUP_SIGNING)."""
        if self._transport.is_replay:
            return
        with self._tx_lock:
            self._write(self._pack(msg))

    def send_all(self, msgs: list) -> None:
        """Pack and write a tick's messages. On a byte stream (TCP, serial) whole frames go out up to WRITE_GROUP
        bytes a write: a log download's gap requests are a thousand small frames a tick, and a write each costs
        the driver and the vehicle a system call and a wake-up per frame. A datagram link keeps a frame a datagram.
        """
        if self._transport.is_replay or not msgs:
            return
        # a frame packed already (SETUP_SIGNING, signed with the key the vehicle has) carries the timestamp of the
        # moment it was made: first, so that nothing packed now with a later one goes out before it (the vehicle
        # would drop it as a replay, and a key's removal was lost so in 1 of 5 loaded runs)
        msgs = [m for m in msgs if isinstance(m, bytes)] + [m for m in msgs if not isinstance(m, bytes)]
        if len(msgs) == 1 or not self._transport.byte_stream:
            for msg in msgs:
                self.send(msg)
            return
        with self._tx_lock:
            group: list[bytes] = []
            size = 0
            for msg in msgs:
                buf = self._pack(msg)
                if size + len(buf) > WRITE_GROUP and group:
                    self._write_group(group)
                    group, size = [], 0
                group.append(buf)
                size += len(buf)
            self._write_group(group)

    def pack(self, msg) -> bytes:
        """One frame as it would go out now (a harness writing it itself)."""
        with self._tx_lock:
            return self._pack(msg)

    def _pack(self, msg) -> bytes:
        """One frame, signed as configured now (caller holds _tx_lock); ``bytes`` are packed already."""
        if isinstance(msg, bytes):
            return msg
        signing, codec = self._signing, self._codec_out
        if self._sender_generation != signing.generation:
            self._sender_generation = signing.generation
            signing.configure_sender(codec, signing.key)
        signing.stamp(codec)
        buf = msg.pack(codec, force_mavlink1=not self._peer.mavlink2)
        codec.seq = (codec.seq + 1) % 256
        signing.note_sent(codec)
        return buf

    def new_encoder(self):
        return mavlink.MAVLink(None, srcSystem=self.config.source_system, srcComponent=self.config.source_component)

    def forward_to_vehicle(self, frame: bytes) -> None:
        with self._tx_lock:
            self._write(frame)

    def post(self, msg) -> None:
        """Send from the ticker thread: callers (the UI among them) never touch the link themselves."""
        self._outbox.append(msg)
        self._wake.set()

    def _write(self, buf: bytes) -> None:
        """Whole frames only, one writer at a time (caller holds _tx_lock)."""
        self._write_group((buf,))

    def _write_group(self, frames) -> None:
        """Frames in one write, all or none (caller holds _tx_lock); the .tlog keeps a record per frame of what
        really went out."""
        if self._transport.write(frames[0] if len(frames) == 1 else b"".join(frames)) and self._tlog is not None:
            for frame in frames:
                self._tlog.write(frame)

    def heartbeat_message(self):
        return mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0,
                                                 mavlink.MAV_STATE_ACTIVE, 3)

    def setpoint_message(self, sp: Setpoint):
        system, component = self._peer.target()
        return mavlink.MAVLink_set_position_target_local_ned_message(
            0, system, component, mavlink.MAV_FRAME_BODY_OFFSET_NED,
            MASK_VELOCITY_YAW_RATE, 0, 0, 0, sp.forward, sp.right, -sp.up, 0, 0, 0, 0, sp.yaw_rate)

    def _legacy_setpoint_messages(self, sp: Setpoint, now: float) -> list:
        """Firmware before ArduCopter 3.5 (the stock Solo) reads neither the frame nor the yaw rate of
        SET_POSITION_TARGET_LOCAL_NED ("for future use" in its GCS_Mavlink): body velocities are turned to
        north/east here, with the heading the vehicle reports, and the nose is steered with CONDITION_YAW
        heading targets a little ahead of it (else the vehicle turns its nose to the direction of travel)."""
        system, component = self._peer.target()
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

    def step(self, now: float) -> list:
        """What is due at ``now`` (the vehicle's clock): the heartbeat, what callers posted, the takeoff's step,
        the setpoint, every part's sends and, every 100 ms, supervision; decided under the state lock, sent by the
        caller (:meth:`run`, or a test through ``Vehicle.step``)."""
        out: list = []
        try:
            if now >= self._next_heartbeat:
                self._next_heartbeat = now + self.config.heartbeat_interval
                out.append(self.heartbeat_message())
            while self._outbox:
                out.append(self._outbox.popleft())
            with self._lock:
                self._sequence.step(now)
                out += self._stream_setpoint(now)
                for service in self._services:
                    out += service(now, self._store.state)
                if now >= self._next_health:
                    self._next_health = now + 0.1
                    out += self._supervise(now)
                out = self._screen(out, now)
        except Exception:                             # heartbeat, setpoints and deadman must outlive any bug
            log.exception("ticker step failed")
            with self._lock:                          # what was gathered still passes the rules, or only the heartbeat
                try:
                    out = self._rules.screen(out, self._store.state, now)
                except Exception:
                    log.exception("flight rules failed: only the heartbeat goes out")
                    out = [m for m in out if not isinstance(m, bytes) and m.get_type() == "HEARTBEAT"]
        return out

    def _screen(self, out: list, now: float) -> list:
        """Every message of the tick through the flight rules (lock held), and the rules' view of the vehicle
        published: nothing leaves the driver without passing here (driver.vehicle.safety)."""
        state = self._store.state
        out = self._rules.screen(out, state, now)
        if self._rules.airborne.lifted != state.lifted:
            self._store.set(lifted=self._rules.airborne.lifted)
            self._store.publish()
        return out

    def tick_within(self, seconds: float) -> None:
        """A part wants the next tick this soon, with or without news from the link (a paced log download);
        called during a step, it holds for the wait after it."""
        self._soon = seconds if self._soon is None else min(self._soon, seconds)

    def run(self) -> None:
        next_flush = 0.0
        while not self._closing.is_set():
            now = self._clock()
            self._soon = None
            self.send_all(self.step(now))             # outside the lock: a slow link stalls nobody else
            if self._tlog is not None and now >= next_flush:
                next_flush = now + LOG_FLUSH_INTERVAL
                self._tlog.flush()
            wait = min(0.05, 1.0 / self.config.setpoint_rate)
            self._wake.wait(wait if self._soon is None else min(wait, self._soon))
            self._wake.clear()

    def _supervise(self, now: float) -> list:
        """Link health, loss, log failures and requests to the vehicle; republishes every 100 ms."""
        store = self._store
        version = self._peer.version
        if self._tlog is not None and self._tlog.error and not self._tlog_told:
            self._tlog_told = True                    # (the writer stopped itself: it writes nothing more)
            store.add_message_locked(Severity.WARNING, f"Flight log stopped: {self._tlog.error}")
        out, event, reopen = self._link.tick(now)
        if reopen:
            self._reopen()
        store.set(link=self._link.health(version), signing=self._signing.snapshot(version))
        for ip, port in self._transport.strangers():
            store.add_message_locked(Severity.WARNING, f"Ignored MAVLink from {ip}:{port}: the link is pinned to the "
                                     f"vehicle at {self._link.health(version).pinned_to} (--allow {ip} "
                                     "accepts that sender)")
        store.publish()
        if event == "lost":
            age = self._link.health(version).heartbeat_age or 0.0
            store.add_message_locked(Severity.CRITICAL, f"Link lost: no heartbeat for {age:.1f} s")
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
        if self._firmware.body_frame_velocity is False:
            return self._legacy_setpoint_messages(sp, now)
        return [self.setpoint_message(sp)]
