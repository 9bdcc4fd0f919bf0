"""Land and RTL: the mode asked, then the vehicle followed down to the ground and to its own disarm.

    Land: asked → descending → on the ground → done (disarmed)
    RTL:  asked → returning → landing → on the ground → done (disarmed)

Each is answered once the heartbeat shows the mode (the pilot's Land or RTL is accepted); the sequence then
goes on following what the vehicle reports, so the pilot sees where in the landing it is, until ArduCopter
disarms by itself on the ground. Leaving the mode (another command, the pilot's RC) ends it there. Neither ever
disarms: ArduCopter does that once landed.
"""
from __future__ import annotations

from concurrent.futures import Future

from ..commands import CommandFuture

from ..state import CommandStatus, LandedState, SequencePhase, VehicleState
from .machine import Machine, Outcome, Pilot

__all__ = ["Descent", "land_sequence", "return_sequence"]


class Descent:
    """One mode that ends on the ground (LAND, RTL), followed through ``stages`` while in the air: the next stage
    when the vehicle reports LANDING, "on the ground" when it reports landed."""

    exclusive = False                    # any later command of the pilot ends it (it only follows the vehicle)
    altitude = 0.0

    def __init__(self, pilot: Pilot, mode: str, name: str, stages: tuple[str, ...], now: float) -> None:
        self.pilot = pilot
        self.mode = mode
        self.name = name
        self.stages = stages
        self.future: Future = CommandFuture()
        self.answer: Outcome | None = None      # settled now, while the sequence goes on following the vehicle
        self.phase, self.detail = SequencePhase.IDLE, ""
        handlers = {"asked": self._asked, "on the ground": self._on_ground}
        handlers.update({stage: self._airborne for stage in stages})
        self.machine = Machine("asked", now, handlers)

    @property
    def state(self) -> str:
        return self.machine.state

    def step(self, s: VehicleState, now: float) -> Outcome | None:
        if self.machine.state != "asked" and s.mode and s.mode != self.mode:
            return Outcome(CommandStatus.ACCEPTED, f"left {self.mode} for {s.mode}")
        return self.machine.step(s, now)

    def _asked(self, s: VehicleState, now: float):
        r = self.machine.ask(lambda: self.pilot.mode(self.mode))
        if r is None:
            return None
        if not r.ok:
            return Outcome(r.status, r.reason, SequencePhase.FAILED, result=r)
        self.answer = Outcome(CommandStatus.ACCEPTED, r.reason, result=r)
        self.machine.go(self.stages[0], now)
        return None

    def _airborne(self, s: VehicleState, now: float):
        m = self.machine
        if s.in_air is False or not s.armed:
            m.go("on the ground", now)
            return None
        later = self.stages.index(m.state) + 1
        if later < len(self.stages) and s.landed_state is LandedState.LANDING:
            m.go(self.stages[later], now)
        return None

    def _on_ground(self, s: VehicleState, now: float):
        if not s.armed:
            return Outcome(CommandStatus.ACCEPTED, "landed and disarmed")
        if s.in_air:                                  # a bounce, or the pilot took off again
            self.machine.go(self.stages[0], now)
        return None


def land_sequence(pilot: Pilot, now: float) -> Descent:
    """LAND where the vehicle is."""
    return Descent(pilot, "LAND", "mode LAND", ("descending",), now)


def return_sequence(pilot: Pilot, now: float) -> Descent:
    """RTL: home, then land there."""
    return Descent(pilot, "RTL", "mode RTL", ("returning", "landing"), now)
