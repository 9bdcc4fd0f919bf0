"""The narrow services a part of the vehicle is handed, instead of the whole vehicle.

MAVSDK gives each plugin a ``Sender&``, a ``MavlinkMessageHandler&`` and a ``TimeoutHandler&``, never the
``SystemImpl`` itself. Here a part (the parameters, the payload, setup, the logs, the missions, a smart shot)
is given the few of these it needs, so what it depends on at run time is what its constructor says:

* :class:`StatePort`: the vehicle's state, its lock, and the pilot's messages and results;
* :class:`Outbox`: the one way out to the link (the ticker writes what a part posts), who the autopilot is;
* :class:`CommandPort`: commands to the autopilot, each through the flight rules' gate
  (:mod:`driver.vehicle.safety`), retried and matched to its own reply;
* :class:`Settler`: futures settled off the lock, on a small fixed pool;
* a clock: ``Callable[[], float]``, seconds, the vehicle's own (a test's manual clock).

:class:`Ports` bundles them for the vehicle to hand out. These are protocols: the ground floor imports nothing
of the driver, and the parts on floors 1 and 2 type against them without importing the vehicle.
"""
from __future__ import annotations

import threading
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any, Callable, Protocol

from .results import CommandResult, CommandStatus

__all__ = ["Clock", "StatePort", "Outbox", "CommandPort", "Settler", "Ports"]

Clock = Callable[[], float]


class StatePort(Protocol):
    """The writer side of the vehicle's snapshots (``driver.vehicle.store.StateStore``). Every method named
    ``*_locked`` and :meth:`set`, :meth:`view`, :meth:`publish` expect :attr:`lock` held."""

    lock: threading.RLock
    state: Any                                   # the latest published VehicleState
    message_index: int

    def view(self) -> Any: ...
    def set(self, **changes) -> None: ...
    def publish(self) -> None: ...
    def add_message(self, severity: int, text: str, source: str = "driver") -> Any: ...
    def add_message_locked(self, severity: int, text: str, source: str = "driver") -> Any: ...
    def messages_since(self, index: int) -> list: ...
    def record(self, command: str, status: CommandStatus, reason: str = "", attempts: int = 0) -> CommandResult: ...
    def record_locked(self, command: str, status: CommandStatus, reason: str = "",
                      attempts: int = 0) -> CommandResult: ...


class Outbox(Protocol):
    """The one way out: a posted message is written by the ticker thread, after every rule of the gate."""

    def post(self, msg) -> None:
        """Queue ``msg`` for the next tick (any thread)."""

    def wake(self) -> None:
        """Run the ticker now: something is due (a part's service has news)."""

    def tick_within(self, seconds: float) -> None:
        """Have the next tick within ``seconds`` (a paced transfer), news or not."""

    def target(self) -> tuple[int, int]:
        """The autopilot's (system, component)."""

    def encoder(self) -> Any:
        """A fresh MAVLink encoder with our system and component ids (a transfer packs its own frames)."""

    @property
    def mavlink2(self) -> bool:
        """The link speaks MAVLink 2 now (the autopilot was heard in it)."""


class CommandPort(Protocol):
    """Commands to the autopilot. Each goes through the gate (the flight rules), is retried, and is settled by
    its own reply and, where the vehicle shows it, by its state (mode, armed)."""

    def long(self, command: int, params=(), name: str | None = None, *, guard=None) -> Future: ...

    def mode(self, name: str) -> Future: ...

    def answer(self, name: str, status: CommandStatus, reason: str = "") -> Future:
        """A result given here and now (refused by the driver, or nothing to do), recorded for the pilot."""

    def settled(self, command: int) -> bool:
        """No request with this id is pending or may still be answered: the state tells the truth about what it
        would change (a mode, the armed bit), and may be answered from."""


class Settler(Protocol):
    def settle(self, future: Future, result) -> None:
        """Resolve ``future`` off the caller's lock."""


@dataclass(frozen=True)
class Ports:
    """What the vehicle hands its parts; each part keeps only the ports its constructor asks for."""
    clock: Clock
    state: StatePort
    outbox: Outbox
    commands: CommandPort
    settler: Settler
