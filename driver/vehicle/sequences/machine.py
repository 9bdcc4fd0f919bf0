"""A small state machine that the driver's ticker steps: named states, one handler each, no thread, no blocking.

A sequence (takeoff, mission start, land, RTL, Stop) *has* a :class:`Machine` and gives it a handler per state;
shared steps (the wait for readiness, GUIDED, arming) are objects the sequences compose, never a base class they
inherit. A handler reads the vehicle's state and the futures of what it asked, and either stays (returns None),
moves (:meth:`Machine.go`), or ends the sequence (returns an :class:`Outcome`). The states visited are kept, so a
test and the pilot's log can say exactly how a sequence went.
"""
from __future__ import annotations

from concurrent.futures import Future
from dataclasses import dataclass
from typing import Callable, Protocol

from ..commands import decided
from ..state import CommandResult, CommandStatus, SequencePhase, VehicleState

__all__ = ["Machine", "Outcome", "Pilot"]


class Pilot(Protocol):
    """What a sequence is handed: the vehicle's state and the one command path (through the flight rules)."""

    def state(self) -> VehicleState: ...

    def may_be_airborne(self) -> bool: ...

    def mode(self, name: str, *, early: bool = False) -> Future:
        """A mode change; ``early``: settled by the vehicle's ACCEPTED already, not only by its heartbeat."""

    def arm(self, *, early: bool = False) -> Future: ...

    def disarm(self) -> Future:
        """A plain disarm, through the flight rules (refused while the vehicle may be airborne)."""

    def hold(self) -> None:
        """Zero velocity from now (streamed for ArduCopter's GUID_TIMEOUT); the pilot's sticks fly again."""

    def quiet(self, command: int) -> bool:
        """No request with this id is pending, and none sent earlier can still reach the vehicle."""

    def long(self, command: int, params=(), name: str | None = None, *, retry: float | None = None,
             shows_mode: str | None = None) -> Future:
        """A COMMAND_LONG; ``shows_mode``: one that switches the mode (MISSION_START), confirmed by the heartbeat
        showing it, as a mode change is."""

    def retry_interval(self) -> float:
        """How soon an idempotent request goes again when unanswered (the link's own round trip)."""


@dataclass(frozen=True)
class Outcome:
    """How a sequence ended: its result for the pilot and the phase it ends in."""
    status: CommandStatus
    reason: str
    phase: SequencePhase = SequencePhase.DONE
    result: CommandResult | None = None      # the pilot was told this already (one command's own result)

    @classmethod
    def failed(cls, result: CommandResult, what: str) -> "Outcome":
        return cls(result.status, f"{what}: {result.reason}", SequencePhase.FAILED)


Handler = Callable[[VehicleState, float], "Outcome | None"]


class Machine:
    """The current state of one sequence, when it was entered, and the request it waits on."""

    def __init__(self, first: str, now: float, handlers: dict[str, Handler]) -> None:
        self.handlers = handlers
        self.state = first
        self.since = now
        self.pending: Future | None = None
        self.history: list[str] = [first]

    def go(self, state: str, now: float) -> None:
        """Enter ``state`` (a handler's own transition): its time starts now, with nothing asked yet."""
        if state not in self.handlers:
            raise KeyError(f"no state {state!r}")
        self.state, self.since, self.pending = state, now, None
        if self.history[-1] != state:
            self.history.append(state)

    def elapsed(self, now: float) -> float:
        return now - self.since

    def ask(self, request: Callable[[], Future]) -> CommandResult | None:
        """Send ``request`` once in this state; its answer once there is one (None while it is awaited)."""
        if self.pending is None:
            self.pending = request()
        return decided(self.pending)

    def step(self, state: VehicleState, now: float) -> Outcome | None:
        """Run the current state's handler; a state just entered runs at once too (no tick lost between steps)."""
        for _ in range(len(self.handlers)):
            entered = self.state
            outcome = self.handlers[entered](state, now)
            if outcome is not None or self.state == entered:
                return outcome
        return None
