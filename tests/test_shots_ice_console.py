"""The smart shots from the console and over Ice: the same shots, the same rules, the same state.

A JdeRobot-era client (or our viewer over Ice) runs a shot through ``mavlinkserver.Shots`` and reads its state
as the server's driver measures it; JdeRobot's own interfaces are untouched.
"""
from __future__ import annotations

import io
import math
import time

from driver.console.console import Console
from driver.ice import load_slice
from driver.shots.model import Keyframe, ShotKind, ShotPhase
from driver.vehicle.state import CommandStatus

from ice_fixtures import drone_factory, eventually, server_factory  # noqa: F401
from shots_fixtures import flight_factory  # noqa: F401

jderobot, mavlinkserver = load_slice()


def test_an_orbit_and_a_cable_over_ice_fly_as_embedded_and_report_the_servers_state(
        flight_factory, server_factory, drone_factory, tmp_path):
    f = flight_factory()
    server = server_factory(f.vehicle)
    drone = drone_factory(server)
    assert drone.wait_for(lambda s: s.connected and s.flying, 15)
    lat, lon = f.latlon(15.0, 0.0)
    started = drone.shots.orbit(lat, lon, radius=15.0, speed=3.0).result(timeout=30)
    assert started.ok, str(started)
    s = drone.wait_for(lambda s: s.shot.kind is ShotKind.ORBIT and s.shot.phase is ShotPhase.FLYING
                       and s.shot.radius is not None, 15)
    assert s is not None, drone.state().shot
    truth = f.sim.truth()
    assert abs(s.shot.radius - math.hypot(truth.north - 15.0, truth.east)) < 1.0
    assert s.shot.centre is not None and abs(s.shot.centre[0] - lat) < 1e-6
    # the sticks over Ice: full stick out widens the circle
    start = f.sim.truth().time
    while f.sim.truth().time - start < 3.0:
        assert drone.shots.sticks(-1.0, 0.0, 0.0, 0.0)
        time.sleep(0.02)
    assert drone.wait_for(lambda s: s.shot.radius is not None and s.shot.radius > 18.0, 10), drone.state().shot
    assert drone.shots.stop().result(timeout=10).ok
    assert drone.wait_for(lambda s: s.shot.phase is ShotPhase.ENDED, 10)

    # keyframes recorded over Ice, saved on the client's machine, loaded again
    assert drone.shots.record_keyframe().result(timeout=10).ok
    assert drone.go_to(20.0, 10.0, 14.0).result(timeout=10).ok
    assert f.vehicle.wait_for(lambda s: s.local and math.hypot(s.local.north - 20, s.local.east - 10) < 0.3
                              and abs(s.altitude - 14) < 0.3 and s.velocity.ground_speed < 0.1, 60)
    assert drone.shots.record_keyframe().result(timeout=10).ok
    assert drone.wait_for(lambda s: len(s.shot.keyframes) == 2, 5)
    path = str(tmp_path / "two.json")
    assert drone.shots.save_cable(path).ok
    assert drone.shots.set_keyframes(()).result(timeout=10).ok
    assert drone.wait_for(lambda s: not s.shot.keyframes, 5)
    assert drone.shots.load_cable(path).result(timeout=10).ok
    assert drone.wait_for(lambda s: len(s.shot.keyframes) == 2, 5)
    assert drone.shots.cable(speed=3.0).result(timeout=30).ok
    s = drone.wait_for(lambda s: s.shot.phase is ShotPhase.PAUSED and s.shot.progress is not None
                       and s.shot.progress < 0.05, 60)
    assert s is not None, drone.state().shot                    # from keyframe 2 back to keyframe 1
    assert len(s.shot.path) > 5 and len(s.shot.looks) >= 2
    first = s.shot.keyframes[0]
    truth = f.sim.truth()
    assert math.dist(f.latlon(truth.north, truth.east), (first.lat, first.lon)) < 1e-5


def test_an_ice_client_cannot_make_the_server_open_a_port_and_a_plain_jderobot_client_is_untouched(
        flight_factory, server_factory, drone_factory):
    f = flight_factory()
    server = server_factory(f.vehicle)
    drone = drone_factory(server)
    assert drone.wait_for(lambda s: s.connected, 10)
    # the source is opened here, on the client: nothing sends on it yet
    refused = drone.shots.follow("nmea+udp://127.0.0.1:0").result(timeout=10)
    assert refused.status is CommandStatus.REJECTED and "no fix" in refused.reason
    assert "Shots" in server.served and "Pose3D" in server.served
    assert server.served["Pose3D"].identity == "Pose3D"


def test_the_console_runs_every_shot_verb(flight_factory, tmp_path):
    f = flight_factory(camera=True)
    out = io.StringIO()
    console = Console(f.vehicle, stdout=out)
    lat, lon = f.latlon(12.0, 0.0)
    for line, expected in ((f"shot orbit {lat} {lon} radius 12 speed 2", "orbit: accepted"),
                           ("shot pause", "shot pause: accepted"), ("shot reverse", "reversed"),
                           ("shot resume", "shot resume: accepted"), ("shot speed 3", "cruising at"),
                           ("shot stop", "shot stop: accepted"), ("shot cable record", "keyframe 1"),
                           ("shot cable list", "1 keyframes")):
        console.onecmd(line)
        assert eventually(lambda: expected in out.getvalue(), 30), (line, out.getvalue())
    keys = (Keyframe(*f.latlon(0, 0), 10.0, -10.0, 0.0), Keyframe(*f.latlon(15, 0), 12.0, -20.0, 30.0))
    assert f.vehicle.shots.set_keyframes(keys).result(timeout=5).ok
    path = tmp_path / "cable.json"
    console.onecmd(f"shot cable save {path}")
    assert eventually(lambda: "2 keyframes to" in out.getvalue(), 5) and path.exists()
    console.onecmd("shot cable clear")
    assert eventually(lambda: not f.vehicle.state().shot.keyframes, 5)
    console.onecmd(f"shot cable load {path}")
    assert eventually(lambda: len(f.vehicle.state().shot.keyframes) == 2, 5)
    console.onecmd("shot pano cylinder fov 90 lens 74 pitch -20")
    assert eventually(lambda: "pano: accepted" in out.getvalue(), 30), out.getvalue()
    assert f.vehicle.wait_for(lambda s: s.shot.phase is ShotPhase.DONE, 120), f.vehicle.state().shot
    console.onecmd("shot")
    assert eventually(lambda: "pano done" in out.getvalue(), 5)
    console.onecmd("shot sideways")
    assert "usage: shot" in out.getvalue()
