"""Command-line value types shared by ``python -m driver``, ``python -m driver.sim`` and ``main.py``.

A bad value is a one-line argparse usage error (exit 2) naming what is wanted, never a traceback later.
"""
from __future__ import annotations

import argparse
import math
from typing import Callable

__all__ = ["as_float", "number", "positive", "not_negative", "whole", "port", "connection", "takeoff_altitude",
           "registry", "accepted_by", "add_link_security", "link_security"]


def as_float(text: str) -> float:
    """The number ``text`` says, or NaN (which fails every range check)."""
    try:
        return float(text)
    except ValueError:
        return math.nan


def number(low: float, high: float, wanted: str) -> Callable[[str], float]:
    """A finite number from ``low`` to ``high``; ``wanted`` says what is needed when it is not."""
    def check(text: str) -> float:
        value = as_float(text)
        if not (low <= value <= high and math.isfinite(value)):
            raise argparse.ArgumentTypeError(f"{text!r}: {wanted}")
        return value
    return check


def positive(text: str) -> float:
    """A finite number above zero."""
    value = as_float(text)
    if not 0 < value < math.inf:
        raise argparse.ArgumentTypeError(f"{text!r}: a positive number is needed")
    return value


not_negative = number(0.0, math.inf, "zero or a positive number is needed")


def whole(low: int, high: int) -> Callable[[str], int]:
    """An integer from ``low`` to ``high`` (ports, MAVLink ids, rates)."""
    def check(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = low - 1
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{text!r}: a whole number from {low} to {high} is needed")
        return value
    return check


port = whole(1, 65535)


def takeoff_altitude(text: str) -> float:
    """Metres above home in the range the driver's takeoff accepts."""
    from .vehicle.rules import takeoff_altitude_problem
    value = as_float(text)
    problem = takeoff_altitude_problem(value)
    if problem:
        raise argparse.ArgumentTypeError(f"{text!r}: {problem}")
    return value


def connection(text: str) -> str:
    """A MAVLink connection string that can be opened (checked by :func:`driver.link.connection.connection_problem`)."""
    from .link.connection import connection_problem
    problem = connection_problem(text)
    if problem:
        raise argparse.ArgumentTypeError(problem)
    return text.strip()


def accepted_by(parse: Callable[[str], object]) -> Callable[[str], str]:
    """An option type: the text as given, once ``parse`` accepts it (its ValueError is the usage error)."""
    def check(text: str) -> str:
        try:
            parse(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        return text
    return check


def registry(text: str) -> str:
    """``HOST:PORT`` of a lab's IceGrid registry (docs/fleet.md), as given."""
    from .ice.registry import registry_address
    return accepted_by(registry_address)(text)


def add_link_security(group) -> None:
    """The vehicle link's protection, the same on ``main.py`` and ``python -m driver`` (docs/security.md)."""
    key = group.add_mutually_exclusive_group()
    key.add_argument("--signing-passphrase", metavar="TEXT",
                     help="sign MAVLink 2 with the key SHA-256(TEXT), as MAVProxy's 'signing setup TEXT' "
                          "(other users can read a command line: prefer --signing-key-file)")
    key.add_argument("--signing-key-file", metavar="FILE",
                     help="sign MAVLink 2 with the key in FILE (64 hex digits, or a passphrase on its first "
                          "line; readable only by you, mode 600)")
    group.add_argument("--signing-allow-unsigned", action="store_true",
                       help="while signing, also accept the vehicle's unsigned frames (it has no key yet)")
    group.add_argument("--allow", action="append", default=[], metavar="ADDR",
                       help="UDP: also read this sender besides the vehicle (ADDRESS or ADDRESS:PORT, repeatable), "
                            "e.g. the Solo's controller 10.1.1.1; it never receives our frames")


def link_security(opts, parser: argparse.ArgumentParser):
    """(SigningConfig or None, allowed senders) from :func:`add_link_security`'s options; a bad key file or
    address is a usage error naming it."""
    from .link.transport import parse_sender
    from .link.signing import SigningConfig, key_from_passphrase, read_key_file
    for address in opts.allow:
        try:
            parse_sender(address)
        except ValueError as exc:
            parser.error(f"--allow {exc}")
    key = None
    if opts.signing_passphrase:
        key = key_from_passphrase(opts.signing_passphrase)
    elif opts.signing_key_file:
        try:
            key = read_key_file(opts.signing_key_file)
        except ValueError as exc:
            parser.error(f"--signing-key-file: {exc}")
    if key is None and not opts.signing_allow_unsigned:
        return None, tuple(opts.allow)
    return SigningConfig(key=key, allow_unsigned=opts.signing_allow_unsigned), tuple(opts.allow)


def battery_threshold(text: str) -> tuple[float, float]:
    """"3.6,30": a battery threshold, volts a cell and percent remaining (driver.vehicle.battery)."""
    try:
        cell, percent = (float(part) for part in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: give volts a cell and percent, e.g. 3.6,30") from None
    if not (2.5 <= cell <= 4.4 and 0.0 <= percent <= 100.0):
        raise argparse.ArgumentTypeError(f"{text!r}: 2.5 to 4.4 V a cell and 0 to 100 %")
    return cell, percent


def battery_thresholds(warning: tuple[float, float] | None, critical: tuple[float, float] | None):
    """The --battery-warning/--battery-critical pair as thresholds (defaults where not given); ValueError if
    critical is above warning."""
    from .vehicle.state import BatteryThresholds
    d = BatteryThresholds()
    wc, wp = warning or (d.warning_cell, d.warning_percent)
    cc, cp = critical or (d.critical_cell, d.critical_percent)
    t = BatteryThresholds(wc, cc, wp, cp)
    if t.problem():
        raise ValueError(t.problem())
    return t
