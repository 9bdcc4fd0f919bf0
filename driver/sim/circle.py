"""ArduCopter's CIRCLE mode for the simulated vehicle, as AC_Circle flies it.

On entering the mode the centre is CIRCLE_RADIUS (cm) ahead of the vehicle along its heading
(AC_Circle::init: the stopping point projected along the nose), and the vehicle starts on the circle at the
angle opposite its heading, so it faces the centre. It then turns around the centre at CIRCLE_RATE (deg/s,
positive clockwise seen from above), ramping up at the controller's angular acceleration and never faster than
WPNAV_SPEED or half the horizontal acceleration allows (AC_Circle::calc_velocities), with its nose on the
centre. The altitude is held where the mode began (no RC throttle: the climb rate is zero). A radius of 0 turns
on the spot (a panorama).
"""
from __future__ import annotations

import math

from .common import clamp, wrap_pi

__all__ = ["CircleNav", "ANGULAR_ACCEL_MIN"]

ANGULAR_ACCEL_MIN = math.radians(2.0)    # AC_CIRCLE_ANGULAR_ACCEL_MIN
KP_XY = 1.0                              # 1/s, position error → speed, as the sim's position controller
YAW_GAIN = 3.0                           # 1/s, heading error → yaw rate
YAW_SLEW = math.radians(60.0)


class CircleNav:
    """One circle, from the moment the mode was entered."""

    def __init__(self, n: float, e: float, d: float, yaw: float, radius_cm: float, rate_deg_s: float,
                 speed_max: float, accel_max: float, now: float) -> None:
        self.radius = max(0.0, float(radius_cm)) / 100.0
        self.centre = (n + self.radius * math.cos(yaw), e + self.radius * math.sin(yaw))
        self.down = d
        rate = math.radians(float(rate_deg_s))
        if self.radius <= 0:
            self.vel_max = rate
            self.accel = max(abs(rate), ANGULAR_ACCEL_MIN)
            self.angle = yaw
        else:
            velocity = min(speed_max, math.sqrt(0.5 * accel_max * self.radius))
            limit = velocity / self.radius
            self.vel_max = clamp(rate, -limit, limit)
            self.accel = max(accel_max / self.radius, ANGULAR_ACCEL_MIN)
            self.angle = wrap_pi(yaw - math.pi)             # from the centre to the vehicle
        self.vel = 0.0
        self.total = 0.0                                    # radians turned so far
        self._t = now

    @classmethod
    def entering(cls, ap) -> "CircleNav":
        """The circle an :class:`~driver.sim.autopilot.Autopilot` starts as it switches to CIRCLE."""
        p = ap.params
        return cls(ap.n, ap.e, ap.d, ap.yaw, float(p.get("CIRCLE_RADIUS", 1000.0)), float(p.get("CIRCLE_RATE", 20.0)),
                   ap.wp_speed(), max(0.5, float(p.get("WPNAV_ACCEL", 250.0)) / 100.0), ap.t)

    def step(self, n: float, e: float, d: float, yaw: float, now: float) -> tuple[float, float, float, float]:
        """(north, east, down velocity wanted, yaw rate wanted) at ``now`` for a vehicle at n, e, d heading ``yaw``."""
        dt = min(0.2, max(0.0, now - self._t))
        self._t = now
        if self.vel < self.vel_max:
            self.vel = min(self.vel + self.accel * dt, self.vel_max)
        elif self.vel > self.vel_max:
            self.vel = max(self.vel - self.accel * dt, self.vel_max)
        self.angle = wrap_pi(self.angle + self.vel * dt)
        self.total += self.vel * dt
        cn, ce = self.centre
        vd = clamp(KP_XY * (self.down - d), -1.0, 1.0)       # the altitude the mode began at
        if self.radius <= 0:
            return KP_XY * (cn - n), KP_XY * (ce - e), vd, clamp(YAW_GAIN * wrap_pi(self.angle - yaw),
                                                                  -YAW_SLEW, YAW_SLEW)
        tn, te = cn + self.radius * math.cos(self.angle), ce + self.radius * math.sin(self.angle)
        speed = self.vel * self.radius                    # along the circle, feed-forward
        vn = -speed * math.sin(self.angle) + KP_XY * (tn - n)
        ve = speed * math.cos(self.angle) + KP_XY * (te - e)
        facing = math.atan2(ce - e, cn - n)                # the nose on the centre
        return vn, ve, vd, clamp(YAW_GAIN * wrap_pi(facing - yaw), -YAW_SLEW, YAW_SLEW)
