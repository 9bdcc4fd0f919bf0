"""Follow: keep a moving target in frame at the offset the vehicle had when the shot began.

The target's fixes come from a position source (:mod:`driver.shots.targets`: the laptop's GPS over NMEA or gpsd,
or positions given over Ice). Two engines fly it:

* **FOLLOW** (ArduCopter 4.x's own mode, mode_follow.cpp with AP_Follow): the driver sets FOLL_ENABLE, FOLL_SYSID
  (its own system id), the offset in FOLL_OFS_X/Y/Z (NED, FOLL_OFS_TYPE 0), FOLL_YAW_BEHAVE 1 (face the target)
  and FOLL_ALT_TYPE 1 (altitudes above home), switches to FOLLOW and sends each fix as FOLLOW_TARGET: the
  autopilot steers itself, dead-reckoning between fixes, and stops by itself 3 s after the last one
  (AP_FOLLOW_TIMEOUT_MS). The sticks do nothing in it (ArduPilot's own TODO).
* **GUIDED** (any ArduCopter, the Solo's 3.3 too): the driver computes the target (the fix moved on by its velocity
  for up to a second, plus the offset) and flies it as position with the target's velocity fed forward (its
  changes held to the acceleration limit, as shotmanager's follow did), the nose and camera on the target. Here
  the sticks work as in Orbit: right/left swings round the target, forward/back closes in or backs off, throttle
  climbs.

Either way, when the fixes stop for :data:`LOST` seconds the shot holds position and says so; it follows again
when they come back. A target (plus the offset) beyond the limits is held at, not chased.
"""
from __future__ import annotations

import math

from .base import CLIMB_RATE, Shot, toward
from .model import ShotKind, ShotPhase, Sticks
from .orbit import MIN_RADIUS, RADIAL_SPEED, strafe_limit
from .setpoint import Target, aim_error, bearing, camera_look, here, horizontal, look_pitch
from .spline import ACCEL_LIMIT, PLANNED_TANGENT, PLAN_SHARE

__all__ = ["Follow", "LOST", "PREDICT"]

LOST = 3.0                   # s without a fix: hold (AP_FOLLOW_TIMEOUT_MS)
PREDICT = 1.0                # s a fix is moved on by its velocity at most


class Follow(Shot):
    kind = ShotKind.FOLLOW

    def __init__(self, latest, start: tuple[float, float, float], now: float, engine: str = "GUIDED",
                 allowed=None, to_ned=None):
        """``latest()`` gives the newest fix (:class:`~driver.shots.targets.TargetFix`) or None; ``to_ned(fix)``
        its (north, east, up) m from home; ``start`` where the vehicle is now."""
        super().__init__()
        self.latest, self.to_ned = latest, to_ned
        self.engine = engine
        self.allowed = allowed or (lambda n, e, u: True)
        fix = latest()
        if fix is None or now - fix.time > LOST:
            raise ValueError("no fix of the target yet (or none for 3 s): is its position source sending?")
        t = to_ned(fix)
        self.offset = [start[0] - t[0], start[1] - t[1], start[2] - t[2]]
        if math.hypot(self.offset[0], self.offset[1]) < MIN_RADIUS:
            raise ValueError(f"the vehicle is {math.hypot(*self.offset[:2]):.1f} m from the target: back off first")
        self.vel = [fix.vn, fix.ve, -fix.vd]
        self.hold: tuple[float, float, float] | None = None
        self.last_fix = fix
        self.swing = self.closing = self.climb = 0.0

    def predicted(self, now: float):
        """(north, east, up) of the target now, and its fix; None when the fixes stopped."""
        fix = self.latest()
        if fix is None or now - fix.time > LOST:
            return None
        self.last_fix = fix
        t = self.to_ned(fix)
        ahead = min(max(now - fix.time, 0.0), PREDICT)
        return (t[0] + fix.vn * ahead, t[1] + fix.ve * ahead, t[2] - fix.vd * ahead), fix

    def step(self, now: float, dt: float, state, sticks: Sticks) -> Target | None:
        seen = self.predicted(now)
        pos = here(state)
        if seen is None:
            if self.phase is not ShotPhase.HOLDING:
                age = now - self.last_fix.time if self.last_fix is not None else float("inf")
                self.phase, self.detail = ShotPhase.HOLDING, f"no fix of the target for {age:.0f} s: holding position"
                self.hold = pos
                self.vel = [0.0, 0.0, 0.0]
            if self.hold is None:
                return None
            return Target(*self.hold, yaw=state.heading_deg)
        target, fix = seen
        a = ACCEL_LIMIT * PLAN_SHARE / math.sqrt(3.0) * dt          # per axis: the vector stays within the limit
        want = (fix.vn, fix.ve, -fix.vd)
        self.vel = [toward(v, w, a) for v, w in zip(self.vel, want)]
        self._sticks(dt, sticks)
        goal = (target[0] + self.offset[0], target[1] + self.offset[1], target[2] + self.offset[2])
        if not self.allowed(*goal):
            self.phase, self.detail = ShotPhase.HOLDING, "the target's offset point is beyond the limits: holding"
            self.hold = self.hold or pos
            return Target(*self.hold, yaw=bearing(target[0] - self.hold[0], target[1] - self.hold[1]),
                          pitch=look_pitch(self.hold, target)) if self.hold else None
        if self.phase is ShotPhase.HOLDING:
            self.phase, self.hold = ShotPhase.FLYING, None
        sw = self.swing / max(math.hypot(self.offset[0], self.offset[1]), MIN_RADIUS)
        vn = self.vel[0] - sw * self.offset[1] + self._radial()[0]
        ve = self.vel[1] + sw * self.offset[0] + self._radial()[1]
        return Target(goal[0], goal[1], goal[2], vn, ve, self.vel[2] + self.climb,
                      bearing(target[0] - goal[0], target[1] - goal[1]), math.degrees(-sw),
                      look_pitch(goal, target))

    def _radial(self) -> tuple[float, float]:
        r = max(math.hypot(self.offset[0], self.offset[1]), 1e-6)
        return self.closing * self.offset[0] / r, self.closing * self.offset[1] / r

    def _sticks(self, dt: float, sticks: Sticks) -> None:
        """GUIDED only: swing round the target, close in or back off, climb; the offset moves with them."""
        a = PLANNED_TANGENT * dt
        r = math.hypot(self.offset[0], self.offset[1])
        self.swing = toward(self.swing, -sticks.right * strafe_limit(r), a)
        self.closing = toward(self.closing, -sticks.forward * RADIAL_SPEED, a)
        self.climb = toward(self.climb, sticks.up * CLIMB_RATE, a)
        angle = math.atan2(self.offset[1], self.offset[0]) + self.swing / max(r, MIN_RADIUS) * dt
        r = max(r + self.closing * dt, MIN_RADIUS)
        self.offset = [r * math.cos(angle), r * math.sin(angle), self.offset[2] + self.climb * dt]

    def report(self, state) -> dict:
        pos, fix = here(state), self.last_fix
        if pos is None or fix is None:
            return {}
        t = self.to_ned(fix)
        distance = math.dist(pos, t)
        out = {"target_distance": distance, "radius": horizontal(t, pos), "radius_wanted": math.hypot(*self.offset[:2]),
               "aim_error": aim_error(camera_look(state), look_pitch(pos, t), bearing(t[0] - pos[0], t[1] - pos[1]))}
        if self.phase is ShotPhase.FLYING:
            self.detail = f"following at {distance:.1f} m ({self.engine})"
        return out
