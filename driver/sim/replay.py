"""A replay vehicle: a real ArduCopter's recording (a MAVProxy .tlog) answering a ground station over TCP.

The simulator answers as we believed ArduPilot answers; this answers as ArduPilot did. A recording is split into

* the vehicle's own telemetry (HEARTBEAT, ATTITUDE, SYS_STATUS, ...), replayed on its recorded timeline (looped,
  so a link stays up for as long as a test needs it; what it said once before any request, the boot's texts and
  parameters, is said in the first lap only), and
* exchanges: each ground station request (system 255: PARAM_*, MISSION_*, COMMAND_LONG, FILE_TRANSFER_PROTOCOL,
  LOG_*, ...) with the vehicle's answers to it (COMMAND_ACK, PARAM_VALUE, MISSION_*, FTP replies, STATUSTEXT,
  ...), each at its delay after the request. An answer belongs to the latest earlier request it can answer (an
  ACK to its command, a PARAM_VALUE to its name or index or to the list, an FTP reply to its request's seq, a
  mission item to its request): a late ACK sent after the next request went out stays with its own command.

A request from the live ground station is matched to an exchange by a normalised key (:func:`request_key`: the
message type and the fields that carry meaning, never seq numbers, target ids or retry counters), the first
unused exchange with that key in recorded order; its answers go out with their recorded delays (divided by
``speedup``), re-encoded with the few volatile fields that must answer *this* request rewritten
(:func:`rewrite`: target ids, the FTP seq and session, a COMMAND_ACK's command where an equivalent request was
recorded). Nothing is invented: a request without a recorded match gets no answer (as ArduPilot does for an
unknown parameter name) and lands in :attr:`ReplayVehicle.unanswered`, so a test can say what went unanswered.

Importable without Qt. ``python -m driver.sim.replay RECORDING.tlog --tcp 5760`` serves one.
"""
from __future__ import annotations

import argparse
import copy
import heapq
import logging
import math
import signal
import struct
import threading
import time
from dataclasses import dataclass, field
from functools import lru_cache

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .faults import Faults
from .server import LinkServer
from .vehicle import SimConfig

log = logging.getLogger(__name__)

__all__ = ["read_tlog", "request_key", "rewrite", "Exchange", "Recording", "Request", "ReplayVehicle"]

GCS_SYSTEM = 255
#: What the vehicle sends only in answer to something (everything else it sends is telemetry).
ANSWER_TYPES = frozenset({
    "COMMAND_ACK", "PARAM_VALUE", "MISSION_COUNT", "MISSION_ITEM", "MISSION_ITEM_INT", "MISSION_REQUEST",
    "MISSION_REQUEST_INT", "MISSION_ACK", "FILE_TRANSFER_PROTOCOL", "STATUSTEXT", "LOG_ENTRY", "LOG_DATA",
    "AUTOPILOT_VERSION", "COMMAND_LONG", "MAG_CAL_REPORT", "CAMERA_INFORMATION", "GIMBAL_MANAGER_INFORMATION",
    "GIMBAL_DEVICE_INFORMATION", "MESSAGE_INTERVAL", "RALLY_POINT", "FENCE_POINT"})
#: What a ground station sends that asks for no answer: its keep-alive and the streams of setpoints and sticks.
NOT_REQUESTS = frozenset({"HEARTBEAT", "MANUAL_CONTROL", "RC_CHANNELS_OVERRIDE", "SET_POSITION_TARGET_LOCAL_NED",
                          "SET_POSITION_TARGET_GLOBAL_INT", "SET_ATTITUDE_TARGET", "GPS_RTCM_DATA"})
FTP_HEADER = struct.Struct("<HBBBBBBI")          # seq, session, opcode, size, req_opcode, burst_complete, pad, offset
FTP_PATH_OPCODES = frozenset({3, 4, 6, 7, 8, 9, 10, 12, 13, 14})   # list, open, create, remove, ...: data is a path
REASKS = frozenset({"MISSION_REQUEST", "MISSION_REQUEST_INT"})
LOOKBACK = 200                                   # requests searched back for the one an answer belongs to


