"""What a takeoff and a mission start from the ground share: the link, readiness, GUIDED, arming.

:class:`GroundStart` is a part a sequence composes (its states join the sequence's machine), not a base class.
Each step goes on as soon as the vehicle has *accepted* the last one (its ACK, taken only when it can answer
nothing else, or the heartbeat showing it): ArduCopter changes mode and arms inside the command's handler, so an
accepted GUIDED is GUIDED. Waiting out a heartbeat between steps would cost a second each, and on a lossy link a
vehicle armed on the ground disarms itself after DISARM_DELAY (10 s) if the next step is too slow.

A request the vehicle never answered at all (lost both ways) is asked again, up to :data:`ANSWER_RETRIES` times:
no answer is not a refusal.
"""
from __future__ import annotations

from typing import Callable

from ..state import CommandResult, CommandStatus, SequencePhase, VehicleState
from .machine import Machine, Outcome, Pilot

__all__ = ["GroundStart", "ANSWER_RETRIES"]

ANSWER_RETRIES = 2           # GUIDED or arm asked again this often when the vehicle never answered

#: The states a GroundStart adds to its sequence's machine, in order.
STATES = ("link", "ready", "guided", "arm")


class GroundStart:
    """Link, readiness, GUIDED and arming; then ``then`` (the sequence's own next state)."""

    def __init__(self, pilot: Pilot, config, then: str, report: Callable[[SequencePhase, str], None]) -> None:
        self._pilot = pilot
        self._cfg = config
        self._then = then
        self._report = report
        self._retries = 0
        self.machine: Machine | None = None
        self.guided_sent = False             # GUIDED was asked: the vehicle may be in it before it says so
        self.arm_sent = False

    def handlers(self) -> dict:
        return {"link": self._link, "ready": self._ready, "guided": self._guided, "arm": self._arm}

    def bind(self, machine: Machine) -> None:
        self.machine = machine

    # -- the states ----------------------------------------------------------------------------------------
    def _link(self, s: VehicleState, now: float):
        m = self.machine
        if s.connected:
            m.go("ready", now)
            self._report(SequencePhase.WAITING_READY,
                         "" if s.readiness.ready_to_arm else "waiting for GPS, EKF and pre-arm checks")
        elif m.elapsed(now) > self._cfg.ready_timeout:
            return Outcome(CommandStatus.TIMED_OUT, "no vehicle on the link", SequencePhase.FAILED)
        return None

    def _ready(self, s: VehicleState, now: float):
        m = self.machine
        if s.armed:                                   # armed already (by the pilot): nothing to prepare
            m.go(self._then, now)
        elif s.readiness.ready_to_arm or m.elapsed(now) > self._cfg.ready_timeout:   # then the vehicle decides
            m.go("guided", now)
            self._report(SequencePhase.SETTING_GUIDED, "")
        elif s.connected:                             # say what is still awaited, as it arrives
            self._report(SequencePhase.WAITING_READY, "waiting for " + ", ".join(s.readiness.missing))
        return None

    def _guided(self, s: VehicleState, now: float):
        m = self.machine
        if s.armed:
            m.go(self._then, now)
            return None
        self.guided_sent = True
        r = m.ask(lambda: self._pilot.mode("GUIDED", early=True))
        if r is None:
            return None
        if r.ok or s.mode == "GUIDED":
            m.go("arm", now)
            self._report(SequencePhase.ARMING, "")
        elif not self._ask_again(r):
            return Outcome.failed(r, "GUIDED")
        return None

    def _arm(self, s: VehicleState, now: float):
        m = self.machine
        if s.armed:
            m.go(self._then, now)
            return None
        self.arm_sent = True
        r = m.ask(lambda: self._pilot.arm(early=True))
        if r is None:
            return None
        if r.ok:
            m.go(self._then, now)
        elif not self._ask_again(r):
            return Outcome.failed(r, "arming")
        return None

    def _ask_again(self, r: CommandResult) -> bool:
        """Only a request the vehicle never answered goes again, a few times."""
        if r.status is not CommandStatus.TIMED_OUT or self._retries >= ANSWER_RETRIES:
            return False
        self._retries += 1
        self.machine.pending = None
        return True
