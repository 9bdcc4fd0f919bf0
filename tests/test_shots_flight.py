"""Every smart shot flown on the simulated ArduCopter through the driver, judged on the simulator's truth.

The figures are accuracy bounds on what the vehicle really did (the path it flew, where its camera looked), and
what the driver reported is compared with it: a shot's state comes from the vehicle's telemetry, never from
what was sent.
"""
from __future__ import annotations

import math
import socket
import threading
import time

import pytest

from driver.shots.model import Keyframe, ShotKind, ShotPhase
from driver.shots.spline import Looks, Spline
from driver.shots.targets import nmea_sentence
from driver.vehicle.state import CommandStatus

from shots_fixtures import angle_between, flight_factory, rms  # noqa: F401

CABLE = [(0.0, 0.0, 10.0), (30.0, 10.0, 15.0), (40.0, 50.0, 12.0), (10.0, 70.0, 20.0)]
LOOKS = [(-10.0, 0.0), (-30.0, 90.0), (-20.0, 180.0), (-45.0, 270.0)]


def look_at(truth, point) -> tuple[float, float]:
    """(pitch, yaw) in degrees from where the truth's vehicle is to ``point`` (north, east, up)."""
    dn, de, du = point[0] - truth.north, point[1] - truth.east, point[2] - truth.altitude
    return math.degrees(math.atan2(du, math.hypot(dn, de))), math.degrees(math.atan2(de, dn)) % 360.0


def aim(truth, point) -> float:
    return angle_between(truth.mount_pitch, truth.heading_deg, *look_at(truth, point))


def test_orbit_circles_the_centre_at_its_radius_with_the_camera_on_it(flight_factory):
    f = flight_factory()
    lat, lon = f.latlon(20.0, 0.0)
    started = f.vehicle.shots.orbit(lat, lon, 0.0, radius=20.0, speed=3.0).result(timeout=30)
    assert started.ok, str(started)
    samples = f.fly_for(45.0)
    flying = [(t, s) for t, s in samples if s.shot.phase is ShotPhase.FLYING][20:]
    assert len(flying) > 100
    radius = [math.hypot(t.north - 20.0, t.east) for t, _ in flying]
    assert rms(r - 20.0 for r in radius) <= 0.5
    aims = [aim(t, (20.0, 0.0, 0.0)) for t, _ in flying]
    assert rms(aims) <= 2.0 and max(aims) <= 4.0
    swept = sum(abs((math.atan2(b.east, b.north - 20) - math.atan2(a.east, a.north - 20) + math.pi) % (2 * math.pi)
                    - math.pi) for (a, _), (b, _) in zip(flying, flying[1:]))
    assert math.degrees(swept) > 200.0                            # it went round, at 3 m/s
    t, s = flying[-1]
    assert abs(s.shot.radius - math.hypot(t.north - 20.0, t.east)) <= 0.5      # reported from telemetry
    assert s.shot.aim_error is not None and s.shot.aim_error <= 3.0
    assert f.vehicle.stop().result(timeout=5).ok
    assert f.vehicle.state().shot.phase is ShotPhase.ENDED


def test_cable_cam_rides_the_spline_through_the_keyframes_with_their_looks(flight_factory):
    f = flight_factory()
    keys = [Keyframe(*f.latlon(n, e), u, p, y) for (n, e, u), (p, y) in zip(CABLE, LOOKS)]
    assert f.vehicle.shots.set_keyframes(keys).result(timeout=5).ok
    started = f.vehicle.shots.cable(speed=5.0).result(timeout=30)
    assert started.ok, str(started)
    samples = f.fly_for(90.0, until=lambda t, s: s.shot.phase is ShotPhase.PAUSED)
    spline, looks = Spline(CABLE), Looks(LOOKS)
    flying = [(t, s) for t, s in samples if s.shot.phase is ShotPhase.FLYING]
    errors, aims, reports = [], [], []
    for t, s in flying:
        here = (t.north, t.east, t.altitude)
        at = spline.nearest(here)
        errors.append(math.dist(here, spline.point(at)))
        aims.append(angle_between(t.mount_pitch, t.heading_deg, *looks.at(float(spline.param(at)))))
        if s.shot.progress is not None:
            reports.append(abs(s.shot.progress - at / spline.length))
    assert rms(errors) <= 0.5
    assert rms(aims[10:]) <= 2.0
    assert max(reports) <= 0.05                                    # progress is where the vehicle is
    end, state = samples[-1]
    assert state.shot.phase is ShotPhase.PAUSED and "last keyframe" in state.shot.detail
    assert math.dist((end.north, end.east, end.altitude), CABLE[-1]) < 1.0
    assert max(t.ground_speed for t, _ in flying) <= 5.3
    # the sticks fly it back: full stick back along the cable
    back = []
    start = f.sim.truth().time
    while f.sim.truth().time - start < 8.0:
        assert f.vehicle.shots.sticks(-1.0, 0.0, 0.0, 0.0)
        back.append(f.sim.truth())
        time.sleep(0.02)
    assert spline.nearest((back[-1].north, back[-1].east, back[-1].altitude)) < spline.length - 10.0
    assert f.vehicle.shots.stop().result(timeout=5).ok


