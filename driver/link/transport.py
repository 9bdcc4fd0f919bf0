"""Byte transports to the autopilot: live links (any mavutil connection string) and .tlog replay.

A transport only moves bytes. Parsing, health and state live in
:mod:`driver.vehicle.vehicle`. Live transports are opened with pymavlink's
``mavutil.mavlink_connection`` so every connection string MAVProxy accepts works
(``udpin:0.0.0.0:14550``, ``tcp:127.0.0.1:5760``, ``udpout:``, ``/dev/ttyUSB0``).
We read and write raw bytes and never call mavutil's ``recv_msg``: its automatic
MAVLink 2 switch rewrites process-global state.
"""
from __future__ import annotations

import bisect
import logging
import os
import select
import socket
import struct
import threading
import time
from concurrent.futures import Future

log = logging.getLogger(__name__)

MAX_UNSENT = 1 << 16        # bytes a TCP link may hold back before new frames are dropped (whole)


class LinkError(Exception):
    """The transport failed; a reconnectable one may be opened again."""


class Transport:
    description = ""
    reconnectable = False        # TCP and serial: reopen after an error
    is_replay = False

    def open(self) -> None: ...
    def read(self, timeout: float) -> bytes: ...
    def write(self, data: bytes) -> bool: ...           # True when handed to the link (and so logged)
    def close(self) -> None: ...

    # UDP pins itself to the vehicle (see UdpTransport); other links reach only what they connect to
    foreign = 0
    pinned: tuple[str, int] | None = None

    def heard_vehicle(self) -> None:
        """The data just read carried the vehicle's heartbeat."""

    def strangers(self) -> list:
        """Senders ignored for the first time since the last call."""
        return []

    def clock(self) -> float:
        """Time base for link supervision: real time, or the log's time when replaying."""
        return time.monotonic()

    def wall_time(self) -> float:
        """The date of what is heard now (time.time()): now, or when it was recorded for a replay."""
        return time.time()


class MavutilTransport(Transport):
    """Any live pymavlink connection string."""

    def __init__(self, connection: str, baud: int = 57600, source_system: int = 255, source_component: int = 190):
        self.description = connection
        self._connection = connection
        self._baud = baud
        self._ids = (source_system, source_component)
        self._conn = None
        self._sock: socket.socket | None = None     # TCP: used directly (mavtcp prints and swallows EOF)
        kind = connection.split(":", 1)[0]
        self.reconnectable = kind in ("tcp", "tcpin") or ":" not in connection or connection.startswith("/")
        self._lock = threading.Lock()
        self._unsent = bytearray()              # TCP: the tail of a frame the socket did not take yet

    def open(self) -> None:
        from pymavlink import mavutil
        try:
            self._conn = mavutil.mavlink_connection(
                self._connection, baud=self._baud, source_system=self._ids[0], source_component=self._ids[1],
                autoreconnect=False, retries=0, reconnect_delay=0)
        except Exception as exc:          # refused, no such device, bad string
            raise LinkError(f"cannot open {self._connection}: {exc}") from exc
        self._sock = self._conn.port if self._connection.startswith("tcp:") else None

    def read(self, timeout: float) -> bytes:
        conn = self._conn
        if conn is None:
            raise LinkError("not open")
        fd = getattr(conn, "fd", None)
        if fd is not None:
            try:
                ready, _, _ = select.select([fd], [], [], timeout)
            except (OSError, ValueError) as exc:
                raise LinkError(str(exc)) from exc
            if not ready:
                return b""
        try:
            if self._sock is not None:
                data = self._sock.recv(65536)
                if not data:
                    raise LinkError("connection closed by the vehicle")
                return data
            data = conn.recv(65536) if fd is not None else conn.recv()
        except LinkError:
            raise
        except BlockingIOError:
            return b""
        except Exception as exc:
            raise LinkError(str(exc)) from exc
        if fd is None and not data:
            time.sleep(min(timeout, 0.01))    # transports without a file descriptor (rare): poll gently
        return bytes(data) if data else b""

    def write(self, data: bytes) -> bool:
        conn = self._conn
        if conn is None:
            return False
        with self._lock:
            try:
                if self._sock is not None:
                    return self._send_whole(self._sock, data)
                conn.write(data)
                return True
            except BlockingIOError:
                log.debug("link busy, dropped %d bytes", len(data))
            except Exception as exc:
                log.debug("write failed: %s", exc)
        return False

    def _send_whole(self, sock: socket.socket, frame: bytes) -> bool:
        """TCP: whole frames or nothing. pymavlink's socket is non-blocking, so ``sendall`` could leave half a
        frame on the wire when the buffer fills; the unsent tail waits here and goes out first next time,
        and a frame that does not fit is dropped whole (caller holds _lock)."""
        if len(self._unsent) + len(frame) > MAX_UNSENT:
            log.debug("link busy, dropped a %d-byte frame", len(frame))
            accepted = False
        else:
            self._unsent += frame
            accepted = True
        if self._unsent:
            try:
                del self._unsent[:sock.send(self._unsent)]
            except (BlockingIOError, InterruptedError):
                pass
        return accepted

    def close(self) -> None:
        self._unsent = bytearray()
        conn, self._conn, self._sock = self._conn, None, None
        if conn is not None:
            try:
                conn.close()
            except Exception:
                pass


