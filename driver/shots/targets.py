"""Where the follow target is: a position source the shot reads the newest fix from.

* :class:`StreamTarget` reads a GPS on the laptop or the companion computer: NMEA 0183 sentences (GGA for place,
  altitude and fix quality, RMC for speed and course; checksums checked) over a serial port, UDP or TCP, or
  gpsd's JSON protocol (``?WATCH={"enable":true,"json":true}``, TPV reports) over TCP.
* :class:`GivenTarget` takes positions given through the API (an Ice client sending its own position).

Each fix is stamped with the receiving clock (the driver's, passed in), so its age is measured the same way as
the shot's. A fix without a velocity gets one from the last two places. Sources are named by a URL:
``nmea+udp://:10110`` (listen), ``nmea+tcp://host:port``, ``nmea+serial:///dev/ttyUSB0?baud=4800``,
``gpsd://host:2947`` (gpsd's port by default).
"""
from __future__ import annotations

import json
import logging
import math
import socket
import threading
import time
from dataclasses import dataclass, replace
from urllib.parse import parse_qs, urlparse

from ..core import frames

log = logging.getLogger(__name__)

__all__ = ["TargetFix", "TargetSource", "GivenTarget", "StreamTarget", "open_target", "parse_nmea", "parse_gpsd",
           "nmea_sentence"]

KNOT = 0.514444              # m/s
GPSD_PORT = 2947


@dataclass(frozen=True)
class TargetFix:
    time: float                  # the receiving clock, s
    lat: float
    lon: float
    alt: float | None            # m above mean sea level; None: not told
    vn: float = 0.0              # m/s north
    ve: float = 0.0
    vd: float = 0.0              # m/s down
    has_velocity: bool = False
    source: str = ""

    def finite(self) -> bool:
        return frames.finite(self.time, self.lat, self.lon, self.vn, self.ve, self.vd) and \
            -90 <= self.lat <= 90 and -180 <= self.lon <= 180 and (self.alt is None or frames.finite(self.alt))


def _checksum_ok(line: str) -> bool:
    if "*" not in line:
        return False
    body, _, given = line[1:].partition("*")
    total = 0
    for ch in body:
        total ^= ord(ch)
    try:
        return total == int(given[:2], 16)
    except ValueError:
        return False


def nmea_sentence(body: str) -> str:
    """``$body*CS``: a sentence with its checksum (for tests and simulated sources)."""
    total = 0
    for ch in body:
        total ^= ord(ch)
    return f"${body}*{total:02X}"


def _degrees(value: str, hemi: str) -> float:
    if not value:
        raise ValueError("empty")
    dot = value.index(".") if "." in value else len(value)
    deg = float(value[:dot - 2]) + float(value[dot - 2:]) / 60.0
    return -deg if hemi in ("S", "W") else deg


def parse_nmea(line: str) -> dict | None:
    """The fields of a GGA or RMC sentence with a fix ({"lat", "lon", and "alt" or "speed"/"course"}), else None."""
    line = line.strip()
    if not line.startswith("$") or not _checksum_ok(line):
        return None
    f = line[1:line.index("*")].split(",")
    kind = f[0][2:] if len(f[0]) == 5 else f[0]
    try:
        if kind == "GGA" and len(f) >= 10:
            if f[6] in ("", "0"):
                return None                              # no fix
            return {"lat": _degrees(f[2], f[3]), "lon": _degrees(f[4], f[5]),
                    "alt": float(f[9]) if f[9] else None}
        if kind == "RMC" and len(f) >= 9:
            if f[2] != "A":
                return None                              # void
            out = {"lat": _degrees(f[3], f[4]), "lon": _degrees(f[5], f[6])}
            if f[7] and f[8]:
                out["speed"], out["course"] = float(f[7]) * KNOT, float(f[8])
            return out
    except ValueError:
        return None
    return None


def parse_gpsd(line: str) -> dict | None:
    """The fields of a gpsd TPV report with a 2D or 3D fix, else None."""
    try:
        report = json.loads(line)
    except (json.JSONDecodeError, UnicodeDecodeError):
        return None
    if not isinstance(report, dict) or report.get("class") != "TPV" or report.get("mode", 0) < 2:
        return None
    try:
        out = {"lat": float(report["lat"]), "lon": float(report["lon"])}
    except (KeyError, TypeError, ValueError):
        return None
    alt = report.get("altMSL", report.get("alt"))
    out["alt"] = float(alt) if isinstance(alt, (int, float)) else None
    if isinstance(report.get("speed"), (int, float)) and isinstance(report.get("track"), (int, float)):
        out["speed"], out["course"] = float(report["speed"]), float(report["track"])
    if isinstance(report.get("climb"), (int, float)):
        out["climb"] = float(report["climb"])
    return out


