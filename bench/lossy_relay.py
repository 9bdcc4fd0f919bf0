"""A frame-parsing relay between a vehicle's TCP MAVLink port and a ground station's ``udpin`` link, that loses
whole frames: the link of bench/real_sitl.py.

Each way it cuts the byte stream into MAVLink frames by their start byte and length (v1 0xFE, v2 0xFD with the
signature flag), then drops each frame with probability ``loss``, each way with its own seeded random stream, so
a run can be repeated; ``latency`` holds every frame that long (in order, as a slow radio does) and ``duplicate``
sends a share twice. ``blackout(seconds)`` drops everything both ways for that long (a radio out of range).
Every frame the vehicle sends goes to the ground station as one UDP datagram, as a telemetry radio's bridge
sends it. Only loopback addresses: the vehicle is reached on 127.0.0.1 and datagrams go to 127.0.0.1.

In a process of its own (so that it shares no interpreter lock with the ground station it serves)::

    python bench/lossy_relay.py TCP_PORT UDP_PORT [--loss 0.3] [--seed 1]

it says "relaying" once connected, and the frames each way passed and dropped when terminated.
"""
from __future__ import annotations

import argparse
import collections
import random
import signal
import socket
import threading
import time
from typing import Callable

STX_V1, STX_V2 = 0xFE, 0xFD
SIGNED = 0x01                    # MAVLink 2 incompat flag: a 13-byte signature follows the checksum


class Framer:
    """Cuts a byte stream into whole MAVLink frames; bytes before a start byte are skipped (and counted)."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self.skipped = 0

    def feed(self, data: bytes) -> list[bytes]:
        self._buf += data
        frames = []
        buf = self._buf
        while buf:
            starts = [i for i in (buf.find(STX_V1), buf.find(STX_V2)) if i >= 0]
            start = min(starts) if starts else len(buf)
            if start:
                self.skipped += start
                del buf[:start]
                continue
            if len(buf) < 3:
                break
            if buf[0] == STX_V2:
                size = 12 + buf[1] + (13 if buf[2] & SIGNED else 0)
            else:
                size = 8 + buf[1]
            if len(buf) < size:
                break
            frames.append(bytes(buf[:size]))
            del buf[:size]
        return frames


class Way:
    """One direction's loss, duplicates and latency, and its counters."""

    def __init__(self, loss: float, seed: int, latency: float = 0.0, duplicate: float = 0.0) -> None:
        self.loss, self.latency, self.duplicate = loss, latency, duplicate
        self.rng = random.Random(seed)
        self.passed = 0
        self.dropped = 0
        self.duplicated = 0
        self._queue: collections.deque = collections.deque()     # (due, frame), in order
        self._ready = threading.Condition()

    def keep(self, blacked_out: bool) -> bool:
        lost = self.rng.random() < self.loss     # drawn for every frame, so a blackout does not shift the stream
        if blacked_out or lost:
            self.dropped += 1
            return False
        self.passed += 1
        return True

    def send(self, frame: bytes, blacked_out: bool, deliver: Callable[[bytes], None]) -> None:
        """``frame`` through this way's faults: delivered now, later, twice or never."""
        if not self.keep(blacked_out):
            return
        copies = 2 if self.duplicate and self.rng.random() < self.duplicate else 1
        self.duplicated += copies - 1
        if not self.latency:
            for _ in range(copies):
                deliver(frame)
            return
        with self._ready:
            for _ in range(copies):
                self._queue.append((time.monotonic() + self.latency, frame))
            self._ready.notify()

    def run_delayed(self, deliver: Callable[[bytes], None], closing: threading.Event) -> None:
        """Hand on held frames once their time has come (a thread of its own while ``latency`` is set)."""
        while not closing.is_set():
            with self._ready:
                if not self._queue:
                    self._ready.wait(0.2)
                    continue
                due, frame = self._queue[0]
                wait = due - time.monotonic()
                if wait > 0:
                    self._ready.wait(min(wait, 0.2))
                    continue
                self._queue.popleft()
            deliver(frame)


