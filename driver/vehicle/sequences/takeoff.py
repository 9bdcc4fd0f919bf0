"""The takeoff sequence, written against the public :class:`~driver.vehicle.api.Drone` interface.

Wait for the link and for readiness, GUIDED, arm, NAV_TAKEOFF, climb to 95 % of the target. It is a
state machine the driver's ticker steps (no thread of its own, never blocking): each step reads the
vehicle's state and the futures of the commands it issued.

It judges by the vehicle, not by replies: a NAV_TAKEOFF re-sent because its first reply was lost may be
refused (ArduCopter's takeoff.cpp: "can't takeoff again" once it no longer counts as landed) or accepted
(ArduCopter 4.7, see tests/data/recordings) while the vehicle is already climbing; either way, a vehicle that
reports taking off or climbing is climbing, and the sequence never reports FAILED while it does.
"""
from __future__ import annotations

from concurrent.futures import Future
from typing import Protocol

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..state import CommandResult, CommandStatus, LandedState, SequencePhase, VehicleState

__all__ = ["TakeoffSequence", "climb_timeout", "is_climbing"]

JUDGE_WINDOW = 3.0           # s a refused or unanswered NAV_TAKEOFF waits for signs of a climb
CLIMB_EVIDENCE = 0.3         # m/s upwards that only a takeoff gives a vehicle on the pad
SECONDS_PER_METRE = 2.0      # the climb timeout grows with the altitude (a slow 0.5 m/s climb still fits)
ANSWER_RETRIES = 2           # GUIDED or arm asked again this often when the vehicle never answered


class Pilotable(Protocol):
    """What the sequence needs: the Drone interface plus a raw command (the embedded driver has both)."""
    def state(self) -> VehicleState: ...
    def set_mode(self, name: str) -> Future: ...
    def arm(self, force: bool = False) -> Future: ...
    def command_long(self, command: int, params=(), name: str | None = None) -> Future: ...


def climb_timeout(base: float, altitude: float) -> float:
    """Seconds a climb to ``altitude`` metres may take."""
    return base + SECONDS_PER_METRE * altitude


def is_climbing(s: VehicleState) -> bool:
    """The vehicle reports a takeoff under way (or done): landed state, system status, or climb rate."""
    if s.landed_state in (LandedState.TAKEOFF, LandedState.IN_AIR):
        return True
    return s.armed and (s.in_air is True or s.velocity.climb > CLIMB_EVIDENCE)


