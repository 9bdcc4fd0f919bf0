"""A connection string, checked for the user and opened as its transport: a live link or a recorded flight."""
from __future__ import annotations

import ipaddress
import os
import re

from .tlog import TlogReplay
from .transport import MavutilTransport, Transport, UdpTransport

__all__ = ["connection_problem", "host_problem", "open_transport", "NETWORK_SCHEMES"]


NETWORK_SCHEMES = ("udp", "udpin", "udpout", "udpbcast", "tcp", "tcpin")
OTHER_SCHEMES = ("ws", "wss", "wsserver", "mcast")      # pymavlink takes these too; checked by it


_LABEL = re.compile(r"[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?$")     # RFC 1123: letters, digits, inner hyphens


def host_problem(host: str) -> str | None:
    """Why ``host`` cannot be a network host (a typo, a pasted command), in a line for the user; None for an IP
    address or a host name made of RFC 1123 labels. Checked before anything is opened or asked: "no such host!!
    ;rm" used to go to the resolver and fail 15 s later as a silent link."""
    try:
        ipaddress.ip_address(host.strip("[]"))
        return None
    except ValueError:
        pass
    name = host[:-1] if host.endswith(".") else host
    if name and len(name) <= 253 and all(_LABEL.match(label) for label in name.split(".")):
        return None
    return f"{host!r} is not a host name or an IP address (letters, digits, '-' and '.' only)"


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
        problem = host_problem(host)
        return f"{text!r}: {problem}" if problem else None
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