# -- reading a recording ---------------------------------------------------------------------------------------
def read_tlog(path: str) -> list[tuple[float, object]]:
    """(seconds from the first frame, message) for every frame of a MAVProxy .tlog (8-byte big-endian µs stamp,
    then the frame). pymavlink's MAVLink 2 codec, fed frame by frame: no process-wide mavutil dialect switch."""
    with open(path, "rb") as f:
        data = f.read()
    codec = mavlink.MAVLink(None)
    codec.robust_parsing = True
    out, i, first = [], 0, None
    while i + 10 <= len(data):
        stamp = struct.unpack(">Q", data[i:i + 8])[0] / 1e6
        i += 8
        magic, length = data[i], data[i + 1]
        size = length + 8 if magic == mavlink.PROTOCOL_MARKER_V1 else length + 12 + (13 if data[i + 2] & 1 else 0)
        first = stamp if first is None else first
        for msg in codec.parse_buffer(data[i:i + size]) or []:
            if msg.get_type() != "BAD_DATA":
                out.append((stamp - first, msg))
        i += size
    return out


def _f32(value: float):
    """A float as float32 carries it (the wire's precision); NaN as the text "nan" (NaN != NaN)."""
    value = struct.unpack("<f", struct.pack("<f", value))[0]
    return "nan" if math.isnan(value) else value


def _name(raw) -> str:
    text = raw if isinstance(raw, str) else bytes(raw).decode("ascii", "replace")
    return text.split("\x00", 1)[0]


def _ftp(m) -> tuple[int, int, int, int, int, int, bytes]:
    """(seq, session, opcode, size, req_opcode, offset, data) of a FILE_TRANSFER_PROTOCOL payload."""
    payload = bytes(m.payload)
    seq, session, opcode, size, req_opcode, _burst, _pad, offset = FTP_HEADER.unpack(payload[:12])
    return seq, session, opcode, size, req_opcode, offset, payload[12:12 + size]


def request_key(m) -> tuple:
    """What a request means, without what changes from one ground station or one try to the next (seq numbers,
    target ids, COMMAND_LONG's confirmation counter, the FTP session): two requests with the same key get the
    same answer from the vehicle."""
    t = m.get_type()
    kind = getattr(m, "mission_type", 0)
    if t == "PARAM_REQUEST_LIST":
        return (t,)
    if t == "PARAM_REQUEST_READ":                # ArduPilot reads by name when the index is -1
        return (t, m.param_index) if m.param_index >= 0 else (t, _name(m.param_id))
    if t == "PARAM_SET":                         # the type is the sender's guess: ArduPilot casts to its own
        return (t, _name(m.param_id), _f32(m.param_value))
    if t == "MISSION_COUNT":
        return (t, kind, m.count)
    if t in ("MISSION_ITEM", "MISSION_ITEM_INT", "MISSION_REQUEST", "MISSION_REQUEST_INT"):
        return (t, kind, m.seq)                  # an item's content is compared by the test, not here
    if t in ("MISSION_REQUEST_LIST", "MISSION_CLEAR_ALL"):
        return (t, kind)
    if t == "MISSION_ACK":
        return (t, kind, m.type)
    if t in ("COMMAND_LONG", "COMMAND_INT"):
        params = [m.param1, m.param2, m.param3, m.param4]
        if t == "COMMAND_LONG":
            params += [m.param5, m.param6, m.param7]
        else:
            params += [m.frame, m.x, m.y, m.z]
        params = [_f32(p) for p in params]
        if m.command == mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW and "nan" not in params[:2]:
            params[2] = params[3] = None         # AP_Mount: angles given, the rates are not read
        return (t, m.command, *params)
    if t == "FILE_TRANSFER_PROTOCOL":
        _seq, _session, opcode, size, _req, offset, data = _ftp(m)
        return (t, opcode, offset, size, data if opcode in FTP_PATH_OPCODES else b"")
    fields = tuple(_f32(v) if isinstance(v, float) else (tuple(v) if isinstance(v, list) else v)
                   for name, v in ((n, getattr(m, n)) for n in m.get_fieldnames())
                   if name not in ("target_system", "target_component"))
    return (t, *fields)


