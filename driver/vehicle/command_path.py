"""The one path every command takes to the autopilot: the flight rules' gate (:mod:`driver.vehicle.safety`), then the
command sender (:mod:`driver.vehicle.commands`: retries, each reply to its own request).

:class:`CommandPath` is the :class:`~driver.core.ports.CommandPort` the parts are handed, and what the façade's own
commands go through: a COMMAND_LONG, a mode change, a result given at once (refused by the driver, or nothing to do),
and whether the state can be trusted about a command (no request with its id may still change it).
"""
from __future__ import annotations

from concurrent.futures import Future

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core import frames
from .commands import command_name
from .rules import COPTER_MODES
from .safety import ARM_FORCE_MAGIC
from .state import CommandStatus

__all__ = ["CommandPath", "REPLAYING"]

REPLAYING = "replaying a recording: no vehicle to command"


class CommandPath:
    """Over the vehicle's store, flight rules, command sender and sequence slot (whose running sequence tags what it
    sends, so that ending it cancels its commands); ``wake`` runs the ticker for the first attempt."""

    def __init__(self, store, rules, sender, sequence, clock, wake, replaying: bool) -> None:
        self._store, self._rules, self._sender, self._sequence = store, rules, sender, sequence
        self._clock, self._wake, self._replaying = clock, wake, replaying

    def long(self, command: int, params=(), name: str | None = None, *, guard=None, retry: float | None = None,
             early: bool = False, shows_mode: str | None = None) -> Future:
        """A COMMAND_LONG within the flight rules, retried, settled by its own ACK (and, for arming, the
        heartbeat); ``retry``: s between attempts; ``early``: settled by the vehicle's ACCEPTED already;
        ``shows_mode``: the mode the heartbeat shows once it is done (MISSION_START: AUTO)."""
        name = name or command_name(command)
        params = [float(p) for p in (list(params) + [0.0] * 7)[:7]]
        if not frames.finite(*params):
            return self.answer(name, CommandStatus.REJECTED, "parameter is not a finite number")
        if self._replaying:
            return self.answer(name, CommandStatus.REJECTED, REPLAYING)
        with self._store.lock:
            problem = self._rules.command_problem(command, params, self._store.state, self._clock())
            if problem:
                return self.answer(name, CommandStatus.REJECTED, problem)
            future = self._sender.submit(name, command, params, self._clock(), guard=guard, tag=self._sequence.tag,
                                         retry=retry, early=early, shows_mode=COPTER_MODES.get(shows_mode or ""))
        self._wake.set()
        return future

    def mode(self, name: str, *, early: bool = False) -> Future:
        """A mode change through the flight rules, confirmed by the heartbeat."""
        number = COPTER_MODES.get(name.upper())
        if number is None:
            return self.answer(f"mode {name}", CommandStatus.REJECTED,
                               f"unknown mode; known: {', '.join(sorted(COPTER_MODES))}")
        if self._replaying:
            return self.answer(f"mode {name.upper()}", CommandStatus.REJECTED, REPLAYING)
        with self._store.lock:                        # sent even when the state shows it: the vehicle may have left
            s = self._store.state                     # it since (a failsafe, its mission's end), the state be older
            problem = self._rules.mode_problem(number, s)
            if problem:
                return self.answer(f"mode {name.upper()}", CommandStatus.REJECTED, problem)
            future = self._sender.submit_mode(f"mode {name.upper()}", number, self._clock(),
                                              tag=self._sequence.tag, early=early)
        self._wake.set()
        return future

    def arming(self, armed: bool, force: bool = False, early: bool = False) -> Future:
        """Arm or disarm; ``force``: past the vehicle's own checks (ArduPilot's magic number). Sent even when the
        state shows it done: the vehicle disarms by itself (DISARM_DELAY, a motor test's end), and the state may be
        older than that; ArduCopter accepts an arm of an armed vehicle."""
        name = ("arm" if armed else "disarm") + (" (forced)" if force else "")
        return self.long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (1 if armed else 0, ARM_FORCE_MAGIC if force else 0), name,
                         early=early)

    def answer(self, name: str, status: CommandStatus, reason: str = "") -> Future:
        f: Future = Future()
        f.set_result(self._store.record(name, status, reason))
        return f

    def busy(self, command: str) -> Future | None:
        """While a takeoff or mission start runs, only Land, Stop and RTL (each of which ends it)."""
        seq = self._sequence.exclusive
        if seq is not None:
            return self.answer(command, CommandStatus.REJECTED, f"{seq.name} in progress: only Land, Stop and RTL")
        return None

    def settled(self, command: int) -> bool:
        """No request with this id is pending or may still be answered: the state tells the truth about it."""
        return self._sender.settled_by_state(command, self._clock())
