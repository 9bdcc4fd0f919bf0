"""The simulated vehicle's CIRCLE mode follows AC_Circle: centre ahead of the nose, rate limited by the radius."""
from __future__ import annotations

import math

import pytest

from driver.sim.circle import CircleNav


def fly(nav: CircleNav, seconds: float, n: float, e: float, d: float, yaw: float, dt: float = 0.02):
    """A vehicle that follows the wanted velocity and yaw rate exactly; returns its path."""
    t, path = 0.0, []
    while t < seconds:
        t += dt
        vn, ve, vd, yaw_rate = nav.step(n, e, d, yaw, t)
        n, e, d, yaw = n + vn * dt, e + ve * dt, d + vd * dt, yaw + yaw_rate * dt
        path.append((n, e, d, yaw))
    return path


def test_the_centre_is_the_radius_ahead_of_the_nose_and_the_vehicle_circles_it_facing_in():
    nav = CircleNav(n=0.0, e=0.0, d=-10.0, yaw=math.radians(90.0), radius_cm=800.0, rate_deg_s=20.0,
                    speed_max=5.0, accel_max=2.5, now=0.0)
    assert nav.centre == pytest.approx((0.0, 8.0), abs=1e-9)          # 8 m east: the nose points east
    path = fly(nav, 30.0, 0.0, 0.0, -10.0, math.radians(90.0))
    for n, e, d, yaw in path[len(path) // 3:]:
        assert math.hypot(n - 0.0, e - 8.0) == pytest.approx(8.0, abs=0.6)
        facing = math.atan2(8.0 - e, 0.0 - n)
        assert abs((math.degrees(yaw - facing) + 180.0) % 360.0 - 180.0) < 15.0
        assert d == pytest.approx(-10.0, abs=0.05)                     # the altitude it began at
    assert math.degrees(nav.total) > 360.0                              # 20°/s for 30 s: more than a turn
    assert nav.vel == pytest.approx(math.radians(20.0))


@pytest.mark.parametrize("radius_m, expected_deg_s", [(5.0, 20.0), (100.0, math.degrees(5.0 / 100.0))])
def test_the_rate_is_capped_by_speed_and_acceleration_as_ac_circle_calc_velocities(radius_m, expected_deg_s):
    nav = CircleNav(0.0, 0.0, -5.0, 0.0, radius_m * 100.0, 20.0, speed_max=5.0, accel_max=2.5, now=0.0)
    assert math.degrees(nav.vel_max) == pytest.approx(expected_deg_s)   # min(WPNAV_SPEED, √(½·accel·r)) / r
    assert nav.vel == 0.0                                               # ramped up from standing


def test_a_zero_radius_turns_on_the_spot():
    nav = CircleNav(3.0, 4.0, -5.0, 0.0, 0.0, 20.0, speed_max=5.0, accel_max=2.5, now=0.0)
    assert nav.centre == (3.0, 4.0)
    n, e, d, yaw = fly(nav, 10.0, 3.0, 4.0, -5.0, 0.0)[-1]
    assert math.hypot(n - 3.0, e - 4.0) < 0.1 and yaw > math.radians(90.0)   # a panorama, turning clockwise