class TargetSource:
    """The newest fix of a target; thread-safe."""

    def __init__(self, clock=time.monotonic, name: str = "target"):
        self.clock, self.name = clock, name
        self._lock = threading.Lock()
        self._fix: TargetFix | None = None
        self._alt: float | None = None
        self.problem = ""                                # why no fixes come (a closed port, a refused connection)

    def latest(self) -> TargetFix | None:
        return self._fix

    def _update(self, fields: dict) -> None:
        """Fold a sentence's or report's fields into a new fix (the caller's thread)."""
        now = self.clock()
        with self._lock:
            old = self._fix
            alt = fields.get("alt", self._alt)
            self._alt = alt if alt is not None else self._alt
            fix = TargetFix(now, fields["lat"], fields["lon"], self._alt, source=self.name)
            if "speed" in fields:
                c = math.radians(fields["course"])
                fix = replace(fix, vn=fields["speed"] * math.cos(c), ve=fields["speed"] * math.sin(c),
                              vd=-fields.get("climb", 0.0), has_velocity=True)
            elif old is not None and now - old.time > 0.05:
                if old.has_velocity and now - old.time < 1.5:       # a GGA after an RMC: keep the RMC's velocity
                    fix = replace(fix, vn=old.vn, ve=old.ve, vd=old.vd, has_velocity=True)
                else:
                    n, e = frames.offset_ned(old.lat, old.lon, fix.lat, fix.lon)
                    dt = now - old.time
                    fix = replace(fix, vn=n / dt, ve=e / dt, has_velocity=True)
            if fix.finite():
                self._fix = fix

    def close(self) -> None:
        pass


class GivenTarget(TargetSource):
    """Positions given through the API (Ice's Shots.followTarget, the console)."""

    def put(self, lat: float, lon: float, alt: float | None = None, vn: float | None = None, ve: float | None = None,
            vd: float = 0.0) -> bool:
        if not frames.finite(lat, lon) or not (-90 <= lat <= 90 and -180 <= lon <= 180):
            return False
        fields = {"lat": float(lat), "lon": float(lon), "alt": alt if alt is None or frames.finite(alt) else None}
        if vn is not None and ve is not None and frames.finite(vn, ve, vd):
            fields.update(speed=math.hypot(vn, ve), course=math.degrees(math.atan2(ve, vn)), climb=-vd)
        self._update(fields)
        return True


class StreamTarget(TargetSource):
    """NMEA or gpsd from a stream, read on a thread of its own; reconnects (TCP, serial) after a second."""

    def __init__(self, url: str, clock=time.monotonic):
        super().__init__(clock, url)
        u = urlparse(url)
        self.scheme, self.host, self.port = u.scheme, u.hostname or "", u.port
        self.path, self.query = u.path, parse_qs(u.query)
        if self.scheme not in ("nmea+udp", "nmea+tcp", "nmea+serial", "gpsd"):
            raise ValueError(f"unknown position source {url!r}: nmea+udp://, nmea+tcp://, nmea+serial://, gpsd://")
        if self.scheme == "gpsd":
            self.port = self.port or GPSD_PORT
        elif self.scheme != "nmea+serial" and self.port is None:
            raise ValueError(f"{url}: a port is needed")
        self._closing = threading.Event()
        self._sock: socket.socket | None = None
        if self.scheme == "nmea+udp":                    # bound now, so the caller knows the port is ours
            self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            self._sock.bind((self.host or "0.0.0.0", self.port))
            self._sock.settimeout(0.5)
            self.port = self._sock.getsockname()[1]
        self._thread = threading.Thread(target=self._run, name=f"target {url}", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._closing.is_set():
            try:
                if self.scheme == "nmea+udp":
                    self._read_udp()
                elif self.scheme == "nmea+serial":
                    self._read_serial()
                else:
                    self._read_tcp()
            except OSError as exc:
                self.problem = f"{self.name}: {exc}"
                log.warning("position source %s", self.problem)
            self._closing.wait(1.0)

    def _line(self, line: str) -> None:
        fields = parse_gpsd(line) if self.scheme == "gpsd" else parse_nmea(line)
        if fields is not None:
            self.problem = ""
            self._update(fields)

    def _read_udp(self) -> None:
        while not self._closing.is_set():
            try:
                data = self._sock.recv(4096)
            except socket.timeout:
                continue
            for line in data.decode("ascii", "replace").splitlines():
                self._line(line)

    def _read_tcp(self) -> None:
        with socket.create_connection((self.host or "127.0.0.1", self.port), timeout=3.0) as s:
            self._sock = s
            s.settimeout(0.5)
            if self.scheme == "gpsd":
                s.sendall(b'?WATCH={"enable":true,"json":true}\n')
            self._lines(lambda: s.recv(4096))

    def _read_serial(self) -> None:
        import serial                                    # pyserial, pinned for the MAVLink link already
        baud = int(self.query.get("baud", ["4800"])[0])
        with serial.Serial(self.path, baud, timeout=0.5) as port:
            self._lines(lambda: port.read(256) or b"")

    def _lines(self, read) -> None:
        buf = b""
        while not self._closing.is_set():
            try:
                data = read()
            except socket.timeout:
                continue
            if data == b"" and self.scheme != "nmea+serial":
                raise ConnectionError("the source closed the connection")
            buf += data
            *lines, buf = buf.split(b"\n")
            for line in lines:
                self._line(line.decode("ascii", "replace"))
            buf = buf[-4096:]

    def close(self) -> None:
        self._closing.set()
        if self._sock is not None:
            try:
                self._sock.close()
            except OSError:
                pass
        self._thread.join(timeout=2.0)


def open_target(url: str, clock=time.monotonic) -> TargetSource:
    """A source by URL; ``given`` (or "") for positions given through the API."""
    if url in ("", "given", "api", "ice"):
        return GivenTarget(clock, "given positions")
    return StreamTarget(url, clock)
