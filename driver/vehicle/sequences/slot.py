"""The one slot in which a takeoff or a mission start runs (driver.vehicle.sequences).

A sequence is stepped by the ticker; while it runs only Land and Stop are taken, and both end it. Aborting cancels
what it asked the vehicle (its tagged commands), so no retry launches it afterwards. The slot owns no lock: every
call here is made with the vehicle's state lock held.
"""
from __future__ import annotations

import logging

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..state import CommandStatus, SequencePhase, SequenceProgress, Severity

log = logging.getLogger("driver.vehicle")

__all__ = ["SequenceSlot"]


class SequenceSlot:
    """Holds the running sequence, steps it, publishes its progress and settles its future."""

    def __init__(self, store, commands, notifier):
        self._store, self._commands, self._notifier = store, commands, notifier
        self.current = None                   # the running TakeoffSequence (or MissionStart), else None
        self.stepping = False                 # the ticker is stepping it now: its own commands pass

    @property
    def tag(self):
        """What the running sequence's commands carry while it steps (an abort cancels them), else None."""
        return self.current if self.stepping else None

    def start(self, seq) -> bool:
        """Put ``seq`` in the slot; False when another one runs."""
        if self.current is not None:
            return False
        self.current = seq
        self.progress(seq)
        return True

    def step(self, now: float) -> None:
        seq = self.current
        if seq is None:
            return
        self.stepping = True
        try:
            outcome = seq.step(now)
        except Exception as exc:                      # never leave the future unresolved
            log.exception("%s sequence failed", seq.name)
            outcome = CommandStatus.REJECTED, f"internal error: {exc}", SequencePhase.FAILED
        finally:
            self.stepping = False
        if outcome is None:
            self.progress(seq)
            return
        status, reason, phase = outcome
        self.current = None
        self._store.set(takeoff=SequenceProgress(phase, reason, seq.altitude))
        log.info("%s: %s %s", seq.name, phase.value, reason)
        self._notifier.settle(seq.future, self._store.record_locked(seq.name, status, reason))

    def progress(self, seq) -> None:
        progress = SequenceProgress(seq.phase, seq.detail, seq.altitude)
        if self._store.state.takeoff != progress:
            self._store.set(takeoff=progress)
            self._store.publish()
            log.info("%s: %s %s", seq.name, seq.phase.value, seq.detail)

    def abort(self, why: str) -> None:
        """Stop the sequence and cancel what it asked the vehicle, so no retry launches it afterwards."""
        seq = self.current
        if seq is None:
            return
        self.current = None
        sent = self._commands.cancel_tagged(seq, f"takeoff aborted: {why}")
        if any(command == mavlink.MAV_CMD_NAV_TAKEOFF for command, _ in sent):
            # a command on its way cannot be called back: say so rather than promise the ground
            self._store.add_message_locked(Severity.WARNING, "Takeoff aborted after NAV_TAKEOFF went out: if "
                                           "the vehicle got it, it lifts off (Land brings it down)")
        self._store.set(takeoff=SequenceProgress(SequencePhase.ABORTED, f"aborted: {why}", seq.altitude))
        self._notifier.settle(seq.future, self._store.record_locked(
            seq.name, CommandStatus.ABORTED, f"aborted by the pilot ({why})"))
