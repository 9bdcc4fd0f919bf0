"""Stop: the vehicle ends holding where it is, or on the ground disarmed; never in a mode that needs a throttle.

    on the ground, disarmed ───────────────────────────────→ done ("nothing to stop")
    a motor test may run:          end test ──────────────→ done  (DO_MOTOR_TEST, timeout 0: the vehicle disarms)
    before liftoff, not airborne:  disarm → restore → done  (what a cancelled takeoff changed, undone)
                                     └ refused ──────┐
    may be airborne (or armed):    guided ─→ holding ─→ watching → done
                                     └ refused → brake ─→ watching → done

Which branch is taken is decided when the pilot presses Stop, with the vehicle's state lock held: a vehicle that
*may be airborne* (:mod:`driver.vehicle.safety`) is never disarmed nor given back a throttle mode, whatever the
sequence it interrupts had done. Holding is GUIDED with zero velocity, where ArduCopter brakes to its stopping
point and holds it (ModeGuided::init); BRAKE where GUIDED is refused (no position). The pilot hears the answer as
soon as the vehicle holds; the sequence then watches until every message that could lift the vehicle again
(a MISSION_START or NAV_TAKEOFF still on its way) can no longer arrive, and holds again if one did.
"""
from __future__ import annotations

from concurrent.futures import Future

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..commands import CommandFuture
from ..state import CommandStatus, SequencePhase, VehicleState
from .machine import Machine, Outcome, Pilot

__all__ = ["StopSequence"]

LIFTING = (mavlink.MAV_CMD_MISSION_START, mavlink.MAV_CMD_NAV_TAKEOFF)


