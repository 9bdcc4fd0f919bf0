"""Selfie: out and up along the line away from the pilot, and back, the camera on the pilot (the Solo's Selfie).

The vehicle first turns to face the pilot where it is; the line starts there and leads away from the pilot
(horizontally, from the pilot through the vehicle), ``distance`` metres out and ``rise`` metres up. The vehicle
cruises out, waits at the far end until it is there (3 s at most), comes back and stops where it began: the shot
is then done, hovering there. The camera stays on the pilot: the vehicle's
region of interest is the pilot's place (the mount tilts to it) and the nose faces the pilot.

Sticks (the Solo's TwoPointPathHandler): forward/back or right/left, whichever is pushed further, moves along
the line, forward/right outward; with the cruise speed they bend it.
"""
from __future__ import annotations

import math

from .base import MAX_SPEED, Shot, stick_speed
from .model import ShotKind, ShotPhase, Sticks
from .setpoint import Target, aim_error, bearing, camera_look, here, horizontal, look_pitch
from .spline import PathRun, SpeedProfile, Spline

__all__ = ["Selfie", "MIN_PILOT_DISTANCE"]

MIN_PILOT_DISTANCE = 2.0     # m: nearer than this the line away from the pilot has no direction
TOP_WAIT = 3.0               # s at most at the far end before coming back


class Selfie(Shot):
    kind = ShotKind.SELFIE

    def __init__(self, pilot: tuple[float, float, float], start: tuple[float, float, float],
                 distance: float = 30.0, rise: float = 15.0, speed: float = 3.0):
        super().__init__()
        away = horizontal(pilot, start)
        if away < MIN_PILOT_DISTANCE:
            raise ValueError(f"the vehicle is {away:.1f} m from the pilot: fly it out a little first")
        if not (1.0 <= distance <= 200.0 and 0.0 <= rise <= 100.0 and 0.1 <= speed <= MAX_SPEED):
            raise ValueError("a selfie goes 1 to 200 m out, 0 to 100 m up, at 0.1 to 8 m/s")
        un, ue = (start[0] - pilot[0]) / away, (start[1] - pilot[1]) / away
        self.pilot, self.start = pilot, start
        self.end = (start[0] + un * distance, start[1] + ue * distance, start[2] + rise)
        self.line = Spline([start, self.end])
        self.run = PathRun(SpeedProfile(self.line, max(speed, 0.1)))
        self.cruise = speed
        self.top = speed
        self.roi = pilot
        self.leg = "out"
        self._top: float | None = None

    def path_points(self, step: float = 2.0) -> list[tuple[float, float, float]]:
        return self.line.sample(step)

    def drawing(self, step: float = 2.0, look_every: float = 10.0):
        pts = self.line.sample(step)
        looks = [(n, e, bearing(self.pilot[0] - n, self.pilot[1] - e), look_pitch((n, e, u), self.pilot))
                 for n, e, u in (pts[0], pts[-1])]
        return pts, looks

    def step(self, now: float, dt: float, state, sticks: Sticks) -> Target:
        run = self.run
        facing = bearing(self.pilot[0] - self.start[0], self.pilot[1] - self.start[1])
        if not self.facing(now, state, facing, "the pilot"):    # the shot starts on them
            return Target(*self.start, yaw=facing)
        if self.phase is not ShotPhase.DONE:
            stick = sticks.right if abs(sticks.right) > abs(sticks.forward) else sticks.forward
            run.step(dt, stick_speed(self.cruise, stick, self.top))
            if self.cruise > 0 and run.at_end and run.speed == 0.0:
                # a moment at the top: back once the vehicle itself is there (it trails its target a little)
                self._top = now if self._top is None else self._top
                pos = here(state)
                if now - self._top >= TOP_WAIT or (pos is not None and math.dist(pos, self.end) < 0.3):
                    self.cruise, self.leg = -self.cruise, "back"
            elif self.cruise < 0 and run.at_start and run.speed == 0.0:
                self.cruise, self.phase, self.detail = 0.0, ShotPhase.DONE, "back where it began: done"
        n, e, u = self.line.point(run.s)
        vn, ve, vu = run.velocity()
        return Target(n, e, u, vn, ve, vu, bearing(self.pilot[0] - n, self.pilot[1] - e), 0.0)

    def report(self, state) -> dict:
        pos = here(state)
        if pos is None:
            return {}
        s = self.line.nearest(pos)
        t = self.line.tangent(s)
        v = state.velocity
        along = v.north * t[0] + v.east * t[1] - v.down * t[2]
        if self.phase in (ShotPhase.FLYING, ShotPhase.PAUSED) and not self.detail.startswith("at the"):
            self.detail = f"{self.leg}: {s:.0f} of {self.line.length:.0f} m"
        p = self.pilot
        return {"progress": s / self.line.length, "speed": along,
                "aim_error": aim_error(camera_look(state), look_pitch(pos, p), bearing(p[0] - pos[0], p[1] - pos[1]))}
