"""The shots' geometry and controllers, pure: state in, targets out, on a clock the test passes in.

Hypothesis draws cables, speeds and stick sequences; the properties are the ones the pilot relies on: the cable
goes through every keyframe with its look there, a vehicle flying it is never asked to accelerate beyond 2.0 m/s²
overall nor 1.75 m/s² normal to the path, it stops at either end, and an orbit never pulls harder than 1.75 m/s²
toward its centre.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from driver.core import frames
from driver.shots.base import stick_speed
from driver.shots.model import Keyframe, ShotPhase, Sticks, load_cable, save_cable
from driver.shots.orbit import Orbit, strafe_limit
from driver.shots.pano import cylinder_steps, sphere_steps
from driver.shots.setpoint import Target, target_message
from driver.shots.spline import (
    ACCEL_LIMIT, NORMAL_ACCEL_LIMIT, TANGENT_ACCEL_LIMIT, Looks, PathRun, SpeedProfile, Spline,
)
from driver.shots.targets import GivenTarget, nmea_sentence, parse_gpsd, parse_nmea
from driver.vehicle.state import GlobalPosition

coordinate = st.floats(-60.0, 60.0, allow_nan=False)
height = st.floats(5.0, 40.0, allow_nan=False)


@st.composite
def cables(draw, most: int = 6):
    """2 to ``most`` keyframes 5 to 40 m apart, each leg turning at most 120° from the one before."""
    n = draw(st.integers(2, most))
    pts = [(draw(coordinate), draw(coordinate), draw(height))]
    heading = draw(st.floats(0.0, 360.0))
    while len(pts) < n:
        heading += draw(st.floats(-120.0, 120.0))
        length = draw(st.floats(5.0, 40.0))
        climb = draw(st.floats(-5.0, 5.0))
        n0, e0, u0 = pts[-1]
        pts.append((n0 + length * math.cos(math.radians(heading)), e0 + length * math.sin(math.radians(heading)),
                    min(max(u0 + climb, 5.0), 40.0)))
    return pts


def fly(run: PathRun, wanted, dt: float, steps: int) -> np.ndarray:
    """The velocity vectors the run asks for, one a step."""
    out = []
    for i in range(steps):
        run.step(dt, wanted(i))
        out.append(run.velocity())
    return np.array(out)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cables())
def test_the_cable_goes_through_every_keyframe_and_is_measured_by_its_length(points):
    sp = Spline(points)
    for s, p in zip(sp.keyframe_s, points):
        assert math.dist(sp.point(s), p) < 1e-6
    chords = sum(math.dist(a, b) for a, b in zip(points, points[1:]))
    assert chords - 1e-6 <= sp.length < 2.0 * chords
    for s in np.linspace(0, sp.length, 17):
        assert abs(sp.nearest(sp.point(s)) - s) < 0.05          # where the vehicle is gives how far it has come


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cables(), st.floats(0.5, 8.0), st.sampled_from([0.05, 0.1, 0.2]),
       st.lists(st.floats(-8.0, 8.0), min_size=1, max_size=6))
def test_a_cable_flown_at_any_speed_and_any_sticks_stays_within_the_acceleration_limits(points, top, dt, asks):
    sp = Spline(points)
    run = PathRun(SpeedProfile(sp, top))
    steps = int(40.0 / dt)
    v = fly(run, lambda i: asks[i * len(asks) // steps], dt, steps)
    a = np.diff(v, axis=0) / dt
    speed = np.linalg.norm(v, axis=1)
    assert speed.max() <= top + 1e-6
    assert np.linalg.norm(a, axis=1).max() <= ACCEL_LIMIT * 1.03
    # along the path: the change of speed; across it: the rest (v²κ)
    tangential = np.abs(np.diff(speed)) / dt
    assert tangential.max() <= TANGENT_ACCEL_LIMIT * 1.03
    normal = np.sqrt(np.maximum(np.linalg.norm(a, axis=1) ** 2 - tangential ** 2, 0.0))
    assert normal.max() <= NORMAL_ACCEL_LIMIT * 1.05
    assert 0.0 <= run.s <= sp.length


@settings(max_examples=10, deadline=None)
@given(cables(4), st.floats(1.0, 8.0))
def test_a_cruise_stops_exactly_at_the_end_and_back_at_the_start(points, speed):
    sp = Spline(points)
    run = PathRun(SpeedProfile(sp, 8.0))
    for _ in range(20000):
        run.step(0.1, speed)
        if run.at_end and run.speed == 0.0:
            break
    assert run.at_end and run.speed == 0.0
    for _ in range(20000):
        run.step(0.1, -speed)
        if run.at_start and run.speed == 0.0:
            break
    assert run.at_start and run.speed == 0.0


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(-90, 0), st.floats(0, 359.9)), min_size=2, max_size=8))
def test_the_look_is_each_keyframes_own_there_and_turns_the_short_way(looks):
    lk = Looks(looks)
    for i, (pitch, yaw) in enumerate(looks):
        p, y = lk.at(float(i))
        assert abs(p - pitch) < 1e-6 and abs(frames.wrap_180(y - yaw)) < 1e-6
    for i in range(len(looks) - 1):
        y0, y1 = looks[i][1], looks[i + 1][1]
        short = abs(frames.wrap_180(y1 - y0))
        mid = lk.at(i + 0.5)[1]
        assert abs(frames.wrap_180(mid - y0)) <= short + 60.0      # never the long way round


def test_two_keyframes_closer_than_a_metre_are_one_place():
    with pytest.raises(ValueError, match="one place"):
        Spline([(0, 0, 10), (0.5, 0, 10), (20, 0, 10)])


@settings(max_examples=15, deadline=None)
@given(st.floats(2.0, 150.0), st.floats(-8.0, 8.0), st.lists(st.floats(-1, 1), min_size=1, max_size=4))
def test_an_orbit_never_pulls_beyond_the_normal_limit_and_starts_where_the_vehicle_is(radius, cruise, rights):
    start = (radius, 0.0, 12.0)
    orbit = Orbit((0.0, 0.0, 0.0), start, 180.0, None, cruise)
    dt, steps = 0.1, 600
    first = None
    vs = []
    for i in range(steps):
        t = orbit.step(i * dt, dt, None, Sticks(right=rights[i * len(rights) // steps]))
        first = first or t
        vs.append((t.vn, t.ve))
        r = math.hypot(t.north, t.east)
        assert abs(r - radius) < 1e-6                              # no stick forward: the radius holds
        assert (t.vn ** 2 + t.ve ** 2) / r <= NORMAL_ACCEL_LIMIT * 1.001
        assert abs(frames.wrap_180(t.yaw - math.degrees(math.atan2(-t.east, -t.north)))) < 1e-6   # on the centre
    assert math.dist((first.north, first.east, first.up), start) < 0.05          # entered without a jump
    a = np.linalg.norm(np.diff(np.array(vs), axis=0) / dt, axis=1)
    assert a.max() <= ACCEL_LIMIT * 1.02


def test_an_orbit_asked_wider_flies_out_at_the_attach_speed_and_settles_on_the_circle():
    orbit = Orbit((0.0, 0.0, 0.0), (10.0, 0.0, 12.0), 180.0, 20.0, 0.0)
    assert orbit.phase is ShotPhase.ATTACHING
    fastest = 0.0
    for i in range(400):
        t = orbit.step(i * 0.1, 0.1, None, Sticks())
        fastest = max(fastest, math.hypot(t.vn, t.ve))
    assert orbit.phase is ShotPhase.FLYING and abs(math.hypot(t.north, t.east) - 20.0) < 0.05
    assert fastest <= 2.0 + 1e-9


def test_the_orbits_top_speed_follows_the_solos_ramp_and_the_pull_toward_the_centre():
    assert strafe_limit(2.0) == pytest.approx(math.sqrt(1.75 * 0.8 * 2.0))
    assert strafe_limit(30.0) == pytest.approx(min(8.0, math.sqrt(1.75 * 0.8 * 30)))
    assert strafe_limit(100.0) == 8.0


def test_the_sticks_bend_a_cruise_as_on_the_solo():
    assert stick_speed(0.0, 0.5, 8.0) == 4.0
    assert stick_speed(2.0, 1.0, 8.0) == 8.0          # with it: up to the top
    assert stick_speed(2.0, -1.0, 8.0) == 0.0         # against it: to a stop
    assert stick_speed(-2.0, -0.5, 8.0) == -5.0
    assert Sticks.checked(float("nan"), 0, 0, 0) is None
    assert Sticks.checked(3, -3, 0, 0) == Sticks(1.0, -1.0, 0.0, 0.0)


def test_a_pano_covers_its_field_with_overlapping_steps():
    steps = cylinder_steps(90.0, 360.0, 74.0, -10.0)
    gaps = sorted(y for y, _ in steps)
    assert len(steps) == 8 and all(p == -10.0 for _, p in steps)
    assert max((b - a) % 360 for a, b in zip(gaps, gaps[1:] + gaps[:1])) <= 74.0 * (2 / 3) + 1e-9
    partial = cylinder_steps(0.0, 180.0, 74.0, 0.0)
    assert frames.wrap_180(partial[0][0]) == pytest.approx(-53.0) and partial[-1][0] == pytest.approx(53.0)
    sphere = sphere_steps(0.0, 74.0)
    assert sphere[-1] == (0.0, -90.0) and {p for _, p in sphere} == {0.0, -30.0, -60.0, -90.0}


def test_nothing_that_is_not_a_finite_number_reaches_the_wire():
    home = GlobalPosition(40.0, -3.0, 600.0)
    assert target_message(Target(1.0, 2.0, 10.0, yaw=float("nan")), home, 1, 1) is None
    assert target_message(Target(float("inf"), 2.0, 10.0), home, 1, 1) is None
    assert target_message(Target(1.0, 2.0, 10.0, pitch=float("nan")), home, 1, 1) is None
    msg = target_message(Target(10.0, 0.0, 12.0, 1.0, 0.0, 0.5, 90.0, 5.0), home, 1, 1)
    assert msg.type_mask == 0b111000000 and msg.vz == -0.5 and msg.alt == 12.0
    assert msg.yaw == pytest.approx(math.pi / 2) and msg.yaw_rate == pytest.approx(math.radians(5.0))


def test_nmea_and_gpsd_fixes_are_read_and_a_bad_checksum_is_not():
    gga = nmea_sentence("GPGGA,123519,4017.034,N,00347.640,W,1,08,0.9,664.5,M,46.9,M,,")
    rmc = nmea_sentence("GPRMC,123519,A,4017.034,N,00347.640,W,2.9,090.0,230394,003.1,W")
    fix = parse_nmea(gga)
    assert fix["lat"] == pytest.approx(40.2839) and fix["lon"] == pytest.approx(-3.794) and fix["alt"] == 664.5
    assert parse_nmea(rmc)["speed"] == pytest.approx(2.9 * 0.514444) and parse_nmea(rmc)["course"] == 90.0
    assert parse_nmea(gga[:-2] + "00") is None
    assert parse_nmea(nmea_sentence("GPGGA,123519,4017.034,N,00347.640,W,0,00,,,M,,M,,")) is None   # no fix
    tpv = '{"class":"TPV","mode":3,"lat":40.2839,"lon":-3.794,"altMSL":664.0,"speed":1.5,"track":90.0}'
    assert parse_gpsd(tpv) == {"lat": 40.2839, "lon": -3.794, "alt": 664.0, "speed": 1.5, "course": 90.0}
    assert parse_gpsd('{"class":"TPV","mode":1}') is None


def test_a_given_target_gets_its_velocity_from_its_places_when_none_is_given():
    now = [100.0]
    target = GivenTarget(lambda: now[0])
    lat, lon = 40.0, -3.0
    assert target.put(lat, lon, 600.0)
    now[0] += 1.0
    assert target.put(*frames.offset_latlon(lat, lon, 0.0, 1.5), 600.0)
    fix = target.latest()
    assert fix.ve == pytest.approx(1.5, rel=1e-3) and abs(fix.vn) < 1e-3 and fix.time == 101.0
    assert not target.put(float("nan"), 0.0)


def test_a_cable_is_saved_and_loaded_whole(tmp_path):
    keys = (Keyframe(40.0, -3.0, 10.0, -20.0, 45.0), Keyframe(40.0002, -3.0, 15.0, -30.0, 90.0))
    path = str(tmp_path / "cable.json")
    save_cable(path, keys)
    assert load_cable(path) == keys
    (tmp_path / "bad.json").write_text('{"format": "uavviewer-cable", "keyframes": [{"lat": 1}]}')
    with pytest.raises(ValueError, match="lacks"):
        load_cable(str(tmp_path / "bad.json"))