def test_keyframes_are_recorded_where_the_vehicle_is_and_a_second_one_on_the_same_spot_replaces_it(flight_factory):
    f = flight_factory()
    v = f.vehicle
    assert v.shots.record_keyframe().result(timeout=5).ok
    assert v.shots.record_keyframe().result(timeout=5).ok             # within a metre: the same keyframe, moved
    assert len(v.state().shot.keyframes) == 1
    assert v.go_to(15.0, 5.0, 12.0).result(timeout=5).ok
    assert v.wait_for(lambda s: s.local and math.hypot(s.local.north - 15, s.local.east - 5) < 0.3
                      and abs(s.altitude - 12) < 0.3 and s.velocity.ground_speed < 0.1, 60)
    assert v.point_gimbal(-30.0).result(timeout=5).ok
    assert v.wait_for(lambda s: s.gimbal.pitch_deg is not None and abs(s.gimbal.pitch_deg + 30) < 1, 10)
    assert v.shots.record_keyframe().result(timeout=5).ok
    first, second = v.state().shot.keyframes
    t = f.sim.truth()
    assert math.dist(f.latlon(t.north, t.east), (second.lat, second.lon)) < 1e-5 and abs(second.alt - t.altitude) < 0.3
    assert abs(second.pitch + 30.0) < 1.0 and abs((second.yaw - t.heading_deg + 180) % 360 - 180) < 2.0


def test_selfie_flies_out_and_up_away_from_the_pilot_and_back_with_the_camera_on_the_pilot(flight_factory):
    f = flight_factory()
    v = f.vehicle
    assert v.go_to(8.0, 0.0, 10.0).result(timeout=5).ok
    assert v.wait_for(lambda s: s.local and abs(s.local.north - 8) < 0.2 and s.velocity.ground_speed < 0.1, 60)
    begin = f.sim.truth()
    started = v.shots.selfie(distance=20.0, rise=10.0, speed=3.0).result(timeout=30)
    assert started.ok, str(started)
    samples = f.fly_for(60.0, until=lambda t, s: s.shot.phase is ShotPhase.DONE)
    assert samples[-1][1].shot.phase is ShotPhase.DONE
    far = max(samples, key=lambda ts: ts[0].north)[0]
    assert math.dist((far.north, far.east, far.altitude), (begin.north + 20.0, begin.east, begin.altitude + 10.0)) < 1.0
    end = samples[-1][0]
    assert math.dist((end.north, end.east, end.altitude), (begin.north, begin.east, begin.altitude)) < 1.0
    on_the_way = [t for t, s in samples if s.shot.phase is ShotPhase.FLYING
                  and math.dist((t.north, t.east, t.altitude), (begin.north, begin.east, begin.altitude)) > 0.5]
    assert max(aim(t, (0.0, 0.0, 0.0)) for t in on_the_way) <= 2.0