def _asks_for_int(m) -> bool:
    return m.get_type() == "STATUSTEXT" and "MISSION_ITEM_INT" in m.text


#: Requests ArduPilot answers the same way as another, recorded one: (live key) -> [(recorded key, what only the
#: recorded form brought)]. MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES (p1 = 1) and REQUEST_MESSAGE AUTOPILOT_VERSION
#: both queue AUTOPILOT_VERSION and ACK ACCEPTED (GCS_Common.cpp); a MISSION_ITEM_INT is taken as the legacy
#: MISSION_ITEM of the same seq is, less the "got MISSION_ITEM; GCS should send MISSION_ITEM_INT" the float form
#: brought (it goes out a few ms later, so the recording has it among the next item's answers).
def alternates(key: tuple) -> list[tuple[tuple, object]]:
    if key[:3] == ("COMMAND_LONG", mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1.0):
        return [(("COMMAND_LONG", mavlink.MAV_CMD_REQUEST_MESSAGE, float(mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION),
                  0.0, 0.0, 0.0, 0.0, 0.0, 0.0), None)]
    if key[0] == "MISSION_ITEM_INT":
        return [(("MISSION_ITEM", *key[1:]), _asks_for_int)]
    return []


WITHHOLD_EXCHANGES = 2          # an alternate's own answers are left out of this many exchanges (its own and next)


def belongs(request, answer) -> bool:
    """Whether ``answer`` (from the vehicle) can be the vehicle's answer to ``request`` (from the ground station)."""
    a, r = answer.get_type(), request.get_type()
    if a == "COMMAND_ACK":
        return r in ("COMMAND_LONG", "COMMAND_INT") and request.command == answer.command
    if a == "PARAM_VALUE":
        if r == "PARAM_REQUEST_LIST":
            return answer.param_index < answer.param_count
        if r == "PARAM_SET":
            return _name(request.param_id) == _name(answer.param_id)
        if r == "PARAM_REQUEST_READ":
            return (answer.param_index == request.param_index if request.param_index >= 0
                    else _name(request.param_id) == _name(answer.param_id))
        return False
    if a.startswith("MISSION_"):
        if not r.startswith("MISSION_") or getattr(request, "mission_type", 0) != getattr(answer, "mission_type", 0):
            return False
        if a in ("MISSION_REQUEST", "MISSION_REQUEST_INT"):      # the vehicle leads an upload
            return r in ("MISSION_COUNT", "MISSION_ITEM", "MISSION_ITEM_INT")
        if a == "MISSION_COUNT":
            return r == "MISSION_REQUEST_LIST"
        if a in ("MISSION_ITEM", "MISSION_ITEM_INT"):
            return r in ("MISSION_REQUEST", "MISSION_REQUEST_INT") and request.seq == answer.seq
        return r != "MISSION_ACK"                                # MISSION_ACK: the latest of its transfer
    if a == "FILE_TRANSFER_PROTOCOL":
        if r != a:
            return False
        reply, asked = _ftp(answer), _ftp(request)
        return reply[4] == asked[2] and 0 <= (reply[0] - asked[0] - 1) & 0xFFFF < 1000
    if a == "LOG_ENTRY":
        return r == "LOG_REQUEST_LIST"
    if a == "LOG_DATA":
        return r == "LOG_REQUEST_DATA" and request.id == answer.id
    if a == "AUTOPILOT_VERSION":
        return r == "COMMAND_LONG" and request.command in (mavlink.MAV_CMD_REQUEST_MESSAGE,
                                                           mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES)
    return False


@dataclass
class Exchange:
    """One recorded request and the vehicle's answers to it: (seconds after the request, message, MAVLink version)."""
    index: int
    t: float
    request: object
    key: tuple
    answers: list = field(default_factory=list)


STATE_SHOWN_WITHIN = 3.0        # s after an accepted arm or mode change its heartbeat showed it


