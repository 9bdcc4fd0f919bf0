"""What every layer of the driver says about a command and the link: a command's result, how bad a message is,
whether the link is up; and the two ways a command's future is made (already answered, or chained).

The ground floor: it imports nothing else of the driver, so the plan model, the parameter and payload
engines, the link and the vehicle all speak in these words without importing each other.
"""
from __future__ import annotations

import enum
import logging
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Callable

log = logging.getLogger(__name__)

__all__ = ["LinkStatus", "Severity", "CommandStatus", "CommandResult", "answered", "chain"]


class LinkStatus(enum.Enum):
    WAITING = "waiting"      # link open, no vehicle heartbeat yet
    OK = "ok"
    LOST = "lost"            # no heartbeat for the loss timeout
    CLOSED = "closed"


class Severity(enum.IntEnum):
    """MAV_SEVERITY: lower is worse."""
    EMERGENCY = 0
    ALERT = 1
    CRITICAL = 2
    ERROR = 3
    WARNING = 4
    NOTICE = 5
    INFO = 6
    DEBUG = 7


class CommandStatus(enum.Enum):
    ACCEPTED = "accepted"
    REFUSED = "refused"          # the vehicle said no (COMMAND_ACK failure / mode not reached)
    TIMED_OUT = "timed out"      # no answer after every retry
    REJECTED = "rejected"        # refused by the driver itself (bad value, busy, no link)
    ABORTED = "aborted"          # cancelled by the pilot (e.g. land during takeoff)
    IN_PROGRESS = "in progress"  # accepted and still running (e.g. a takeoff climbing)


@dataclass(frozen=True)
class CommandResult:
    command: str                         # "takeoff", "arm", "mode GUIDED", ...
    status: CommandStatus
    reason: str = ""                     # the vehicle's words (ACK result + STATUSTEXT) or ours
    attempts: int = 0
    index: int = 0                       # increases by one for every result of a session

    @property
    def ok(self) -> bool:
        return self.status in (CommandStatus.ACCEPTED, CommandStatus.IN_PROGRESS)

    def __str__(self) -> str:
        return f"{self.command}: {self.status.value}" + (f" ({self.reason})" if self.reason else "")


def answered(result: CommandResult) -> Future[CommandResult]:
    """A future that already holds ``result``: a refusal the driver gives at once, without asking the vehicle."""
    future: Future[CommandResult] = Future()
    future.set_result(result)
    return future


def chain(inner: Future, then: Callable, name: str = "command") -> Future:
    """A future resolved by ``then(result)`` (a CommandResult, or a Future to follow) once ``inner`` is. If
    ``then`` raises, it resolves REJECTED ("internal error") under ``name``: never left unresolved."""
    outer: Future = Future()

    def follow(f: Future) -> None:
        try:
            nxt = then(f.result())
        except Exception as exc:               # never leave the caller's future unresolved
            log.exception("%s: a chained step failed", name)
            nxt = CommandResult(name, CommandStatus.REJECTED, f"internal error: {exc}")
        if isinstance(nxt, Future):
            nxt.add_done_callback(lambda g: outer.done() or outer.set_result(g.result()))
        elif not outer.done():
            outer.set_result(nxt)
    inner.add_done_callback(follow)
    return outer
