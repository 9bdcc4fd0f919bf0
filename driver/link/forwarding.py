"""Forwarding to other ground stations (MAVProxy's ``--out``): the vehicle's bytes go out as they came,
and each station's whole frames come back to the vehicle.

Frames from a station are passed on as they are, never re-signed: a signing vehicle obeys them only if that
station signs with the key itself, so a forwarding port never lends our key to whoever reaches it.
"""
from __future__ import annotations

import logging
import threading
from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .transport import LinkError, MavutilTransport

log = logging.getLogger(__name__)

__all__ = ["Forwarder"]


class Forwarder:
    """One thread per output; ``to_vehicle`` writes a whole frame to the vehicle link (any thread)."""

    def __init__(self, connections: tuple[str, ...], baud: int, to_vehicle: Callable[[bytes], None],
                 warn: Callable[[str], None], closing: threading.Event):
        self._connections = connections
        self._baud = baud
        self._to_vehicle = to_vehicle
        self._warn = warn
        self._closing = closing
        self.outputs: list[MavutilTransport] = []

    def start(self) -> list[threading.Thread]:
        threads = []
        for out in self._connections:
            t = threading.Thread(target=self._run, args=(out,), name=f"mavlink-out {out}", daemon=True)
            t.start()
            threads.append(t)
        return threads

    def send(self, data: bytes) -> None:
        """The vehicle's bytes, to every station (reader thread)."""
        for out in self.outputs:
            out.write(data)

    def close(self) -> None:
        for out in self.outputs:
            out.close()

    @staticmethod
    def _parser():
        codec = mavlink.MAVLink(None)
        codec.robust_parsing = True
        return codec

    def _run(self, connection: str) -> None:
        target = "udpout:" + connection[4:] if connection.startswith("udp:") else connection
        out = MavutilTransport(target, self._baud)
        try:
            out.open()
        except LinkError as exc:
            self._warn(f"Forwarding to {connection} failed: {exc}")
            return
        self.outputs.append(out)
        parser = self._parser()                       # whole frames only: the log and the vehicle get no garbage
        while not self._closing.is_set():
            try:
                data = out.read(0.2)
            except LinkError:
                self._closing.wait(0.5)
                continue
            try:
                frames_in = parser.parse_buffer(data) or () if data else ()
            except Exception:
                parser, frames_in = self._parser(), ()
            for msg in frames_in:
                if msg.get_type() != "BAD_DATA":
                    self._to_vehicle(bytes(msg.get_msgbuf()))
