"""Recorded flights: the telemetry log written as we fly (.tlog, MAVProxy's and QGroundControl's format), and a
.tlog played back as if it were a live link, with the replay bar's controls.
"""
from __future__ import annotations

import bisect
import os
import struct
import threading
import time
from concurrent.futures import Future

from .transport import Transport, frame_length

__all__ = ["TlogWriter", "TlogReplay", "ReplayControl"]


class TlogWriter:
    """Writes the MAVProxy/QGroundControl telemetry log: 8-byte big-endian µs timestamp, then the packet.

    A log that never received a packet (no vehicle answered) is removed on close: no empty files pile up.
    """

    def __init__(self, path: str, append: bool = False):
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        self.path = path
        self._new = not (append and os.path.exists(path))
        self._written = False
        # never through a symbolic link planted at the name (a shared log folder): O_NOFOLLOW
        flags = os.O_WRONLY | os.O_CREAT | (os.O_APPEND if append else os.O_TRUNC) | getattr(os, "O_NOFOLLOW", 0)
        try:
            fd = os.open(path, flags, 0o644)
        except OSError as exc:
            raise OSError(exc.errno, f"cannot write the flight log {path}: {exc.strerror}") from None
        self._file = os.fdopen(fd, "ab" if append else "wb")
        self._lock = threading.Lock()
        self.error = ""                       # why it stopped writing (disk full, ...); the link goes on

    def write(self, packet: bytes, when: float | None = None) -> None:
        stamp = struct.pack(">Q", int((time.time() if when is None else when) * 1e6))
        with self._lock:
            if self._file is not None:
                try:
                    self._file.write(stamp + packet)
                    self._written = True
                except OSError as exc:
                    self.error = f"{self.path}: {exc.strerror or exc}"
                    self._close()

    def flush(self) -> None:
        with self._lock:
            if self._file is not None:
                try:
                    self._file.flush()
                except OSError as exc:
                    self.error = f"{self.path}: {exc.strerror or exc}"
                    self._close()

    def close(self) -> None:
        with self._lock:
            self._close()
            if self._new and not self._written and not self.error:
                try:
                    os.remove(self.path)
                except OSError:
                    pass

    def _close(self) -> None:
        if self._file is not None:
            try:
                self._file.close()
            except OSError:
                pass
            self._file = None


MAX_RECORD_GAP = 86400.0     # s: a record further from the previous one than a day is damage, not a flight
MAX_RECORD_BACK = 60.0       # s a record may stand before the previous one (clock adjustments)


def _records(data: bytes) -> list[tuple[float, bytes]]:
    """(time, frame) of every whole record of a .tlog, resynchronising byte by byte over damage.

    A record counts only when its frame passes pymavlink's CRC check and its time follows the previous
    record's: bytes that merely look like a timestamp and a frame start (a damaged or foreign file) would
    otherwise be played at a made-up time, and one stamped in the future would hold back everything after it.
    """
    from pymavlink.dialects.v20 import ardupilotmega as mavlink
    parser = mavlink.MAVLink(None)
    parser.robust_parsing = True
    records: list[tuple[float, bytes]] = []
    last: float | None = None
    i, n = 0, len(data)
    while i + 9 <= n:
        stamp = struct.unpack_from(">Q", data, i)[0] * 1e-6
        length = frame_length(data, i + 8)
        frame = data[i + 8:i + 8 + length]
        if (length == 0 or i + 8 + length > n
                or (last is not None and not last - MAX_RECORD_BACK <= stamp <= last + MAX_RECORD_GAP)
                or not _whole_frame(parser, frame)):
            i += 1                            # resynchronise on a damaged record
            continue
        records.append((stamp, frame))
        last = stamp
        i += 8 + length
    return records


def _whole_frame(parser, frame: bytes) -> bool:
    parser.buf, parser.buf_index = bytearray(), 0
    try:
        msg = parser.parse_char(frame)
    except Exception:                         # robust parsing reports damage as BAD_DATA, but never trust it
        return False
    return msg is not None and msg.get_type() != "BAD_DATA" and parser.buf_len() == 0


