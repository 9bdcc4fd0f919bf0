"""What every shot is to the part that runs it (:mod:`driver.shots.control`), and the feel they share.

A shot is pure: :meth:`Shot.step` takes the time, the vehicle's latest snapshot and the pilot's sticks and
returns the :class:`~driver.shots.setpoint.Target` to fly now; :meth:`Shot.report` reads from the same snapshot
where the vehicle really is on the shot. The clock is passed in, so a test steps a shot as fast as it likes.

The sticks feel as on 3DR's Solo (shotmanager's pathHandler): with no cruise speed a stick sets the speed
(full stick: the shot's top speed); with a cruise speed, a stick the same way speeds it up toward the top speed
and a stick against it slows it down, to a stop at full deflection. Speeds change no faster than the tangential
share of the acceleration limit.
"""
from __future__ import annotations

import math

from .model import ShotKind, ShotPhase, Sticks
from .setpoint import Target

__all__ = ["Shot", "stick_speed", "toward", "MAX_SPEED", "CLIMB_RATE"]

MAX_SPEED = 8.0              # m/s: the Solo's shots' top speed (shotManagerConstants.MAX_SPEED)
FACING = 5.0                 # degrees: the nose this near what the camera should see, a shot sets off
TURN_WAIT = 8.0              # s it waits for that at most
CLIMB_RATE = 1.25            # m/s at full throttle stick: PILOT_SPEED_UP 250 cm/s halved, as the Solo's 1.33×0.95


def stick_speed(cruise: float, stick: float, top: float) -> float:
    """The speed the pilot asks for: ``stick`` (-1..1) alone, or bending the ``cruise`` speed (signed)."""
    if cruise == 0.0:
        return stick * top
    speed = abs(cruise)
    if stick and math.copysign(1.0, stick) != math.copysign(1.0, cruise):
        speed *= 1.0 - abs(stick)
    else:
        speed += (top - speed) * abs(stick)
    return math.copysign(min(speed, top), cruise)


def toward(value: float, wanted: float, step: float) -> float:
    """``value`` moved toward ``wanted`` by at most ``step``."""
    return min(max(wanted, value - step), value + step)


class Shot:
    """One shot in flight; subclasses fill in :meth:`step` and :meth:`report`."""
    kind = ShotKind.NONE
    engine = "GUIDED"

    def __init__(self) -> None:
        self.phase = ShotPhase.FLYING
        self.detail = ""
        self.cruise = 0.0                 # m/s when the sticks are centred (signed: the shot's own sense)
        self.paused_cruise: float | None = None
        #: (north, east, up) the vehicle's region of interest is set to at the start (the gimbal points itself)
        self.roi: tuple[float, float, float] | None = None
        self.faced, self._turning_since = False, None

    def facing(self, now: float, state, bearing: float, what: str) -> bool:
        """Whether the shot may set off: the vehicle's nose (its own report) within FACING degrees of ``bearing``,
        or TURN_WAIT s spent turning; until then the shot holds where it began, turning, so the camera is on
        ``what`` from the first metre."""
        if self.faced:
            return True
        self._turning_since = now if self._turning_since is None else self._turning_since
        off = abs((state.heading_deg - bearing + 180.0) % 360.0 - 180.0)
        if off > FACING and now - self._turning_since < TURN_WAIT:
            self.detail = f"turning to {what}: {off:.0f}° to go"
            return False
        self.faced = True
        return True

    def step(self, now: float, dt: float, state, sticks: Sticks) -> Target | None:
        raise NotImplementedError

    def report(self, state) -> dict:
        """The ShotState fields this shot measures from ``state`` (its telemetry)."""
        return {}

    # -- the pilot's buttons ----------------------------------------------------------------------------
    def pause(self) -> str:
        if self.paused_cruise is None:
            self.paused_cruise, self.cruise = self.cruise, 0.0
        self.phase = ShotPhase.PAUSED if self.phase is ShotPhase.FLYING else self.phase
        return "paused: the sticks still move it"

    def resume(self) -> str:
        if self.paused_cruise is not None:
            self.cruise, self.paused_cruise = self.paused_cruise, None
        if self.phase is ShotPhase.PAUSED:
            self.phase = ShotPhase.FLYING
        return f"cruising at {self.cruise:+.1f} m/s"

    def reverse(self) -> str:
        if self.paused_cruise is not None:
            self.paused_cruise = -self.paused_cruise
            return f"reversed: {self.paused_cruise:+.1f} m/s once resumed"
        self.cruise = -self.cruise
        return f"reversed: {self.cruise:+.1f} m/s"

    def set_cruise(self, speed: float) -> str:
        speed = max(-MAX_SPEED, min(MAX_SPEED, float(speed)))
        if self.paused_cruise is not None:
            self.paused_cruise = speed
            return f"{speed:+.1f} m/s once resumed"
        self.cruise = speed
        return f"cruising at {speed:+.1f} m/s"