Address = tuple[str, int]


def parse_sender(text: str) -> tuple[str, int | None]:
    """"10.1.1.1" or "10.1.1.1:14550" → (ip, port or None); names are resolved once, here."""
    host, sep, port = text.strip().rpartition(":")
    if not sep:
        host, port = text.strip(), ""
    if port and not port.isdigit():
        raise ValueError(f"{text!r}: expected ADDRESS or ADDRESS:PORT")
    try:
        ip = socket.gethostbyname(host)
    except OSError as exc:
        raise ValueError(f"{text!r}: cannot resolve {host}") from exc
    return ip, int(port) if port else None


class UdpTransport(Transport):
    """UDP pinned to the vehicle: pymavlink's ``mavudp`` takes datagrams from anyone and sends every frame to
    every address that ever sent one, so a laptop on the same Wi-Fi would receive our commands and could
    speak for the vehicle. Here, once the vehicle is heard (:meth:`heard_vehicle`), datagrams from other
    addresses are dropped and counted (``foreign``) and frames go to the vehicle's address only.

    ``allowed`` names other senders whose datagrams are read (the Solo's controller, a second ground
    station); they never receive our frames. ``udpout:`` is pinned to its destination from the start. If the
    pinned vehicle falls silent for ``repin_after`` seconds (it rebooted onto another source port), the
    same IP may take the pin again with its next heartbeat; any other address never can.
    """

    def __init__(self, connection: str, allowed: tuple[str, ...] = (), repin_after: float = 3.5):
        self.description = connection
        scheme, _, rest = connection.partition(":")
        host, _, port = rest.rpartition(":")
        self._listen = scheme.lower() in ("udp", "udpin")
        self._address: Address = (host, int(port))
        self._allowed = [parse_sender(a) for a in allowed]
        self._repin_after = repin_after
        self._sock: socket.socket | None = None
        self.pinned: Address | None = None
        self.last_source: Address | None = None
        self._pinned_heard = 0.0
        self.foreign = 0                                  # datagrams dropped from strangers
        self._strangers: list[Address] = []               # each new one, for the pilot (read by the driver)

    def open(self) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            if self._listen:
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
                sock.bind(self._address)
            else:
                self.pinned = (socket.gethostbyname(self._address[0]), self._address[1])
            sock.setblocking(False)
        except OSError as exc:
            sock.close()
            raise LinkError(f"cannot open {self.description}: {exc.strerror or exc}") from exc
        self._sock = sock

    def _accepts(self, source: Address, now: float) -> bool:
        pinned = self.pinned
        if pinned is None or source == pinned:
            return True
        if any(ip == source[0] and port in (None, source[1]) for ip, port in self._allowed):
            return True
        return (self._listen and source[0] == pinned[0] and now - self._pinned_heard > self._repin_after)

    def read(self, timeout: float) -> bytes:
        sock = self._sock
        if sock is None:
            raise LinkError("not open")
        deadline = time.monotonic() + timeout
        while True:
            try:
                ready, _, _ = select.select([sock], [], [], max(0.0, deadline - time.monotonic()))
            except (OSError, ValueError) as exc:
                raise LinkError(str(exc)) from exc
            if not ready:
                return b""
            try:
                data, source = sock.recvfrom(65536)
            except (BlockingIOError, ConnectionRefusedError):   # ICMP refused from an earlier send
                continue
            except OSError as exc:
                raise LinkError(str(exc)) from exc
            now = time.monotonic()
            if self._accepts(source, now):
                self.last_source = source
                if source == self.pinned:
                    self._pinned_heard = now
                return data
            self.foreign += 1
            if source not in self._strangers and len(self._strangers) < 64:
                self._strangers.append(source)

    def heard_vehicle(self) -> None:
        """The datagram just read carried the vehicle's heartbeat: pin (or re-pin) its sender."""
        source = self.last_source
        if source is not None and source != self.pinned and self._listen:
            if self.pinned is None or self._accepts(source, time.monotonic()):
                log.info("vehicle link pinned to %s:%d", *source)
                self.pinned = source
        if source == self.pinned:
            self._pinned_heard = time.monotonic()

    def strangers(self) -> list[Address]:
        """Senders dropped for the first time since the last call."""
        out, self._strangers = self._strangers, []
        return out

    def write(self, data: bytes) -> bool:
        sock, target = self._sock, self.pinned
        if sock is None or target is None:              # nobody to speak to until the vehicle is heard
            return False
        try:
            sock.sendto(data, target)
            return True
        except OSError as exc:                          # buffer full, unreachable: a lost datagram
            log.debug("udp send failed: %s", exc)
            return False

    def close(self) -> None:
        sock, self._sock = self._sock, None
        if sock is not None:
            sock.close()
        if self._listen:
            self.pinned = None