class Walker:
    """A person walking east at 1.5 m/s from (north, east), whose GPS sends fixes twice a second of sim time."""

    def __init__(self, flight, north: float, east: float, send):
        self.flight, self.start, self.send = flight, (north, east), send
        self.t0 = flight.sim.truth().time
        self.on = threading.Event()
        self.on.set()
        self.gone = threading.Event()
        threading.Thread(target=self._walk, daemon=True).start()

    def where(self, t: float) -> tuple[float, float, float]:
        return self.start[0], self.start[1] + 1.5 * (t - self.t0), 0.0

    def _walk(self) -> None:
        last = -1.0
        while not self.gone.is_set():
            now = self.flight.sim.truth().time
            if self.on.is_set() and now - last >= 0.5:
                last = now
                n, e, _ = self.where(now)
                self.send(*self.flight.latlon(n, e))
            time.sleep(0.01)


@pytest.mark.parametrize("engine", ["guided", "follow"])
def test_follow_keeps_its_distance_to_a_walking_target_and_holds_when_the_fixes_stop(flight_factory, engine):
    f = flight_factory()
    v = f.vehicle
    if engine == "follow":                         # ArduCopter's FOLLOW needs FOLL_ENABLE, then the others show
        assert v.set_parameter("FOLL_ENABLE", 1).result(timeout=10).ok
        assert v.fetch_parameters().result(timeout=60).ok
        walker = Walker(f, -15.0, 0.0, lambda lat, lon: v.shots.follow_position(lat, lon, f.home.alt, 0.0, 1.5))
        source = "given"
    else:                                          # the laptop's GPS: NMEA over UDP
        out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        port = _free_udp_port()
        source = f"nmea+udp://127.0.0.1:{port}"

        def nmea(lat, lon):
            def dm(value, pos, neg, width):
                d = abs(value)
                return f"{int(d):0{width}d}{(d - int(d)) * 60:07.4f},{pos if value >= 0 else neg}"
            gga = nmea_sentence(f"GPGGA,000000,{dm(lat, 'N', 'S', 2)},{dm(lon, 'E', 'W', 3)},1,08,0.9,"
                                f"{f.home.alt:.1f},M,0,M,,")
            rmc = nmea_sentence(f"GPRMC,000000,A,{dm(lat, 'N', 'S', 2)},{dm(lon, 'E', 'W', 3)},{1.5 / 0.514444:.3f},"
                                "90.0,010125,,")
            out.sendto((gga + "\r\n" + rmc + "\r\n").encode(), ("127.0.0.1", port))
        refused = v.shots.follow(source, engine).result(timeout=10)   # opens the source: no fix yet
        assert refused.status is CommandStatus.REJECTED and "no fix" in refused.reason
        walker = Walker(f, -15.0, 0.0, nmea)
    assert v.wait_for(lambda s: s.connected, 5)
    time.sleep(0.5)
    started = v.shots.follow(source, engine).result(timeout=30)
    assert started.ok, str(started)
    assert v.state().shot.engine == engine.upper()
    samples = f.fly_for(30.0)
    wanted = None
    distances = []
    for t, s in samples[10:]:
        d = math.dist((t.north, t.east, t.altitude), walker.where(t.time))
        wanted = wanted or d
        distances.append(d - wanted)
    assert rms(distances) <= 1.0
    assert min(t.ground_speed for t, _ in samples[-20:]) > 1.2                 # it kept walking with it
    last = samples[-1][1].shot
    assert last.target_distance is not None and abs(last.target_distance - wanted) < 2.0
    walker.on.clear()                                                           # the fixes stop
    held = f.fly_for(15.0, until=lambda t, s: s.shot.phase is ShotPhase.HOLDING and t.ground_speed < 0.2)
    assert held[-1][1].shot.phase is ShotPhase.HOLDING and "no fix" in held[-1][1].shot.detail
    assert held[-1][0].ground_speed < 0.2
    walker.gone.set()
    assert v.stop().result(timeout=5).ok


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_pano_takes_a_confirmed_picture_at_each_step_aimed_there(flight_factory):
    f = flight_factory(camera=True)
    v = f.vehicle
    heading = f.sim.truth().heading_deg
    started = v.shots.pano("cylinder", 360.0, 74.0, -10.0).result(timeout=30)
    assert started.ok, str(started)
    seen, shots_at = f.sim.autopilot.images, []

    def picture(t, s):
        nonlocal seen
        if f.sim.autopilot.images != seen:
            seen = f.sim.autopilot.images
            shots_at.append(t)
        return s.shot.phase is ShotPhase.DONE
    samples = f.fly_for(120.0, until=picture)
    final = samples[-1][1].shot
    assert final.phase is ShotPhase.DONE and final.photos == final.photos_total == 8
    assert len(shots_at) == 8
    for i, t in enumerate(shots_at):
        want = (heading + i * 45.0) % 360.0
        assert angle_between(t.mount_pitch, t.heading_deg, -10.0, want) <= 2.0


