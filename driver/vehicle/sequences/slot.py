"""The one slot in which a sequence runs: a takeoff or mission start, a Land or RTL followed down, a Stop.

A sequence is stepped by the ticker. While a takeoff or a mission start (an *exclusive* sequence) runs, only
Land, Stop and RTL are taken, and each ends it; any command ends a Land, RTL or Stop that is only following the
vehicle. Ending a sequence cancels what it asked the vehicle (its tagged commands), so no retry sends it after.
The slot owns no lock: every call here is made with the vehicle's state lock held.
"""
from __future__ import annotations

import logging
import weakref

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..state import CommandStatus, SequencePhase, SequenceProgress, SequenceState, Severity
from .machine import Outcome

log = logging.getLogger("driver.vehicle")

__all__ = ["SequenceSlot"]


class SequenceSlot:
    """Holds the running sequence, steps it, publishes its progress and settles its future."""

    def __init__(self, store, commands, settler, clock):
        self._store, self._commands, self._settler, self._clock = store, commands, settler, clock
        self.current = None                   # the running sequence, else None
        self.stepping = False                 # the ticker is stepping it now: its own commands carry its tag
        self._answered = weakref.WeakSet()    # sequences whose future is settled (a Land answers, then follows)

    @property
    def tag(self):
        """What the running sequence's commands carry while it steps (an abort cancels them), else None."""
        return self.current if self.stepping else None

    @property
    def exclusive(self):
        """The takeoff or mission start running now, else None."""
        seq = self.current
        return seq if seq is not None and seq.exclusive else None

    def start(self, seq) -> bool:
        """Put ``seq`` in the slot, ending a Land, RTL or Stop that runs; False while a takeoff or mission start
        runs (the caller ends it first when ``seq`` may replace it)."""
        if self.exclusive is not None:
            return False
        self.end("superseded by " + seq.name)
        self.current = seq
        self.progress(seq)
        return True

    def step(self, now: float) -> None:
        seq = self.current
        if seq is None:
            return
        self.stepping = True
        try:
            outcome = seq.step(self._store.state, now)
        except Exception as exc:                      # never leave the future unresolved
            log.exception("%s sequence failed", seq.name)
            outcome = Outcome(CommandStatus.REJECTED, f"internal error: {exc}", SequencePhase.FAILED)
        finally:
            self.stepping = False
        answer = getattr(seq, "answer", None)
        if answer is not None:                        # answered now, followed on
            seq.answer = None
            self._settle(seq, answer)
        if outcome is None:
            self.progress(seq)
            return
        self.current = None
        if seq.exclusive:
            self._store.set(takeoff=SequenceProgress(outcome.phase, outcome.reason, seq.altitude))
        self._store.set(sequence=SequenceState(seq.name, "done" if outcome.status is CommandStatus.ACCEPTED
                                               else "failed", outcome.reason))
        log.info("%s: %s %s (%s)", seq.name, outcome.phase.value, outcome.reason, " → ".join(seq.machine.history))
        self._settle(seq, outcome)
        self._store.publish()

    def _settle(self, seq, outcome) -> None:
        if seq in self._answered:
            return
        self._answered.add(seq)
        result = outcome.result or self._store.record_locked(seq.name, outcome.status, outcome.reason)
        seq.future.decision = result               # known to the driver now (a CommandFuture), to callers once settled
        self._settler.settle(seq.future, result)

    def progress(self, seq) -> None:
        changed = False
        if seq.exclusive:
            progress = SequenceProgress(seq.phase, seq.detail, seq.altitude)
            if self._store.state.takeoff != progress:
                self._store.set(takeoff=progress)
                changed = True
        state = SequenceState(seq.name, seq.state, seq.detail)
        if self._store.state.sequence != state:
            self._store.set(sequence=state)
            changed = True
        if changed:
            self._store.publish()
            log.info("%s: %s %s", seq.name, seq.state, seq.detail)

    def end(self, why: str):
        """End the running sequence, whatever it is, and cancel what it asked; returns it (None if none ran)."""
        seq = self.current
        if seq is None:
            return None
        self.current = None
        sent = self._commands.cancel_tagged(seq, f"{seq.name} ended: {why}", self._clock())
        if seq.exclusive and any(command == mavlink.MAV_CMD_NAV_TAKEOFF for command, _ in sent):
            # a command on its way cannot be called back: say so rather than promise the ground
            self._store.add_message_locked(Severity.WARNING, "Takeoff ended after NAV_TAKEOFF went out: if "
                                           "the vehicle got it, it lifts off (Land brings it down)")
        if seq.exclusive:
            self._store.set(takeoff=SequenceProgress(SequencePhase.ABORTED, f"aborted: {why}", seq.altitude))
        self._store.set(sequence=SequenceState(seq.name, "ended", why))
        # a takeoff or mission start, or a Land, RTL or Stop not yet answered, was cut short; one that answered
        # already (the vehicle showed LAND) keeps its answer
        self._settle(seq, Outcome(CommandStatus.ABORTED, f"aborted by the pilot ({why})"))
        self._store.publish()
        return seq