class LossyRelay:
    """Vehicle TCP port <-> relay <-> ``udpin:127.0.0.1:udp_port`` of the ground station."""

    def __init__(self, tcp_port: int, udp_port: int, loss: float, seed: int, connect_timeout: float = 30.0,
                 latency: float = 0.0, duplicate: float = 0.0):
        self.udp_port = udp_port
        self.down = Way(loss, seed, latency, duplicate)        # vehicle -> ground station
        self.up = Way(loss, seed + 1, latency, duplicate)      # ground station -> vehicle
        self._dark_until = 0.0
        self._closing = threading.Event()
        self._tcp = _connect(("127.0.0.1", tcp_port), connect_timeout)
        self._udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._udp.bind(("127.0.0.1", 0))
        self._udp.settimeout(0.2)
        self._threads = [threading.Thread(target=self._downlink, name="relay-down", daemon=True),
                         threading.Thread(target=self._uplink, name="relay-up", daemon=True)]
        if latency:
            self._threads += [
                threading.Thread(target=self.down.run_delayed, args=(self._to_ground, self._closing), daemon=True),
                threading.Thread(target=self.up.run_delayed, args=(self._to_vehicle, self._closing), daemon=True)]
        for t in self._threads:
            t.start()

    def blackout(self, seconds: float) -> None:
        """Drop every frame both ways for ``seconds`` from now."""
        self._dark_until = time.monotonic() + seconds

    def retarget(self, udp_port: int) -> None:
        """Send the vehicle's frames to another ground station's port from now on (a new driver)."""
        self.udp_port = udp_port

    def _dark(self) -> bool:
        return time.monotonic() < self._dark_until

    def _downlink(self) -> None:
        framer = Framer()
        self._tcp.settimeout(0.2)
        while not self._closing.is_set():
            try:
                data = self._tcp.recv(65536)
            except socket.timeout:
                continue
            except OSError:
                break
            if not data:
                break                            # the vehicle closed its port
            for frame in framer.feed(data):
                self.down.send(frame, self._dark(), self._to_ground)

    def _to_ground(self, frame: bytes) -> None:
        try:
            self._udp.sendto(frame, ("127.0.0.1", self.udp_port))
        except OSError:
            pass                                 # nobody listening yet: a frame lost, as on the air

    def _to_vehicle(self, frame: bytes) -> None:
        try:
            self._tcp.sendall(frame)
        except OSError:
            pass                                 # the vehicle closed its port

    def _uplink(self) -> None:
        framers: dict = {}
        while not self._closing.is_set():
            try:
                data, sender = self._udp.recvfrom(65536)
            except socket.timeout:
                continue
            except OSError:
                break
            if sender[0] != "127.0.0.1":
                continue
            for frame in framers.setdefault(sender, Framer()).feed(data):
                self.up.send(frame, self._dark(), self._to_vehicle)

    def close(self) -> None:
        self._closing.set()
        for t in self._threads:
            t.join(1.0)
        for s in (self._tcp, self._udp):
            try:
                s.close()
            except OSError:
                pass


def _connect(address: tuple[str, int], timeout: float) -> socket.socket:
    """A TCP connection, retried until ``timeout`` (the vehicle may still be starting)."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            return socket.create_connection(address, timeout=2.0)
        except OSError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)


def free_udp_port() -> int:
    """A loopback UDP port nobody uses now, for the driver's ``udpin``."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def main() -> None:
    p = argparse.ArgumentParser(description="A frame-losing relay: a vehicle's TCP port to a ground station's udpin")
    p.add_argument("tcp_port", type=int)
    p.add_argument("udp_port", type=int)
    p.add_argument("--loss", type=float, default=0.0, help="share of frames lost each way")
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args()
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    relay = LossyRelay(args.tcp_port, args.udp_port, args.loss, args.seed)
    print("relaying", flush=True)
    while not stop.wait(0.5):
        pass
    relay.close()
    for name, way in (("down", relay.down), ("up", relay.up)):
        print(f"{name}: {way.passed} passed, {way.dropped} dropped", flush=True)


if __name__ == "__main__":
    main()