class TakeoffSequence:
    """One takeoff. ``step(now)`` returns None while it runs, then (status, reason, phase) once."""

    name = "takeoff"                        # what its result is called (driver.mission's MissionStart: its own)

    def __init__(self, drone: Pilotable, altitude: float, config, now: float):
        self.drone = drone
        self.altitude = altitude
        self.future: Future = Future()
        self._cfg = config
        self._stage = "link"
        self._since = now
        self._pending: Future | None = None
        self._answer: CommandResult | None = None
        self._retries = 0                   # commands asked again after no answer at all
        self.takeoff_sent = False           # NAV_TAKEOFF was issued (it may reach the vehicle after an abort)
        self.guided_sent = False            # GUIDED was asked: the vehicle may be in it before it says so
        self.phase = SequencePhase.WAITING_READY
        self.detail = ""
        before = drone.state()                      # what a cancel before liftoff gives back
        self.mode_before, self.armed_before = before.mode, before.armed

    def _go(self, stage: str, now: float, phase: SequencePhase | None = None, detail: str = "") -> None:
        self._stage, self._since, self._pending = stage, now, None
        if phase is not None:
            self.phase, self.detail = phase, detail

    def _result(self) -> CommandResult | None:
        f = self._pending
        return f.result() if f is not None and f.done() else None

    def step(self, now: float):
        s = self.drone.state()
        cfg = self._cfg
        elapsed = now - self._since
        stage = self._stage
        if stage == "link":
            if s.connected:
                self._go("ready", now, SequencePhase.WAITING_READY,
                         "" if s.readiness.ready_to_arm else "waiting for GPS, EKF and pre-arm checks")
            elif elapsed > cfg.ready_timeout:
                return CommandStatus.TIMED_OUT, "no vehicle on the link", SequencePhase.FAILED
        elif stage == "ready":
            if s.readiness.ready_to_arm or elapsed > cfg.ready_timeout:   # then let the vehicle decide
                self._go("guided", now, SequencePhase.SETTING_GUIDED)
            elif s.connected:                       # say what is still awaited, as it arrives
                self.detail = "waiting for " + ", ".join(s.readiness.missing)
        elif stage == "guided":
            if self._pending is None:
                self._pending = self.drone.set_mode("GUIDED")
                self.guided_sent = True
            r = self._result()
            if r is not None:
                if not r.ok and not self._ask_again(r):
                    return r.status, f"GUIDED: {r.reason}", SequencePhase.FAILED
                if r.ok or s.mode == "GUIDED":
                    self._go("arm", now, SequencePhase.ARMING)
        elif stage == "arm":
            if s.armed:
                return self._start_takeoff(now)
            if self._pending is None:
                self._pending = self.drone.arm()
            r = self._result()
            if r is not None:
                if not r.ok and not self._ask_again(r):
                    return r.status, f"arming: {r.reason}", SequencePhase.FAILED
                if r.ok:
                    self._go("armed?", now)
        elif stage == "armed?":
            if s.armed:
                return self._start_takeoff(now)
            if elapsed > 2 * cfg.command_timeout:
                return CommandStatus.REFUSED, "the vehicle did not report armed", SequencePhase.FAILED
        elif stage == "takeoff":
            if self._pending is None:
                self.takeoff_sent = True
                self._pending = self.drone.command_long(mavlink.MAV_CMD_NAV_TAKEOFF, (0, 0, 0, 0, 0, 0, self.altitude),
                                                        f"NAV_TAKEOFF {self.altitude:.1f} m")
            r = self._result()
            if r is not None:
                if r.ok:
                    self._go("climb", now, SequencePhase.CLIMBING, f"to {self.altitude:.1f} m")
                else:
                    self._answer = r
                    self._go("judge", now)
        elif stage == "judge":
            r = self._answer
            if is_climbing(s):
                self._go("climb", now, SequencePhase.CLIMBING,
                         f"to {self.altitude:.1f} m (the vehicle climbs; NAV_TAKEOFF was answered {r.status.value})")
            elif not s.armed or elapsed > JUDGE_WINDOW:
                return r.status, f"takeoff command: {r.reason}", SequencePhase.FAILED
        elif stage == "climb":
            if not s.armed:
                return CommandStatus.REFUSED, "the vehicle disarmed during the climb", SequencePhase.FAILED
            if s.altitude >= 0.95 * self.altitude:
                return CommandStatus.ACCEPTED, f"reached {s.altitude:.1f} m", SequencePhase.DONE
            if elapsed > climb_timeout(cfg.climb_timeout, self.altitude) and not s.velocity.climb > CLIMB_EVIDENCE:
                return (CommandStatus.TIMED_OUT, f"did not reach {self.altitude:.1f} m (at {s.altitude:.1f} m)",
                        SequencePhase.FAILED)
        return None

    @property
    def nothing_flown(self) -> bool:
        """Before NAV_TAKEOFF: the vehicle may have been switched or armed, but nothing has left the ground."""
        return not self.takeoff_sent

    def _ask_again(self, r: CommandResult) -> bool:
        """A command the vehicle never answered (lost both ways on a bad link) is asked again, up to
        ANSWER_RETRIES times: no answer is not a refusal. The caller checks first whether the vehicle did it."""
        if r.status is not CommandStatus.TIMED_OUT or self._retries >= ANSWER_RETRIES:
            return False
        self._retries += 1
        self._pending = None
        return True

    def _start_takeoff(self, now: float):
        self._go("takeoff", now, SequencePhase.TAKING_OFF, f"to {self.altitude:.1f} m")
        return None
