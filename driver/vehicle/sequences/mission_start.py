"""The mission start: link, readiness, GUIDED, arm (:class:`~.preparation.GroundStart`), MISSION_START, running.

    link → ready → guided → arm → start → running → done
    (armed or flying already: straight to start)

As QGroundControl's ArduPilot plugin does (APMFirmwarePlugin::startMission): from the ground GUIDED, arm, then
MISSION_START; in the air MISSION_START alone. ArduCopter's MISSION_START (GCS_MAVLINK_Copter::
handle_MAV_CMD_MISSION_START) switches to AUTO itself, lets the takeoff item lift off (auto_armed) and starts or
resumes the mission, so no separate AUTO step waits between arming and the start: an armed copter on the ground
disarms itself after DISARM_DELAY, and every step a lossy link must confirm eats into it. MISSION_START is
harmless to repeat (a running mission is not restarted), so it goes again at the link's own round trip, not
every 3 s, until a heartbeat the vehicle sent after it shows AUTO (never one from before: the vehicle may have
left AUTO since, for a LAND on its way).

The mission runs when the vehicle says so: its heartbeat in AUTO, and MISSION_CURRENT active (or, from firmware
without the mission state, an item current, or the vehicle climbing).
"""
from __future__ import annotations

from concurrent.futures import Future

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..commands import CommandFuture
from ...mission.plan import MissionRunState
from ..state import CommandStatus, SequencePhase, VehicleState
from .machine import Machine, Outcome, Pilot
from .preparation import GroundStart
from .takeoff import is_climbing

__all__ = ["MissionStartSequence", "CONFIRM_TIME"]

CONFIRM_TIME = 5.0           # s the vehicle's report may take to show the mission running (MISSION_CURRENT streams
                             # at the stream rate; on a lossy link a few are lost)


class MissionStartSequence:
    """One mission start. ``step(state, now)`` returns None while it runs, then an :class:`Outcome` once."""

    name = "mission start"
    exclusive = True
    altitude = 0.0

    def __init__(self, pilot: Pilot, config, now: float):
        self.pilot = pilot
        self.future: Future = CommandFuture()
        self._cfg = config
        self.phase, self.detail = SequencePhase.WAITING_READY, ""
        before = pilot.state()
        self.mode_before, self.armed_before = before.mode, before.armed
        self.ground = GroundStart(pilot, config, "start", self.report)
        self.machine = Machine("link", now, {**self.ground.handlers(), "start": self._start, "running": self._running})
        self.ground.bind(self.machine)
        self.seen_armed = False
        self._auto_fallback = False           # the vehicle knows no MISSION_START: AUTO instead

    def report(self, phase: SequencePhase, detail: str) -> None:
        self.phase, self.detail = phase, detail

    @property
    def state(self) -> str:
        return self.machine.state

    @property
    def lifting_sent(self) -> bool:
        """MISSION_START (or AUTO) was asked: from here on only a hold stops it, never a disarm."""
        return self.machine.state in ("start", "running")

    def step(self, s: VehicleState, now: float) -> Outcome | None:
        self.seen_armed = self.seen_armed or s.armed
        if self.machine.state == "start" and self.phase is not SequencePhase.TAKING_OFF:
            self.report(SequencePhase.TAKING_OFF, "MISSION_START")
        if self.machine.state in ("start", "running") and self.seen_armed and not s.armed:
            return Outcome(CommandStatus.REFUSED, f"the vehicle disarmed before the mission flew (in {s.mode}; on the "
                           "ground it disarms DISARM_DELAY s after arming)", SequencePhase.FAILED)
        return self.machine.step(s, now)

    def _start(self, s: VehicleState, now: float):
        m = self.machine
        if self._auto_fallback:
            r = m.ask(lambda: self.pilot.mode("AUTO", early=True))
        else:                                          # confirmed when a heartbeat sent after it shows AUTO
            r = m.ask(lambda: self.pilot.long(mavlink.MAV_CMD_MISSION_START, (0, 0), "MISSION_START",
                                              retry=self.pilot.retry_interval(), shows_mode="AUTO"))
        if r is None:
            return None
        if r.ok:
            m.go("running", now)
            self.report(SequencePhase.CLIMBING, "waiting for MISSION_CURRENT")
        elif not self._auto_fallback and "UNSUPPORTED" in r.reason:
            self._auto_fallback = True
            m.pending = None
        else:
            return Outcome.failed(r, "MISSION_START" if not self._auto_fallback else "AUTO")
        return None

    def _running(self, s: VehicleState, now: float):
        if s.mode == "AUTO":
            p = s.mission
            if p.state is MissionRunState.ACTIVE or (p.state is MissionRunState.UNKNOWN and p.current):
                return Outcome(CommandStatus.ACCEPTED, f"mission running, item {p.current}")
            if is_climbing(s) and p.state is not MissionRunState.COMPLETE:
                return Outcome(CommandStatus.ACCEPTED, "mission running: the vehicle climbs in AUTO")
        elif self.machine.elapsed(now) > CONFIRM_TIME and s.mode:
            return Outcome(CommandStatus.REFUSED, f"the vehicle accepted MISSION_START but shows {s.mode}",
                           SequencePhase.FAILED)
        if self.machine.elapsed(now) > 2 * CONFIRM_TIME:
            return Outcome(CommandStatus.TIMED_OUT, "AUTO shown, but MISSION_CURRENT never said the mission runs",
                           SequencePhase.FAILED)
        return None
