"""Orbit: circle a point of interest with the camera on it, as the Solo's Orbit did.

The centre is a place the pilot picks: the spot under the camera (where its look meets the ground, as the
Solo's spot lock), a point on the map, or the region of interest the vehicle already has. The orbit starts where
the vehicle is: at its present distance from the centre and its present altitude, so it enters the circle without
a jump; with a radius asked for it flies in or out along the radius at no more than the attach speed, braking
onto the circle. The start point is kept.

Sticks (shotmanager's orbitController): right/left flies right/left around the centre (a cruise speed is bent by
it), forward/back flies in/out (changing the radius), throttle climbs or descends. The speed around is at most
3 m/s on a 2 m circle up to 8 m/s on 30 m and more, and never so fast that the pull toward the centre (v²/r)
passes 1.75 m/s²; speeds change by at most the tangential share of the 2 m/s² limit (each planned at 80 %, as
the cable: driver.shots.spline.PLAN_SHARE). A positive cruise is
clockwise seen from above (ArduPilot's CIRCLE_RATE sense).

The camera stays on the centre: the vehicle's region of interest is set to it (DO_SET_ROI_LOCATION: the mount
tilts to it) and the nose is steered to it with each target's yaw and yaw rate; the orbit sets off only once the
vehicle has turned to it.
"""
from __future__ import annotations

import math

from .base import CLIMB_RATE, MAX_SPEED, Shot, stick_speed, toward
from .model import ShotKind, ShotPhase, Sticks
from .setpoint import Target, aim_error, bearing, camera_look, here, horizontal, look_pitch
from .spline import PLANNED_NORMAL, PLANNED_TANGENT

__all__ = ["Orbit", "MIN_RADIUS", "MAX_RADIUS", "ATTACH_SPEED", "strafe_limit", "spot_under_camera"]

MIN_RADIUS = 2.0             # m (ORBIT_RAD_FOR_MIN_SPEED)
MAX_RADIUS = 200.0           # m: kept well inside line of sight
ATTACH_SPEED = 2.0           # m/s along the radius toward a radius asked for (multipoint's ATTACH_SPEED)
RADIAL_SPEED = 4.0           # m/s in/out at full forward/back stick
SLOW, FAST = (2.0, 3.0), (30.0, 8.0)     # (radius m, top speed m/s) around the circle (orbitController)
ARRIVED = 0.3                # m from the radius asked for: on the circle


def strafe_limit(radius: float) -> float:
    """The top speed around a circle of ``radius``: the Solo's ramp, and v²/r within the normal limit."""
    ratio = min(max((radius - SLOW[0]) / (FAST[0] - SLOW[0]), 0.0), 1.0)
    return min(SLOW[1] + (FAST[1] - SLOW[1]) * ratio, math.sqrt(PLANNED_NORMAL * max(radius, 0.1)))


def spot_under_camera(state, floor: float = 0.0) -> tuple[float, float, float] | None:
    """(north, east, up) where the camera's look meets the ground (up = ``floor``), or None when it looks at or
    above the horizon (the Solo refused shallower than 5° down) or the vehicle has not said where it is."""
    pos, look = here(state), camera_look(state)
    if pos is None or look is None or look[0] > -5.0:
        return None
    distance = (pos[2] - floor) / math.tan(math.radians(-look[0]))
    yaw = math.radians(look[1])
    return pos[0] + distance * math.cos(yaw), pos[1] + distance * math.sin(yaw), floor


