"""The takeoff: link, readiness, GUIDED, arm (:class:`~.preparation.GroundStart`), NAV_TAKEOFF, climb to 95 %.

    link → ready → guided → arm → takeoff → climb → done
                                         ↘ judge ↗

It judges by the vehicle, not by replies: a NAV_TAKEOFF re-sent because its first reply was lost may be refused
(ArduCopter's takeoff.cpp: "can't takeoff again" once it no longer counts as landed) or accepted (ArduCopter 4.7,
see tests/data/recordings) while the vehicle is already climbing; either way, a vehicle that reports taking off or
climbing is climbing, and the sequence never reports FAILED while it does (``judge``).
"""
from __future__ import annotations

from concurrent.futures import Future

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..commands import CommandFuture
from ..state import CommandStatus, LandedState, SequencePhase, VehicleState
from .machine import Machine, Outcome, Pilot
from .preparation import GroundStart

__all__ = ["TakeoffSequence", "climb_timeout", "is_climbing"]

JUDGE_WINDOW = 3.0           # s a refused or unanswered NAV_TAKEOFF waits for signs of a climb
CLIMB_EVIDENCE = 0.3         # m/s upwards that only a takeoff gives a vehicle on the pad
SECONDS_PER_METRE = 2.0      # the climb timeout grows with the altitude (a slow 0.5 m/s climb still fits)


def climb_timeout(base: float, altitude: float) -> float:
    """Seconds a climb to ``altitude`` metres may take."""
    return base + SECONDS_PER_METRE * altitude


def is_climbing(s: VehicleState) -> bool:
    """The vehicle reports a takeoff under way (or done): landed state, system status, or climb rate."""
    if s.landed_state in (LandedState.TAKEOFF, LandedState.IN_AIR):
        return True
    return s.armed and (s.in_air is True or s.velocity.climb > CLIMB_EVIDENCE)


class TakeoffSequence:
    """One takeoff. ``step(state, now)`` returns None while it runs, then an :class:`Outcome` once."""

    name = "takeoff"
    exclusive = True                     # while it runs only Land, Stop and RTL are taken

    def __init__(self, pilot: Pilot, altitude: float, config, now: float):
        self.pilot = pilot
        self.altitude = altitude
        self.future: Future = CommandFuture()
        self._cfg = config
        self.phase, self.detail = SequencePhase.WAITING_READY, ""
        before = pilot.state()                      # what a cancel before liftoff gives back
        self.mode_before, self.armed_before = before.mode, before.armed
        self.ground = GroundStart(pilot, config, "takeoff", self.report)
        self.machine = Machine("link", now, {**self.ground.handlers(), "takeoff": self._takeoff,
                                             "judge": self._judge, "climb": self._climb})
        self.ground.bind(self.machine)
        self._refusal = None
        self.seen_armed = False              # the heartbeat has shown the vehicle armed since the start

    def _disarmed(self, s: VehicleState) -> bool:
        """Disarmed after the heartbeat showed it armed (an accepted arm shows in the next heartbeat only)."""
        return self.seen_armed and not s.armed

    def report(self, phase: SequencePhase, detail: str) -> None:
        self.phase, self.detail = phase, detail

    @property
    def state(self) -> str:
        return self.machine.state

    @property
    def lifting_sent(self) -> bool:
        """NAV_TAKEOFF was asked: from here on only a hold stops it, never a disarm."""
        return self.machine.state in ("takeoff", "judge", "climb")

    def step(self, s: VehicleState, now: float) -> Outcome | None:
        self.seen_armed = self.seen_armed or s.armed
        if self.machine.state == "takeoff" and self.phase is not SequencePhase.TAKING_OFF:
            self.report(SequencePhase.TAKING_OFF, f"to {self.altitude:.1f} m")
        return self.machine.step(s, now)

    def _takeoff(self, s: VehicleState, now: float):
        m = self.machine
        r = m.ask(lambda: self.pilot.long(mavlink.MAV_CMD_NAV_TAKEOFF, (0, 0, 0, 0, 0, 0, self.altitude),
                                          f"NAV_TAKEOFF {self.altitude:.1f} m"))
        if r is None:
            return None
        if r.ok:
            m.go("climb", now)
            self.report(SequencePhase.CLIMBING, f"to {self.altitude:.1f} m")
        else:
            self._refusal = r
            m.go("judge", now)
        return None

    def _judge(self, s: VehicleState, now: float):
        r = self._refusal
        if is_climbing(s):
            self.machine.go("climb", now)
            self.report(SequencePhase.CLIMBING, f"to {self.altitude:.1f} m (the vehicle climbs; NAV_TAKEOFF was "
                                                f"answered {r.status.value})")
        elif self._disarmed(s) or self.machine.elapsed(now) > JUDGE_WINDOW:
            return Outcome.failed(r, "takeoff command")
        return None

    def _climb(self, s: VehicleState, now: float):
        if self._disarmed(s):
            return Outcome(CommandStatus.REFUSED, "the vehicle disarmed during the climb", SequencePhase.FAILED)
        if not self.seen_armed and self.machine.elapsed(now) > 2 * self._cfg.command_timeout:
            return Outcome(CommandStatus.REFUSED, "the vehicle accepted arming but never reported armed",
                           SequencePhase.FAILED)
        if s.altitude >= 0.95 * self.altitude:
            return Outcome(CommandStatus.ACCEPTED, f"reached {s.altitude:.1f} m")
        if self.machine.elapsed(now) > climb_timeout(self._cfg.climb_timeout, self.altitude) \
                and not s.velocity.climb > CLIMB_EVIDENCE:
            return Outcome(CommandStatus.TIMED_OUT, f"did not reach {self.altitude:.1f} m (at {s.altitude:.1f} m)",
                           SequencePhase.FAILED)
        return None
