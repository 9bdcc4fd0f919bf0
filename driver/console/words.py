"""Words every console command set shares: a typed number checked, a command's answer in one line.

A module of its own so that the command sets (flight, plans, payload, parameters) import it and not each other.
"""
from __future__ import annotations

import math

from ..core.results import CommandResult, CommandStatus

__all__ = ["number", "result_line"]


def number(text: str, name: str, integer: bool = False) -> float:
    """``text`` as a finite number (an int with ``integer``, any base Python reads), or ValueError naming ``name``."""
    try:
        value = int(text, 0) if integer else float(text)
    except ValueError:
        raise ValueError(f"{name} must be a number, not {text!r}") from None
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number")
    return value


def result_line(result: CommandResult) -> str:
    """A command's answer; one the vehicle never acknowledges (the safety switch) says just that it was sent."""
    if result.status is CommandStatus.ACCEPTED and result.reason.startswith("sent"):
        return f"{result.command}: {result.reason}"
    return str(result)