class Orbit(Shot):
    kind = ShotKind.ORBIT

    def __init__(self, centre: tuple[float, float, float], start: tuple[float, float, float], heading: float,
                 radius: float | None = None, cruise: float = 0.0, allowed=None):
        """``centre`` and ``start`` (the vehicle now) are (north, east, up) m from home; ``heading`` degrees."""
        super().__init__()
        self.centre, self.start = centre, start
        self.roi = centre
        self.allowed = allowed or (lambda n, e, u: True)
        r0 = horizontal(centre, start)
        if r0 < MIN_RADIUS and radius is None:
            raise ValueError(f"the vehicle is {r0:.1f} m from the centre: give a radius, or fly out first")
        wanted = r0 if radius is None else float(radius)
        if not MIN_RADIUS <= wanted <= MAX_RADIUS:
            raise ValueError(f"an orbit's radius is {MIN_RADIUS:g} to {MAX_RADIUS:g} m")
        # over the centre: back away opposite the nose, facing it
        self.angle = math.radians(bearing(start[0] - centre[0], start[1] - centre[1]) if r0 >= 0.5
                                  else (heading + 180.0) % 360.0)
        self.radius, self.radius_wanted = max(r0, 0.0), wanted
        self.alt = start[2]
        self.speed = 0.0                         # m/s around, + clockwise
        self.radial = 0.0                        # m/s outward
        self.climb = 0.0
        self.cruise = float(cruise)
        self.phase = ShotPhase.ATTACHING                  # turning to the centre, then to the radius asked for
        self._pilot_radius = False

    def path_points(self, step: float = 5.0) -> list[tuple[float, float, float]]:
        """The circle at the radius asked for, for the limits check before starting."""
        n = max(12, int(2 * math.pi * self.radius_wanted / step))
        c = self.centre
        return [(c[0] + self.radius_wanted * math.cos(2 * math.pi * i / n),
                 c[1] + self.radius_wanted * math.sin(2 * math.pi * i / n), self.alt) for i in range(n)]

    def step(self, now: float, dt: float, state, sticks: Sticks) -> Target:
        c = self.centre
        if not self.faced:                       # the nose to the centre first: on it from the first metre
            n, e = c[0] + self.radius * math.cos(self.angle), c[1] + self.radius * math.sin(self.angle)
            yaw = (math.degrees(self.angle) + 180.0) % 360.0
            if state is not None and not self.facing(now, state, yaw, "the centre"):
                return Target(n, e, self.alt, yaw=yaw)
            self.faced = True
        a = PLANNED_TANGENT * dt
        # in and out: the pilot's stick, else brake onto the radius asked for
        if sticks.forward:
            radial_wanted = -sticks.forward * RADIAL_SPEED
            self._pilot_radius = True
        else:
            if self._pilot_radius:               # the stick let go: the radius is where it is now
                self.radius_wanted, self._pilot_radius = self.radius, False
            error = self.radius_wanted - self.radius
            radial_wanted = math.copysign(min(ATTACH_SPEED if self.phase is ShotPhase.ATTACHING else RADIAL_SPEED,
                                              math.sqrt(2.0 * PLANNED_TANGENT * abs(error))), error)
            if abs(error) < 0.02:
                radial_wanted = 0.0
        self.radial = toward(self.radial, radial_wanted, a)
        top = strafe_limit(self.radius)
        around = stick_speed(self.cruise, -sticks.right, top)       # right stick: to the right = anticlockwise
        self.speed = toward(self.speed, max(-top, min(top, around)), a)
        self.climb = toward(self.climb, sticks.up * CLIMB_RATE, a)
        radius = min(max(self.radius + self.radial * dt, MIN_RADIUS), MAX_RADIUS)
        angle = self.angle + self.speed / max(radius, MIN_RADIUS) * dt
        alt = self.alt + self.climb * dt
        n, e = c[0] + radius * math.cos(angle), c[1] + radius * math.sin(angle)
        if self.allowed(n, e, alt):
            self.radius, self.angle, self.alt = radius, angle, alt
        else:                                    # the limits: stay where the last target was, stopped
            self.speed = self.radial = self.climb = 0.0
            self.detail = "at the limits (fence, ceiling or distance): stopped"
        if self.phase is ShotPhase.ATTACHING and abs(self.radius_wanted - self.radius) < ARRIVED:
            self.phase = ShotPhase.FLYING if self.paused_cruise is None else ShotPhase.PAUSED
        ca, sa = math.cos(self.angle), math.sin(self.angle)
        n, e = c[0] + self.radius * ca, c[1] + self.radius * sa
        vn = -self.speed * sa + self.radial * ca
        ve = self.speed * ca + self.radial * sa
        yaw = (math.degrees(self.angle) + 180.0) % 360.0
        yaw_rate = math.degrees(self.speed / max(self.radius, MIN_RADIUS))
        return Target(n, e, self.alt, vn, ve, self.climb, yaw, yaw_rate)

    def report(self, state) -> dict:
        pos = here(state)
        if pos is None:
            return {}
        c = self.centre
        radius = horizontal(c, pos)
        out = {"radius": radius, "radius_wanted": self.radius_wanted,
               "angle": bearing(pos[0] - c[0], pos[1] - c[1]) if radius > 0.1 else None,
               "aim_error": aim_error(camera_look(state), look_pitch(pos, c), bearing(c[0] - pos[0], c[1] - pos[1]))}
        if self.phase is ShotPhase.FLYING:
            self.detail = f"orbiting at {radius:.1f} m, {state.velocity.ground_speed:.1f} m/s"
        elif self.phase is ShotPhase.ATTACHING and self.faced:
            self.detail = f"to the {self.radius_wanted:.0f} m circle: {radius:.1f} m now"
        return out
