"""What the pilot picked in File › Connect, as one value that opens a drone and is remembered as a line of text.

No Qt here. A :class:`Choice` is a MAVLink link (UDP, TCP, serial: any mavutil connection string), the built-in
simulated vehicle, an Ice server (a host, or a viewer config file), a lab's registry (a fleet), or a recorded
flight (.tlog). Its
:attr:`Choice.key` is what the recent-connections list keeps; :func:`parse_key` reads it back.
"""
from __future__ import annotations

import enum
import os
from dataclasses import dataclass, field

from driver.link.connection import connection_problem, host_problem

__all__ = ["Kind", "Choice", "parse_key", "from_command_line", "serial_ports", "sim_name", "SITL_TCP", "SOLO_UDP",
           "waiting_words"]

SITL_TCP = "tcp:127.0.0.1:5760"          # ArduPilot SITL's first serial port (sim_vehicle.py, Mission Planner)
SOLO_UDP = "udpin:0.0.0.0:14550"         # a 3DR Solo, or any vehicle sending to the GCS port



def sim_name(speedup: float) -> str:
    """What the window calls the built-in simulator (its title, About)."""
    return "simulated ArduCopter (built in)" + (f", {speedup:g}× time" if speedup != 1 else "")

def waiting_words(address: str) -> str:
    """What a link does while no vehicle has answered, by its connection string: an outgoing TCP link connects
    ("connecting to 127.0.0.1:5760"), it never listens; udpin listens; udpout sends; a serial port waits."""
    scheme, _, rest = address.partition(":")
    scheme = scheme.lower()
    if scheme in ("tcp", "tcpout"):
        return f"connecting to {rest}"
    if scheme == "tcpin":
        return f"waiting for a TCP connection on {rest}"
    if scheme in ("udpin", "udp"):
        return f"listening on UDP {rest}"
    if scheme in ("udpout", "udpbcast"):
        return f"sending to UDP {rest}"
    return f"waiting on {address}"


class Kind(enum.Enum):
    MAVLINK = "mavlink"                  # udpin/udpout/tcp/serial
    SIM = "sim"                          # the built-in simulated ArduCopter
    ICE = "ice"                          # a MAVLinkServer over ZeroC Ice: a host or a config file
    REGISTRY = "registry"                # a lab's IceGrid registry: every vehicle registered there (docs/fleet.md)
    REPLAY = "replay"                    # a .tlog


@dataclass(frozen=True)
class Choice:
    kind: Kind
    target: str = ""                     # the connection string, the Ice host or config, the .tlog path
    baud: int = 57600                    # serial only
    options: dict = field(default_factory=dict, compare=False, hash=False)   # e.g. the simulator's speedup

    @property
    def key(self) -> str:
        """One line for the recent-connections list."""
        if self.kind is Kind.SIM:
            return "sim"
        if self.kind is Kind.ICE:
            return ("ice-config:" if self.target.endswith(".cfg") or os.sep in self.target else "ice:") + self.target
        if self.kind is Kind.REGISTRY:
            return f"registry:{self.target}"
        if self.kind is Kind.MAVLINK and self.is_serial:
            return f"{self.target},{self.baud}"
        return self.target

    @property
    def is_serial(self) -> bool:
        return self.kind is Kind.MAVLINK and not self.target.split(":", 1)[0].lower().startswith(("udp", "tcp"))

    @property
    def label(self) -> str:
        """How the pilot reads it in menus and the title."""
        if self.kind is Kind.SIM:
            return "Simulated vehicle (built in)"
        if self.kind is Kind.ICE:
            return f"Ice server {self.target}"
        if self.kind is Kind.REGISTRY:
            return f"Fleet at registry {self.target}"
        if self.kind is Kind.REPLAY:
            return f"Replay {os.path.basename(self.target)}"
        if self.is_serial:
            return f"Serial {self.target} at {self.baud}"
        return self.target

    def problem(self) -> str | None:
        """Why this cannot be opened, in a line for the pilot; None when it may be."""
        if self.kind is Kind.SIM:
            return None
        if not self.target.strip():
            return {Kind.ICE: "name the Ice server's host or config file", Kind.REPLAY: "pick a flight log",
                    Kind.REGISTRY: "name the registry's HOST:PORT"}.get(self.kind, "enter a connection")
        if self.kind is Kind.ICE:
            if self.key.startswith("ice-config:"):
                return None if os.path.isfile(self.target) else f"no such Ice config: {self.target}"
            return host_problem(self.target)
        if self.kind is Kind.REPLAY:
            return None if os.path.isfile(self.target) else f"no such flight log: {self.target}"
        if self.kind is Kind.REGISTRY:
            from driver.ice.registry import registry_address
            try:
                registry_address(self.target)
            except ValueError as exc:
                return str(exc)
            return None
        return connection_problem(self.target)


def parse_key(key: str) -> Choice | None:
    """The :class:`Choice` a recent-connections line names, or None if it no longer reads as one."""
    key = key.strip()
    if not key:
        return None
    if key == "sim":
        return Choice(Kind.SIM)
    if key.startswith("ice-config:"):
        return Choice(Kind.ICE, key[len("ice-config:"):])
    if key.startswith("ice:"):
        return Choice(Kind.ICE, key[len("ice:"):])
    if key.startswith("registry:"):
        return Choice(Kind.REGISTRY, key[len("registry:"):])
    if key.lower().endswith(".tlog"):
        return Choice(Kind.REPLAY, key)
    target, _, baud = key.rpartition(",")
    if target and baud.isdigit() and not key.lower().startswith(("udp", "tcp")):
        return Choice(Kind.MAVLINK, target, int(baud))
    return Choice(Kind.MAVLINK, key)


def from_command_line(args, connection: str) -> Choice:
    """What the command line chose (uavviewer.app's options), as the recent-connections list keeps it."""
    if args.sim:
        return Choice(Kind.SIM)
    if args.replay is not None:
        return Choice(Kind.REPLAY, str(args.replay))
    if args.registry is not None:
        return Choice(Kind.REGISTRY, args.registry)
    if args.ice is not None or args.ice_host is not None:
        return Choice(Kind.ICE, str(args.ice) if args.ice is not None else args.ice_host)
    return Choice(Kind.MAVLINK, connection, args.baud)


def serial_ports() -> list[tuple[str, str]]:
    """(device, description) of the serial ports this machine has now, autopilots first: pyserial's list, as
    pymavlink's mavutil.auto_detect_serial reads it. Empty without pyserial."""
    try:
        from pymavlink import mavutil
        found = mavutil.auto_detect_serial(preferred_list=["*"])
    except Exception:                    # noqa: BLE001 - no pyserial, no /sys: no ports to offer
        return []
    keen = ("ardupilot", "px4", "3dr", "cubepilot", "hex", "holybro", "mro", "fmu", "pixhawk", "radio", "sik")
    ports = [(p.device, p.description or "") for p in found]
    return sorted(ports, key=lambda p: (not any(k in p[1].lower() for k in keen), p[0]))
