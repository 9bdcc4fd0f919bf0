"""The writer side of :class:`~driver.vehicle.state.VehicleState`: changes gathered under one lock, published as
one immutable snapshot that any thread may read without locking."""
from __future__ import annotations

import collections
import logging
import threading
import time
from collections import ChainMap
from typing import Callable

from .state import CommandResult, CommandStatus, Message, Severity, VehicleState

log = logging.getLogger("driver.vehicle")

__all__ = ["StateStore"]

MAX_MESSAGES = 200
MAX_RESULTS = 100


class StateStore:
    """Pending changes, the pilot's messages and command results; ``publish`` swaps the snapshot in."""

    def __init__(self, initial: VehicleState, wall_time: Callable[[], float]):
        self.lock = threading.RLock()
        self.changed = threading.Condition(self.lock)
        self.state = initial
        self.fields: dict = {}
        self.published_at = 0.0
        self._wall_time = wall_time
        self._messages: collections.deque[Message] = collections.deque(maxlen=MAX_MESSAGES)
        self._results: collections.deque[CommandResult] = collections.deque(maxlen=MAX_RESULTS)
        self.message_index = 0
        self._result_index = 0

    def set(self, **changes) -> None:
        self.fields.update(changes)

    def view(self) -> ChainMap:
        """The state as it will be published: pending changes over the last snapshot (lock held)."""
        return ChainMap(self.fields, self.state.__dict__)

    def publish(self) -> None:
        """Swap in a new snapshot (lock held)."""
        self.published_at = time.monotonic()
        self.fields["time"] = time.time()
        self.state = VehicleState(**{**self.state.__dict__, **self.fields})
        self.fields = {}
        self.changed.notify_all()

    def wait_for(self, predicate, timeout: float, closing: threading.Event) -> VehicleState | None:
        deadline = time.monotonic() + timeout
        with self.changed:
            while True:
                s = self.state
                if predicate(s):
                    return s
                remaining = deadline - time.monotonic()
                if remaining <= 0 or closing.is_set():
                    return None
                self.changed.wait(min(remaining, 0.2))

    # -- messages and results -------------------------------------------------------------------------
    def add_message_locked(self, severity: int, text: str, source: str = "driver") -> Message:
        self.message_index += 1
        m = Message(self.message_index, self._wall_time(), Severity(severity), text, source)
        self._messages.append(m)
        self.fields["messages"] = tuple(self._messages)
        if source == "driver":
            self.publish()
        log.log(logging.WARNING if severity <= Severity.WARNING else logging.INFO, "%s: %s", source, text)
        return m

    def add_message(self, severity: int, text: str, source: str = "driver") -> Message:
        with self.lock:
            return self.add_message_locked(severity, text, source)

    def messages_since(self, index: int) -> list[Message]:
        return [m for m in self._messages if m.index > index]

    def record_locked(self, command: str, status: CommandStatus, reason: str = "", attempts: int = 0) -> CommandResult:
        self._result_index += 1
        result = CommandResult(command, status, reason, attempts, self._result_index)
        self._results.append(result)
        self.fields["results"] = tuple(self._results)
        self.publish()
        (log.info if result.ok else log.warning)("command %s", result)
        return result

    def record(self, command: str, status: CommandStatus, reason: str = "", attempts: int = 0) -> CommandResult:
        with self.lock:
            return self.record_locked(command, status, reason, attempts)
