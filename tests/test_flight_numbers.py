"""The numbers a pilot reads in flight say what a pilot expects: the time left is steady while hovering (the draw
averaged, the charge left from BATT_CAPACITY rather than whole percent steps), a motor test is no flight (the
last flight's time stays), and the pictures the vehicle confirmed (a survey's CAMERA_FEEDBACK) are counted on the
Photo button."""
from __future__ import annotations

import pytest

from driver.vehicle.battery import Battery, time_left
from driver.mission.plan import MissionRunState
from driver.vehicle.state import LandedState
from uavviewer.flight.timer import FlightTimer, clock_text

from test_sim_survey_photos import one_pass, quick_rtl
from viewer_fixtures import app_style, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)


def test_the_charge_left_comes_from_the_capacity_and_the_averaged_draw():
    b = Battery(current=30.0, draw=15.0, reported_remaining=80.0, consumed_mah=1000.0, capacity_mah=5200.0)
    assert time_left(b) == pytest.approx(3.6 * (5200.0 * 0.85 - 1000.0) / 15.0)   # to the 15 % reserve
    airborne = Battery(draw=15.0, draw_at=100.0, draw_weight=30.0)
    gust = airborne.drawing(45.0, 101.0, airborne=True)["draw"]
    assert 15.0 < gust < 16.5                              # one second of a gust moves it by one part in thirty
    assert airborne.drawing(2.0, 101.0, airborne=False)["draw"] == 2.0      # on the ground: the current itself


def test_time_left_is_steady_while_hovering(flying, sim):
    """The sim hovers at a steady 15 A; its SYS_STATUS percent moves by whole steps. 20 s of hovering must read
    as 20 s less, give or take, not 13 then 14 then 19 minutes."""
    assert flying.wait_for(lambda s: s.landed_state is LandedState.IN_AIR, 10)      # the climb is over
    climbed = sim.truth().time
    assert flying.wait_for(lambda s: sim.truth().time > climbed + 2.0, 10)
    start = sim.truth().time
    lefts: list[float] = []

    def sample(s) -> bool:
        left = time_left(s.battery)
        if left is not None and (not lefts or left != lefts[-1]):
            lefts.append(left)
        return sim.truth().time > start + 20.0
    assert flying.wait_for(sample, 30) is not None and len(lefts) > 5
    rises = [b - a for a, b in zip(lefts, lefts[1:]) if b > a]
    assert max(rises, default=0.0) < 10.0, [clock_text(x) for x in lefts]
    assert abs(lefts[-1] - lefts[0]) < 0.05 * lefts[0], [clock_text(x) for x in lefts]


def test_a_motor_test_leaves_the_last_flights_time(sim, vehicle):
    now = [1000.0]
    timer = FlightTimer(clock=lambda: now[0])
    assert vehicle.wait_for(lambda s: s.readiness.ready_to_arm, 20)
    assert vehicle.set_mode("GUIDED").result(20).ok and vehicle.arm().result(20).ok
    assert vehicle.wait_for(lambda s: timer.update(s) is not None and s.armed, 10)
    now[0] += 462.0                                          # a flight of 7:42
    assert vehicle.disarm().result(20).ok
    assert vehicle.wait_for(lambda s: timer.update(s) is not None and not s.armed, 10)
    assert clock_text(timer.seconds) == "07:42"
    assert vehicle.setup.motor_test(1, throttle_pct=20, seconds=2.0, propellers_removed=True).result(20).ok
    seen = []

    def follow(s) -> bool:                                   # every snapshot, as the window feeds it
        now[0] += 0.05
        timer.update(s)
        seen.append((s.armed, s.setup.motor_test_running))
        return (True, True) in seen and not s.armed and not s.setup.motor_test_running
    assert vehicle.wait_for(follow, 30) is not None
    assert clock_text(timer.seconds) == "07:42"              # a motor test is no flight


def test_the_mission_progress_counts_a_surveys_pictures(qtbot, sim_factory, vehicle_factory, window_factory):
    sim = quick_rtl(sim_factory(speedup=8.0, camera="trigger"))
    drone = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    w = window_factory(drone)
    progress = w.plan.panel.progressLabel
    qtbot.waitUntil(lambda: w.adapter.state.connected and w.adapter.state.home is not None, timeout=20000)
    assert drone.upload_plan(one_pass(drone)).result(30).result.ok   # a pass with the camera every 5 m
    drone.start_mission()
    qtbot.waitUntil(lambda: progress.text().startswith("Item ") and progress.text().endswith(" photos"),
                    timeout=60000)                                    # as the vehicle confirms them
    qtbot.waitUntil(lambda: w.adapter.state.mission.state is MissionRunState.COMPLETE
                    and not w.adapter.state.armed, timeout=100000)
    n = w.adapter.state.camera.photos
    assert n == sim.autopilot.images >= 6
    qtbot.waitUntil(lambda: progress.text() == f"Mission complete (7 items) · {n} photos", timeout=5000)