class StopSequence:
    """One Stop. ``interrupted``: the takeoff or mission start it ends (None: none ran), with ``lifting_sent``,
    ``armed_before`` and ``mode_before``; ``airborne``: the flight rules' "may be airborne" at the press; ``armed``:
    armed as shown, or an arm or disarm still on its way."""

    name = "stop"
    exclusive = False
    altitude = 0.0

    def __init__(self, pilot: Pilot, now: float, interrupted=None, airborne: bool = True, armed: bool = True,
                 testing: bool = False) -> None:
        self.pilot = pilot
        self.future: Future = CommandFuture()
        self.answer: Outcome | None = None
        self.phase, self.detail = SequencePhase.IDLE, ""
        self._interrupted = interrupted
        self.machine = Machine("decide", now, {
            "decide": self._decide, "disarm": self._disarm, "restore": self._restore, "guided": self._guided,
            "brake": self._brake, "holding": self._holding, "watching": self._watching, "end test": self._end_test})
        self._airborne = airborne
        self._testing = testing                       # a motor test runs, or one went out that may
        self._armed = armed                           # armed, or an arm or disarm on its way may have made it so
        self._held_in = ""
        self._guided_refusal = ""
        self._again = False                           # holding again after a late lifting message

    @property
    def state(self) -> str:
        return self.machine.state

    def step(self, s: VehicleState, now: float) -> Outcome | None:
        return self.machine.step(s, now)

    # -- the states --------------------------------------------------------------------------------------------
    def _decide(self, s: VehicleState, now: float):
        m, seq = self.machine, self._interrupted
        armed = self._armed or s.armed
        if self._testing and not self._airborne:      # motors spinning on the bench: they stop first
            m.go("end test", now)
            return None
        if not self._airborne and seq is not None and not seq.armed_before and (seq.ground.arm_sent or armed):
            m.go("disarm", now)                       # armed by the cancelled takeoff, nothing lifted: undo it (the
            return None                               # state may not show the arm yet: disarm all the same)
        if not self._airborne and not armed:
            if seq is not None and seq.ground.guided_sent and seq.mode_before and seq.mode_before != "GUIDED":
                m.go("restore", now)                  # a takeoff cancelled after it asked GUIDED
                return None
            return Outcome(CommandStatus.ACCEPTED, "cancelled before liftoff: the vehicle was not changed" if seq
                           else "on the ground: nothing to stop")
        if s.mode == "GUIDED" and not self._airborne:   # on the pad in GUIDED: nothing can have changed it
            m.go("holding", now)
        else:                                           # the mode shown may be older than a MISSION_START on its way:
            m.go("guided", now)                         # ask, and hold once a fresh heartbeat shows GUIDED
        return None

    def _end_test(self, s: VehicleState, now: float):
        """ArduCopter's motor test takes a timeout of 0 as the end of the test: it stops and disarms itself
        (motor_test.cpp); the test asked before, if still unanswered, is replaced and never sent again."""
        r = self.machine.ask(lambda: self.pilot.long(mavlink.MAV_CMD_DO_MOTOR_TEST, (1, 0, 0, 0, 0),
                                                     "stop motor test"))
        if r is None:
            return None
        if r.ok:
            return Outcome(CommandStatus.ACCEPTED, "motor test stopped: the vehicle disarms itself")
        if r.status is CommandStatus.REJECTED:        # the flight rules: the test's run is over (it ended by
            self._testing = False                     # itself meanwhile): Stop decides as for any other state
            self.machine.go("decide", now)
            return None
        return Outcome(r.status, f"the motor test may still run: {r.reason}", SequencePhase.FAILED)

    def _disarm(self, s: VehicleState, now: float):
        r = self.machine.ask(lambda: self.pilot.disarm())
        if r is None:
            return None
        if r.ok:
            self.machine.go("restore", now)
        elif r.status is CommandStatus.REJECTED:      # the flight rules: it may be airborne after all
            self.machine.go("guided" if s.mode != "GUIDED" else "holding", now)
        else:
            return Outcome(r.status, f"cancelled before liftoff, but disarming: {r.reason}", SequencePhase.FAILED)
        return None

    def _restore(self, s: VehicleState, now: float):
        seq = self._interrupted
        before = seq.mode_before if seq is not None else ""
        if not before or s.mode == before:
            return Outcome(CommandStatus.ACCEPTED, "cancelled before liftoff: " + self._undone(s))
        r = self.machine.ask(lambda: self.pilot.mode(before))
        if r is None:
            return None
        if r.status is CommandStatus.REJECTED:        # a mode the rules forbid now: hold instead
            self.machine.go("guided" if s.mode != "GUIDED" else "holding", now)
            return None
        return Outcome(CommandStatus.ACCEPTED if r.ok else r.status,
                       "cancelled before liftoff: " + self._undone(s) + ("" if r.ok else f" ({r.reason})"))

    def _undone(self, s: VehicleState) -> str:
        seq = self._interrupted
        done = []
        if seq is not None and not seq.armed_before:
            done.append("disarmed")
        if seq is not None and seq.mode_before and s.mode == seq.mode_before and seq.ground.guided_sent:
            done.append(f"back to {seq.mode_before}")
        return ", ".join(done) or "the vehicle was not changed"

    def _guided(self, s: VehicleState, now: float):
        r = self.machine.ask(lambda: self.pilot.mode("GUIDED"))
        if r is None:
            return None
        if r.ok:
            self.machine.go("holding", now)
        else:
            self._guided_refusal = r.reason
            self.machine.go("brake", now)
        return None

    def _brake(self, s: VehicleState, now: float):
        r = self.machine.ask(lambda: self.pilot.mode("BRAKE"))
        if r is None:
            return None
        if not r.ok:
            return Outcome(r.status, f"GUIDED refused ({self._guided_refusal}) and BRAKE too: {r.reason}",
                           SequencePhase.FAILED)
        self._held_in = "BRAKE"
        self.answer = Outcome(CommandStatus.ACCEPTED, f"GUIDED refused ({self._guided_refusal}): BRAKE, holding")
        self.machine.go("watching", now)
        return None

    def _holding(self, s: VehicleState, now: float):
        self._held_in = "GUIDED"
        if self._again:                               # zeros went out at the press; again after a late AUTO
            self.pilot.hold()
        was = self._interrupted.name if self._interrupted is not None else ""
        self.answer = Outcome(CommandStatus.ACCEPTED, "holding position in GUIDED" +
                              (f" ({was} stopped)" if was else "") + ": the sticks fly")
        self.machine.go("watching", now)
        return None

    def _watching(self, s: VehicleState, now: float):
        """Until no lifting message can still arrive: if one did (the vehicle left the hold for AUTO), hold again.
        Any other change of mode is the pilot's (an RC switch): not fought."""
        if s.mode == "AUTO" and s.armed:
            self._again = True
            self.machine.go("guided", now)
            return None
        if all(self.pilot.quiet(command) for command in LIFTING):
            return Outcome(CommandStatus.ACCEPTED, f"holding position in {self._held_in or s.mode}")
        return None
