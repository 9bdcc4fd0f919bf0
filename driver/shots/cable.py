"""Cable cam (the Solo's multipoint): a smooth cable through 2 to 10 keyframes, flown back and forth.

The pilot records keyframes while flying by hand (the place, the gimbal's pitch and the camera's heading), then
plays them: the vehicle first attaches to the cable, flying straight to a keyframe (the nearest end unless one
is named) at 2 m/s with the camera turning to that keyframe's look, and then rides the cable
(:class:`~driver.shots.spline.Spline`), its speed from the sticks or a cruise speed within the acceleration
limits (:class:`~driver.shots.spline.SpeedProfile`), the camera's look interpolated between the keyframes'
(:class:`~driver.shots.spline.Looks`): the nose turns to the look's heading, the gimbal to its pitch.

Sticks (multipoint.handleRCs): forward/back or right/left, whichever is pushed further, moves along the cable,
forward/right toward the last keyframe; with a cruise speed they bend it. Pause stops where it is (the sticks
still move it), reverse turns the cruise round; reaching an end pauses there, as the Solo did.
"""
from __future__ import annotations

import math

from .base import MAX_SPEED, Shot, stick_speed
from .model import ShotKind, ShotPhase, Sticks
from .setpoint import Target, aim_error, camera_look, here
from .spline import Looks, PathRun, SpeedProfile, Spline

__all__ = ["Cable", "ATTACH_SPEED", "ATTACHED"]

ATTACH_SPEED = 2.0           # m/s to the cable (multipoint's ATTACH_SPEED)
ATTACHED = 0.5               # m: closer to the keyframe than this, the vehicle flies the cable itself
LOOK_STEP = 0.5              # m along the path over which the look's turn rate is measured


class Cable(Shot):
    kind = ShotKind.CABLE

    def __init__(self, points, looks, start: tuple[float, float, float], start_look: tuple[float, float],
                 attach: int | None = None, cruise: float = 0.0, max_speed: float = MAX_SPEED):
        """``points`` (north, east, up) and ``looks`` (pitch, yaw) of the keyframes; ``start`` and ``start_look``
        where the vehicle and its camera are now; ``attach`` the keyframe to join at (None: the nearest end);
        ``cruise`` the speed (m/s) toward the far end once attached (0: the sticks alone)."""
        super().__init__()
        self.spline = Spline(points)
        self.looks = Looks(looks)
        self.profile = SpeedProfile(self.spline, max_speed)
        last = len(points) - 1
        if attach is None:
            attach = 0 if math.dist(start, points[0]) <= math.dist(start, points[last]) else last
        if not 0 <= attach <= last:
            raise ValueError(f"keyframe {attach + 1} does not exist: the cable has {last + 1}")
        self.attach_index = attach
        self.run = PathRun(self.profile, s=self.spline.keyframe_s[attach])
        self.cruise = abs(cruise) * (-1.0 if attach == last else 1.0)
        self.approach: PathRun | None = None
        if math.dist(start, points[attach]) > ATTACHED:
            line = Spline([start, points[attach]])
            self.approach = PathRun(SpeedProfile(line, ATTACH_SPEED))
            self.approach_looks = Looks([start_look, tuple(looks[attach])])
            self.phase = ShotPhase.ATTACHING
        self.max_speed = max_speed

    def path_points(self, step: float = 2.0) -> list[tuple[float, float, float]]:
        """Every place the shot will fly through: the way to the cable, then the cable."""
        out = self.approach.profile.spline.sample(step) if self.approach is not None else []
        return out + self.spline.sample(step)

    def drawing(self, step: float = 2.0, look_every: float = 15.0):
        """(points along the cable, looks (north, east, yaw, pitch) every ``look_every`` m and at each keyframe)."""
        sp = self.spline
        marks = sorted(set([round(s, 3) for s in sp.keyframe_s] +
                           [i * look_every for i in range(1, int(sp.length / look_every) + 1)]))
        looks = []
        for s in marks:
            n, e, _ = sp.point(s)
            pitch, yaw = self.looks.at(float(sp.param(s)))
            looks.append((n, e, yaw, pitch))
        return sp.sample(step), looks

    @staticmethod
    def _aim(run: PathRun, looks: Looks) -> tuple[float, float, float]:
        """(pitch, yaw, yaw rate deg/s) of the look where ``run`` is, the rate from its speed along the path."""
        sp = run.profile.spline
        pitch, yaw = looks.at(float(sp.param(run.s)))
        ahead = min(run.s + LOOK_STEP, sp.length)
        behind = max(ahead - LOOK_STEP, 0.0)
        turn = (looks.at(float(sp.param(ahead)))[1] - looks.at(float(sp.param(behind)))[1] + 180.0) % 360.0 - 180.0
        rate = turn / max(ahead - behind, 1e-6) * run.speed
        return pitch, yaw, rate

    def step(self, now: float, dt: float, state, sticks: Sticks) -> Target:
        if self.phase is ShotPhase.ATTACHING and self.approach is not None:
            run, looks = self.approach, self.approach_looks
            run.step(dt, ATTACH_SPEED)
            if run.at_end and run.speed == 0.0:
                self.phase = ShotPhase.FLYING if self.paused_cruise is None else ShotPhase.PAUSED
        else:
            run, looks = self.run, self.looks
            stick = sticks.right if abs(sticks.right) > abs(sticks.forward) else sticks.forward
            run.step(dt, stick_speed(self.cruise, stick, self.max_speed))
            if self.cruise and run.speed == 0.0 and (run.at_end if self.cruise > 0 else run.at_start):
                self.cruise = 0.0                      # the end of the cable: paused there (the Solo's PAUSED)
                self.phase = ShotPhase.PAUSED
                self.detail = f"at the {'last' if run.at_end else 'first'} keyframe: the sticks fly it back"
        n, e, u = run.profile.spline.point(run.s)
        vn, ve, vu = run.velocity()
        pitch, yaw, rate = self._aim(run, looks)
        return Target(n, e, u, vn, ve, vu, yaw, rate, pitch)

    def report(self, state) -> dict:
        pos = here(state)
        if pos is None:
            return {}
        sp = self.spline
        s = sp.nearest(pos)
        tangent = sp.tangent(s)
        v = state.velocity
        along = v.north * tangent[0] + v.east * tangent[1] - v.down * tangent[2]
        if self.phase is ShotPhase.ATTACHING and self.approach is not None:
            line = self.approach.profile.spline
            wanted = self.approach_looks.at(float(line.param(line.nearest(pos))))
            self.detail = f"attaching to keyframe {self.attach_index + 1}: {math.dist(pos, sp.points[self.attach_index]):.1f} m to go"
        else:
            wanted = self.looks.at(float(sp.param(s)))
            if self.phase is ShotPhase.FLYING:
                self.detail = f"{s:.0f} of {sp.length:.0f} m, {along:+.1f} m/s"
        return {"progress": s / sp.length if sp.length > 0 else 0.0, "speed": along,
                "aim_error": aim_error(camera_look(state), *wanted)}