def _with_state_shown(exchanges: list, telemetry: list) -> None:
    """An accepted arm, disarm or mode change is answered by its ACK *and* by the autopilot's next heartbeat
    showing it, as the vehicle sent them: a ground station confirms those by the heartbeat, and the looped
    telemetry cannot be in step with a live request."""
    beats = [(t, m, v) for t, m, v in telemetry if m.get_type() == "HEARTBEAT" and m.get_srcComponent() == 1]
    for ex in exchanges:
        r = ex.request
        if r.get_type() != "COMMAND_LONG" or r.command not in (mavlink.MAV_CMD_COMPONENT_ARM_DISARM,
                                                               mavlink.MAV_CMD_DO_SET_MODE):
            continue
        acks = [(dt, m) for dt, m, _ in ex.answers if m.get_type() == "COMMAND_ACK"
                and m.result == mavlink.MAV_RESULT_ACCEPTED]
        if not acks:
            continue
        after = ex.t + acks[0][0]
        for t, m, v in beats:
            if after <= t <= after + STATE_SHOWN_WITHIN and (
                    (r.command == mavlink.MAV_CMD_DO_SET_MODE and m.custom_mode == int(r.param2)) or
                    (r.command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM and
                     bool(m.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED) == (r.param1 >= 0.5))):
                ex.answers.append((t - ex.t, m, v))
                break


@dataclass
class Recording:
    """A .tlog split into telemetry (t, message, version) and exchanges, in recorded order."""
    path: str
    telemetry: list
    exchanges: list
    duration: float

    @staticmethod
    @lru_cache(maxsize=8)
    def load(path: str) -> "Recording":
        frames = read_tlog(path)
        telemetry, exchanges = [], []
        for t, msg in frames:
            version = 2 if msg.get_msgbuf()[0] == mavlink.PROTOCOL_MARKER_V2 else 1
            if msg.get_srcSystem() == GCS_SYSTEM:
                if msg.get_type() not in NOT_REQUESTS:
                    exchanges.append(Exchange(len(exchanges), t, msg, request_key(msg)))
                continue
            if msg.get_type() not in ANSWER_TYPES or not exchanges:
                telemetry.append((t, msg, version))
                continue
            owner = next((ex for ex in reversed(exchanges[-LOOKBACK:]) if belongs(ex.request, msg)), exchanges[-1])
            owner.answers.append((t - owner.t, msg, version))
        _with_state_shown(exchanges, telemetry)
        return Recording(path, telemetry, exchanges, frames[-1][0] if frames else 0.0)

    def exchanges_of(self, mtype: str) -> list[Exchange]:
        return [ex for ex in self.exchanges if ex.request.get_type() == mtype]


def rewrite(answer, live, recorded):
    """A copy of the recorded ``answer`` to the ``recorded`` request that answers the ``live`` one instead: its
    target ids, a COMMAND_ACK's command (an equivalent request), an FTP reply's seq (the same distance from the
    request's seq: request + 1, counting up in a burst) and session."""
    out = copy.copy(answer)
    for name, source in (("target_system", "get_srcSystem"), ("target_component", "get_srcComponent")):
        if getattr(out, name, 0) and getattr(out, name) == getattr(recorded, source)():
            setattr(out, name, getattr(live, source)())
    if out.get_type() == "COMMAND_ACK" and out.command == getattr(recorded, "command", None):
        out.command = live.command
    if out.get_type() == "FILE_TRANSFER_PROTOCOL":
        payload = list(out.payload)
        seq = (_ftp(live)[0] + FTP_HEADER.unpack(bytes(payload[:12]))[0] - _ftp(recorded)[0]) & 0xFFFF
        payload[0:3] = [seq & 0xFF, seq >> 8, _ftp(live)[1]]
        out.payload = payload
    return out


@dataclass(frozen=True)
class Request:
    """One request the live ground station sent and what the replay made of it."""
    at: float                      # s since the replay started
    type: str
    key: tuple
    answered_by: float | None      # the recorded request's time (s in the recording), None: not answered
    answers: int                   # how many answers went out for it
    why: str                       # for an unanswered one, why; for an equivalent one, which was recorded
    message: object = field(default=None, repr=False, compare=False)   # what the ground station sent
    schedule: tuple = field(default=(), repr=False)   # s after it each answer was due: recorded delay / speedup


