"""A second ground station on the simulated vehicle's link, for tests: what a shared radio link carries.

It connects with a plain socket and pymavlink's MAVLink 2 codec (not ``mavutil``,
whose MAVLink 2 switch is process-wide) as system 255 with a component id of its
own, says HEARTBEAT at 1 Hz (type GCS, autopilot INVALID) and sends its own
COMMAND_LONGs, in MAVLink 1 framing if asked (a Solo drops MAVLink 2). The
vehicle's COMMAND_ACKs name the sender in target_system/target_component and reach
every peer, as on a real shared link: a ground station must take only those
addressed to it.

    other = OtherGroundStation(f"tcp:127.0.0.1:{sim.tcp_port}", component=191).start()
    ack = other.command(mavlink.MAV_CMD_DO_SET_MODE, 1, 4)
    other.close()
"""
from __future__ import annotations

import socket
import threading
import time

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .server import parse_address

__all__ = ["OtherGroundStation", "first_message"]


def first_message(cond: threading.Condition, heard: list, predicate, timeout: float, since: int = 0,
                  message=lambda item: item):
    """The first of ``heard`` (a list that grows under ``cond``) from index ``since`` on whose message satisfies
    ``predicate`` (a type name works), waiting up to ``timeout`` seconds; None if none came."""
    if isinstance(predicate, str):
        kind = predicate
        predicate = lambda m: m.get_type() == kind  # noqa: E731
    deadline = time.monotonic() + timeout
    with cond:
        index = since
        while True:
            while index < len(heard):
                msg = message(heard[index])
                index += 1
                if predicate(msg):
                    return msg
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            cond.wait(left)


class OtherGroundStation:
    def __init__(self, url: str, system: int = 255, component: int = 191, target_system: int = 1,
                 target_component: int = 1, heartbeat_interval: float = 1.0, mavlink1: bool = False) -> None:
        """``url``: "tcp:HOST:PORT" (the sim's TCP server) or "udpout:HOST:PORT" (its UDP socket)."""
        scheme, _, address = url.partition(":")
        host, port = parse_address(address)
        if scheme == "tcp":
            self.sock = socket.create_connection((host, port), timeout=5)
            self._address = None
        elif scheme == "udpout":
            self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            self._address = (host, port)
        else:
            raise ValueError(f"expected tcp:HOST:PORT or udpout:HOST:PORT, got {url!r}")
        self.sock.settimeout(0.1)
        self.url = url
        self.system = system
        self.component = component
        self.target = (target_system, target_component)
        self.heartbeat_interval = heartbeat_interval
        self.mavlink1 = mavlink1
        self.mav = mavlink.MAVLink(None, srcSystem=system, srcComponent=component)
        self.parser = mavlink.MAVLink(None, srcSystem=system, srcComponent=component)
        self.parser.robust_parsing = True
        self.messages: list = []                 # everything heard, oldest first
        self._cond = threading.Condition()
        self._send_lock = threading.Lock()
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []

    def start(self) -> "OtherGroundStation":
        for target, name in ((self._read, "other-gcs-read"), (self._beat, "other-gcs-heartbeat")):
            thread = threading.Thread(target=target, name=name, daemon=True)
            thread.start()
            self._threads.append(thread)
        return self

    def close(self) -> None:
        self._stop.set()
        for thread in self._threads:
            thread.join(timeout=2.0)
        self.sock.close()

    def __enter__(self) -> "OtherGroundStation":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.close()

    # -- sending ------------------------------------------------------------------------------------
    def send(self, msg) -> None:
        with self._send_lock:
            data = msg.pack(self.mav, force_mavlink1=self.mavlink1)
            self.mav.seq = (self.mav.seq + 1) % 256
            if self._address is None:
                self.sock.sendall(data)
            else:
                self.sock.sendto(data, self._address)

    def heartbeat(self) -> None:
        self.send(self.mav.heartbeat_encode(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0,
                                            mavlink.MAV_STATE_ACTIVE))

    def send_command(self, command: int, *params: float) -> int:
        """COMMAND_LONG to the vehicle; returns the mark to wait for its answer from."""
        p = list(params) + [0.0] * (7 - len(params))
        mark = self.mark()
        self.send(self.mav.command_long_encode(*self.target, command, 0, *p))
        return mark

    def command(self, command: int, *params: float, timeout: float = 5.0):
        """COMMAND_LONG, then the COMMAND_ACK addressed to this station (None if none came)."""
        mark = self.send_command(command, *params)
        return self.wait(lambda m: m.get_type() == "COMMAND_ACK" and m.command == command and self.addressed(m),
                         timeout, since=mark)

    def set_mode(self, custom_mode: int, timeout: float = 5.0):
        return self.command(mavlink.MAV_CMD_DO_SET_MODE, mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, custom_mode,
                            timeout=timeout)

    def addressed(self, msg) -> bool:
        """Whether an answer names this station (an ACK without target fields, MAVLink 1, names no one)."""
        return (getattr(msg, "target_system", 0), getattr(msg, "target_component", 0)) == \
            (self.system, self.component)

    # -- receiving ----------------------------------------------------------------------------------
    def mark(self) -> int:
        with self._cond:
            return len(self.messages)

    def wait(self, predicate, timeout: float = 5.0, since: int = 0):
        """The first message from index ``since`` on that satisfies ``predicate`` (a type name works)."""
        return first_message(self._cond, self.messages, predicate, timeout, since)

    def _read(self) -> None:
        while not self._stop.is_set():
            try:
                data = self.sock.recv(65536)
            except socket.timeout:
                continue
            except OSError:
                return
            if not data:
                return
            heard = [m for m in self.parser.parse_buffer(data) or [] if m.get_type() != "BAD_DATA"]
            if heard:
                with self._cond:
                    self.messages.extend(heard)
                    self._cond.notify_all()

    def _beat(self) -> None:
        while True:
            try:
                self.heartbeat()
            except OSError:
                return
            if self._stop.wait(self.heartbeat_interval):
                return