def frame_length(buf: bytes | bytearray, offset: int) -> int:
    """Length of the MAVLink frame starting at ``offset`` (0 if not a frame start)."""
    magic = buf[offset]
    if magic == 0xFE and offset + 1 < len(buf):
        return 6 + buf[offset + 1] + 2
    if magic == 0xFD and offset + 2 < len(buf):
        return 10 + buf[offset + 1] + 2 + (13 if buf[offset + 2] & 0x01 else 0)
    return 0


def _message_id(frame: bytes) -> int:
    """The message id of a whole MAVLink 1 or 2 frame."""
    return frame[5] if frame[0] == 0xFE else frame[7] | frame[8] << 8 | frame[9] << 16


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


NETWORK_SCHEMES = ("udp", "udpin", "udpout", "udpbcast", "tcp", "tcpin")
OTHER_SCHEMES = ("ws", "wss", "wsserver", "mcast")      # pymavlink takes these too; checked by it


def connection_problem(connection: str) -> str | None:
    """Why ``connection`` cannot be a link, in a line for the user; None when it may be one.

    Network strings need SCHEME:HOST:PORT; a .tlog must exist; a serial device is a path (/dev/...) or a
    Windows COM port, and may be missing for now: a USB radio can be plugged in later and the link retries.
    """
    text = connection.strip()
    usage = "a link is udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT, a serial device such as " \
            "/dev/ttyUSB0, or a .tlog file"
    if not text:
        return "empty connection string: " + usage
    scheme, colon, rest = text.partition(":")
    if colon and scheme.lower() in NETWORK_SCHEMES:
        host, colon2, port = rest.rpartition(":")
        if not colon2 or not host:
            return f"{text!r}: {scheme} needs HOST:PORT"
        if not port.isdigit() or not 0 < int(port) < 65536:
            return f"{text!r}: the port must be a number from 1 to 65535"
        return None
    if colon and scheme.lower() in OTHER_SCHEMES:
        return None
    if text.lower().endswith(".tlog"):
        return None if os.path.isfile(text) else f"no such flight log: {text}"
    device = text.split(",")[0]
    if device.startswith("/dev/") or os.path.exists(device) or \
            (device.upper().startswith("COM") and device[3:].isdigit()):
        return None
    return f"{text!r} is not a connection string: {usage}"


def open_transport(connection: str, baud: int = 57600, source_system: int = 255, source_component: int = 190,
                   replay_speed: float = 1.0, allowed: tuple[str, ...] = ()) -> Transport:
    if connection.lower().endswith(".tlog") and os.path.isfile(connection):
        return TlogReplay(connection, replay_speed)
    if connection.split(":", 1)[0].lower() in ("udp", "udpin", "udpout"):
        return UdpTransport(connection, allowed)
    return MavutilTransport(connection, baud, source_system, source_component)