class TlogReplay(Transport):
    """Plays a .tlog back as if it were a live link, at 1x or faster, pausable.

    Packets are released when the replay clock reaches their recorded time; the
    clock stops while paused, so link supervision sees no gap.
    """

    is_replay = True

    def __init__(self, path: str, speed: float = 1.0):
        self.description = f"replay {os.path.basename(path)}"
        self.path = path
        with open(path, "rb") as f:
            data = f.read()
        self._packets = _records(data)
        self._stamps = [stamp for stamp, _ in self._packets]     # for seeking
        self.start_time = self._packets[0][0] if self._packets else 0.0
        self.duration = (self._packets[-1][0] - self.start_time) if self._packets else 0.0
        self._cond = threading.Condition()
        self._speed = max(0.1, min(64.0, float(speed)))
        self._paused = False
        self._index = 0
        self._position = 0.0                  # seconds of log time played
        self._anchor = time.monotonic()       # real time at which _position was last set
        self._closed = False
        self.seeks = 0                        # how many times the pilot moved in it: its clock jumped

    # -- controls (any thread) -------------------------------------------------------------
    @property
    def speed(self) -> float:
        return self._speed

    @speed.setter
    def speed(self, value: float) -> None:
        with self._cond:
            self._rebase()
            self._speed = max(0.1, min(64.0, float(value)))
            self._cond.notify_all()

    @property
    def paused(self) -> bool:
        return self._paused

    def pause(self) -> None:
        with self._cond:
            self._rebase()
            self._paused = True

    def resume(self) -> None:
        with self._cond:
            self._rebase()
            self._paused = False
            self._cond.notify_all()

    @property
    def position(self) -> float:
        with self._cond:
            return self._now()

    @property
    def finished(self) -> bool:
        return self._index >= len(self._packets)

    def seek(self, position: float) -> None:
        """Play on from ``position`` seconds of log time (0: the start again); paused stays paused."""
        with self._cond:
            self._position = max(0.0, min(self.duration, float(position)))
            self._anchor = time.monotonic()
            when = self.start_time + self._position
            self._index = bisect.bisect_left(self._stamps, when) if self._packets else 0
            self.seeks += 1
            self._cond.notify_all()

    def track(self) -> list[tuple[float, float, float]]:
        """(seconds from the start, lat, lon) of every GLOBAL_POSITION_INT with a position: the whole flight,
        for a map's trail. Reads the records already in memory; takes a moment on a long log (call it off the
        UI thread)."""
        from pymavlink.dialects.v20 import ardupilotmega as mavlink
        parser = mavlink.MAVLink(None)
        parser.robust_parsing = True
        out = []
        for stamp, frame in self._packets:
            if _message_id(frame) != mavlink.MAVLINK_MSG_ID_GLOBAL_POSITION_INT:
                continue
            for m in parser.parse_buffer(frame) or ():
                if m.get_type() == "GLOBAL_POSITION_INT" and (m.lat or m.lon):
                    out.append((stamp - self.start_time, m.lat * 1e-7, m.lon * 1e-7))
        return out

    def _now(self) -> float:
        if self._paused:
            return self._position
        return min(self.duration, self._position + (time.monotonic() - self._anchor) * self._speed)

    def _rebase(self) -> None:
        self._position = self._now()
        self._anchor = time.monotonic()

    # -- transport -------------------------------------------------------------------------
    def clock(self) -> float:
        return self.position

    def wall_time(self) -> float:
        return self.start_time + self.position

    def open(self) -> None:
        with self._cond:
            self._position, self._anchor = 0.0, time.monotonic()

    def read(self, timeout: float) -> bytes:
        deadline = time.monotonic() + timeout
        with self._cond:
            while not self._closed:
                if self._index >= len(self._packets):
                    self._cond.wait(max(0.0, deadline - time.monotonic()))
                    return b""
                now = self._now()
                out = bytearray()
                while self._index < len(self._packets) and self._packets[self._index][0] - self.start_time <= now:
                    out += self._packets[self._index][1]
                    self._index += 1
                if out:
                    return bytes(out)
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    return b""
                if self._paused:
                    wait = remaining
                else:
                    due = (self._packets[self._index][0] - self.start_time - now) / self._speed
                    wait = min(remaining, max(0.0005, due))
                self._cond.wait(wait)
        return b""

    def write(self, data: bytes) -> bool:
        """A recording cannot be commanded."""
        return False

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()


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

    def seek(self, position: float) -> None:
        """Jump to ``position`` seconds into the recording; what the vehicle reports from there is shown."""
        self._t.seek(position)

    def restart(self) -> None:
        self._t.seek(0.0)

    def track(self) -> Future:
        """The recording's whole track, (seconds, lat, lon) each, read on a thread of its own."""
        future: Future = Future()

        def read() -> None:
            try:
                future.set_result(self._t.track())
            except Exception as exc:        # noqa: BLE001 - a damaged log: the map shows no trail
                future.set_exception(exc)
        threading.Thread(target=read, name="replay-track", daemon=True).start()
        return future


def _message_id(frame: bytes) -> int:
    """The message id of a whole MAVLink 1 or 2 frame."""
    return frame[5] if frame[0] == 0xFE else frame[7] | frame[8] << 8 | frame[9] << 16