class ReplayVehicle:
    """Serves ``recording`` on TCP (``tcp_port`` 0: any free port) at ``speedup`` times the recorded pace.

    ``skip``: windows (start, end) of recorded seconds whose exchanges are not offered (a test takes another part
    of the session); ``telemetry_from``: where in the recording the telemetry starts (and loops back to).
    ``self.faults`` are the simulator's link faults (driver.sim.faults): off unless a test sets them.

    The telemetry runs on its own timeline: a command's ACK is the recorded one, but the mode, arming or mission
    state the vehicle then shows is what the recording shows at that moment of its timeline.
    """

    def __init__(self, recording: str | Recording, tcp_port: int = 0, speedup: float = 1.0,
                 skip: tuple[tuple[float, float], ...] = (), telemetry_from: float = 0.0,
                 host: str = "127.0.0.1") -> None:
        if not speedup > 0:
            raise ValueError("speedup must be positive")
        self.recording = recording if isinstance(recording, Recording) else Recording.load(recording)
        self.speedup = speedup
        self.config = SimConfig(tcp_host=host, tcp_port=tcp_port)
        self.faults = Faults()
        self.server = LinkServer(self.config, self.faults, self._received)
        self._used = {ex.index for ex in self.recording.exchanges if any(a <= ex.t <= b for a, b in skip)}
        self._by_key: dict[tuple, list[Exchange]] = {}
        for ex in self.recording.exchanges:
            if ex.index not in self._used:
                self._by_key.setdefault(ex.key, []).append(ex)
        telemetry = self.recording.telemetry
        self._loop_start = next((i for i, (t, _, _) in enumerate(telemetry) if t >= telemetry_from), len(telemetry))
        self._telemetry_from = telemetry_from
        self._lock = threading.Lock()
        self._queue: list = []                   # heap of (due, order, message, version, peer)
        self._order = 0
        self._withheld: list = []                # [rule, exchanges left]: answers an alternate's live request
                                                 # would not have brought
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._t0 = 0.0
        self.requests: list[Request] = []
        self.sent = 0                            # frames sent (telemetry and answers)

    # -- lifecycle ------------------------------------------------------------------------------------------
    @property
    def tcp_port(self) -> int:
        return self.server.tcp_port

    def start(self) -> "ReplayVehicle":
        self._t0 = time.monotonic()
        self.server.start()
        self._thread = threading.Thread(target=self._run, name="replay-vehicle", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        self.server.stop()

    # -- what a test reads -----------------------------------------------------------------------------------
    @property
    def unanswered(self) -> list[Request]:
        with self._lock:
            return [r for r in self.requests if r.answered_by is None]

    @property
    def pending(self) -> int:
        """Answers scheduled and not sent yet."""
        with self._lock:
            return len(self._queue)

    # -- requests (the link's I/O thread) ------------------------------------------------------------------
    def _received(self, msg, version: int, peer) -> None:
        if msg.get_type() in NOT_REQUESTS:
            return
        now = time.monotonic()
        key = request_key(msg)
        with self._lock:
            found, withhold, why = self._match(key)
            schedule = []
            if found is not None and msg.get_type().startswith("MISSION_"):
                self._drop_reasks(getattr(msg, "mission_type", 0))
            if withhold is not None:
                self._withheld.append([withhold, WITHHOLD_EXCHANGES])
            if found is not None:
                withheld = [rule for rule, _ in self._withheld]
                self._withheld = [[rule, n - 1] for rule, n in self._withheld if n > 1]
                for delay, answer, answer_version in found.answers:
                    if any(rule(answer) for rule in withheld):
                        continue
                    heapq.heappush(self._queue, (now + delay / self.speedup, self._order,
                                                 rewrite(answer, msg, found.request), answer_version, peer))
                    self._order += 1
                    schedule.append(delay / self.speedup)
            self.requests.append(Request(now - self._t0, msg.get_type(), key, None if found is None else found.t,
                                         len(schedule), why, msg, tuple(schedule)))
        if found is None:
            log.info("no recorded answer to %s: %s", key, why)
        self._wake.set()

    def _drop_reasks(self, mission_type: int) -> None:
        """A mission request from the ground station: the vehicle's pending re-asks of that plan are not sent.
        ArduPilot asks for an item again only while it does not come (1 s); the recorded ground station let one
        wait, the live one may answer at once (caller holds the lock)."""
        still_due = [entry for entry in self._queue if entry[2].get_type() not in REASKS
                     or getattr(entry[2], "mission_type", 0) != mission_type]
        if len(still_due) != len(self._queue):
            self._queue = still_due
            heapq.heapify(self._queue)

    def _match(self, key: tuple) -> tuple[Exchange | None, object, str]:
        """The first unused exchange for ``key`` (or an equivalent one), what of its answers and the next exchange's
        to leave out (None: nothing), and a note."""
        for wanted, withhold in [(key, None)] + alternates(key):
            for ex in self._by_key.get(wanted, ()):
                if ex.index not in self._used:
                    self._used.add(ex.index)
                    note = "" if wanted == key else f"as the recorded {ex.request.get_type()} at {ex.t:.3f} s"
                    return ex, withhold, note
        recorded = sum(len(self._by_key.get(k, ())) for k, _ in [(key, None)] + alternates(key))
        return None, None, (f"its {recorded} recorded answer(s) are used up" if recorded
                                   else "not in the recording")

    # -- sending (the replay's own thread) -----------------------------------------------------------------
    def _run(self) -> None:
        telemetry = self.recording.telemetry
        index, lap = self._loop_start, 0
        lap_length = (self.recording.duration - self._telemetry_from) if telemetry else 0.0
        while not self._stop.is_set():
            now = time.monotonic()
            due_next = now + 0.05
            while index < len(telemetry):
                t, msg, version = telemetry[index]
                due = self._t0 + (t - self._telemetry_from + lap * lap_length) / self.speedup
                if due > now:
                    due_next = min(due_next, due)
                    break
                if lap == 0 or msg.get_type() not in ANSWER_TYPES:   # events (boot texts) are said once
                    self._send(msg, version, None)
                index += 1
                if index >= len(telemetry) and lap_length > 0:
                    index, lap = self._loop_start, lap + 1
            with self._lock:
                ready = []
                while self._queue and self._queue[0][0] <= now:
                    ready.append(heapq.heappop(self._queue))
                if self._queue:
                    due_next = min(due_next, self._queue[0][0])
            for _due, _order, msg, version, peer in ready:
                self._send(msg, version, peer)
            self.server.pump()                   # what the link's faults (self.faults) held back
            self._wake.wait(max(0.0, due_next - time.monotonic()))
            self._wake.clear()

    def _send(self, msg, version: int, peer) -> None:
        if peer is not None and peer.closed:
            return
        # a copy: packing sets the message's header, and the recording (cached) is shared
        self.server.broadcast(copy.copy(msg), component=msg.get_srcComponent(), mavlink2=version == 2, to=peer)
        self.sent += 1


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m driver.sim.replay",
                                     description="Serve a real vehicle's recording (.tlog) to a ground station.")
    parser.add_argument("recording", help="a MAVProxy .tlog (tests/data/recordings/*.tlog)")
    parser.add_argument("--tcp", type=int, default=5760, help="TCP port (0: any free port); default 5760")
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--speedup", type=float, default=1.0, help="times the recorded pace")
    parser.add_argument("--telemetry-from", type=float, default=0.0, help="recorded second the telemetry starts at")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    replay = ReplayVehicle(args.recording, args.tcp, args.speedup, telemetry_from=args.telemetry_from,
                           host=args.host).start()
    rec = replay.recording
    log.info("replaying %s (%.0f s, %d exchanges) on tcp:%s:%d", rec.path, rec.duration, len(rec.exchanges),
             args.host, replay.tcp_port)
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    while not stop.wait(1.0):
        pass
    replay.stop()
    log.info("%d requests, %d unanswered", len(replay.requests), len(replay.unanswered))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
