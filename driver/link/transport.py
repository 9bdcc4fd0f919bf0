"""Live byte transports to the autopilot: any mavutil connection string, and UDP pinned to the vehicle.

A transport only moves bytes. Parsing, health and state live in :mod:`driver.vehicle.reader`. Live
transports are opened with pymavlink's ``mavutil.mavlink_connection`` so every connection string MAVProxy
accepts works (``udpin:0.0.0.0:14550``, ``tcp:127.0.0.1:5760``, ``udpout:``, ``/dev/ttyUSB0``). We read and
write raw bytes and never call mavutil's ``recv_msg``: its automatic MAVLink 2 switch rewrites process-global
state. Recorded flights (.tlog) are :mod:`driver.link.tlog`; a connection string is turned into its transport by
:mod:`driver.link.connection`.
"""
from __future__ import annotations

import logging
import select
import socket
import threading
import time

log = logging.getLogger(__name__)

MAX_UNSENT = 1 << 16        # bytes a TCP link may hold back before new frames are dropped (whole)


class LinkError(Exception):
    """The transport failed; a reconnectable one may be opened again."""


class Transport:
    description = ""
    reconnectable = False        # TCP and serial: reopen after an error
    is_replay = False
    byte_stream = False          # TCP and serial: frames may share a write (a datagram carries one frame)

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
        self.byte_stream = self._sock is not None or not isinstance(getattr(self._conn, "port", None), socket.socket)

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
