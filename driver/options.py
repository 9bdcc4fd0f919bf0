"""Command-line value types shared by ``python -m driver``, ``python -m driver.sim`` and ``main.py``.

A bad value is a one-line argparse usage error (exit 2) naming what is wanted, never a traceback later.
"""
from __future__ import annotations

import argparse
import math
from typing import Callable

__all__ = ["as_float", "number", "positive", "not_negative", "whole", "port", "connection", "takeoff_altitude"]


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
    from .vehicle import takeoff_altitude_problem
    value = as_float(text)
    problem = takeoff_altitude_problem(value)
    if problem:
        raise argparse.ArgumentTypeError(f"{text!r}: {problem}")
    return value


def connection(text: str) -> str:
    """A MAVLink connection string that can be opened (checked by :func:`driver.link.connection_problem`)."""
    from .link import connection_problem
    problem = connection_problem(text)
    if problem:
        raise argparse.ArgumentTypeError(problem)
    return text.strip()