def test_a_shot_starts_only_in_the_air_and_within_the_fence(sim_factory, vehicle_factory, flight_factory):
    sim = sim_factory()
    grounded = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert grounded.wait_for(lambda s: s.connected and s.home is not None, 20)
    home = grounded.state().home
    refused = grounded.shots.orbit(home.lat + 0.0001, home.lon, radius=10.0).result(timeout=5)
    assert refused.status is CommandStatus.REJECTED and "take off first" in refused.reason

    f = flight_factory()
    v = f.vehicle
    for name, value in (("FENCE_RADIUS", 30.0), ("FENCE_ENABLE", 1)):
        assert v.set_parameter(name, value).result(timeout=10).ok
    assert v.wait_for(lambda s: s.fence.circle == 30.0, 5)
    lat, lon = f.latlon(10.0, 0.0)
    refused = v.shots.orbit(lat, lon, radius=25.0).result(timeout=5)
    assert refused.status is CommandStatus.REJECTED and "fence" in refused.reason
    assert v.state().shot.phase is ShotPhase.IDLE and f.sim.truth().mode == "GUIDED"
    assert v.shots.orbit(lat, lon, radius=15.0).result(timeout=30).ok


@pytest.mark.parametrize("how", ["stop", "land", "rtl", "mode", "velocity"])
def test_stop_land_rtl_a_mode_or_the_pilots_sticks_end_the_shot_at_once(flight_factory, how):
    f = flight_factory()
    v = f.vehicle
    lat, lon = f.latlon(15.0, 0.0)
    assert v.shots.orbit(lat, lon, radius=15.0, speed=4.0).result(timeout=30).ok
    f.fly_for(8.0)
    assert f.sim.truth().ground_speed > 3.0
    action = {"stop": v.stop, "land": v.land, "rtl": v.return_to_launch, "mode": lambda: v.set_mode("LOITER"),
              "velocity": lambda: v.set_velocity(0.5, 0.0, 0.0, 0.0)}[how]
    result = action()
    if how == "velocity":                          # the pilot's stream is seen on the next beat
        assert v.wait_for(lambda s: s.shot.phase is ShotPhase.ENDED, 5)
    shot = v.state().shot
    assert shot.phase is ShotPhase.ENDED and "took over" in shot.detail       # at once, before any answer
    if hasattr(result, "result"):
        assert result.result(timeout=10).ok
    sent = lambda: sum(1 for _, kind, _ in list(f.sim.received_messages)   # noqa: E731
                       if kind == "SET_POSITION_TARGET_GLOBAL_INT")
    f.fly_for(1.0)
    before = sent()
    samples = f.fly_for(4.0)
    assert sent() == before                                                   # nothing more from the shot
    if how == "stop":
        assert samples[-1][0].ground_speed < 1.0                              # braking to a hold
        assert samples[-1][0].mode == "GUIDED"


def test_a_short_silence_of_the_link_is_ridden_out_and_a_long_one_ends_the_shot(flight_factory):
    f = flight_factory()
    v = f.vehicle
    lat, lon = f.latlon(15.0, 0.0)
    assert v.shots.orbit(lat, lon, radius=15.0, speed=3.0).result(timeout=30).ok
    f.fly_for(3.0)
    f.sim.faults.outage(1.5)                       # real seconds: 6 s of the vehicle's, past the 3.5 s loss timeout
    lost = f.fly_for(20.0, until=lambda t, s: not s.connected)
    assert not lost[-1][1].connected
    back = f.fly_for(30.0, until=lambda t, s: s.connected)
    assert back[-1][1].connected and v.state().shot.phase is ShotPhase.FLYING          # ridden out
    f.sim.faults.outage(4.0)                       # 16 s of the vehicle's: past the 10 s grace
    ended = f.fly_for(40.0, until=lambda t, s: s.shot.phase is ShotPhase.ENDED)
    assert "link is down" in ended[-1][1].shot.detail
