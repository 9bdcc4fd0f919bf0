"""A mission uploaded before the vehicle has a home (no GPS fix yet), as ArduPilot, QGroundControl and MAVProxy
allow: checked against the limits as soon as home arrives, and not started before that or while an item is
beyond them. Before "ArduPilot Ready" the vehicle itself refuses, and its reason is shown."""
from __future__ import annotations

import io

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.core import frames
from driver.console.console import Console, run_commands
from driver.mission.files import save_plan_file
from driver.mission.plan import MissionItem, Plan, PlanKind
from driver.vehicle.state import CommandStatus

from ice_fixtures import eventually

HOME = (40.2839, -3.7940, 664.0, 0.0)


def waypoint(north: float, east: float, alt: float = 20.0) -> MissionItem:
    lat, lon = frames.offset_latlon(HOME[0], HOME[1], north, east)
    return MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, lat=lat, lon=lon, alt=alt)


def mission(*far: MissionItem) -> Plan:
    return Plan(PlanKind.MISSION, (MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=10), waypoint(30, 20), *far,
                                   MissionItem(mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH, frame=mavlink.MAV_FRAME_MISSION)))


@pytest.fixture
def ready_without_home(sim_factory, vehicle_factory):
    """ArduPilot Ready (storage up) but no GPS fix yet: home comes some real seconds later."""
    sim = sim_factory(ready_after=40.0, home=HOME)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: any(m.text == "ArduPilot Ready" for m in s.messages), 20)
    assert vehicle.state().home is None
    return sim, vehicle


def test_a_mission_goes_up_before_home_and_is_checked_when_home_arrives(ready_without_home, tmp_path):
    sim, vehicle = ready_without_home
    path = tmp_path / "far.waypoints"
    save_plan_file(str(path), (mission(waypoint(800, 0)),), None)
    out = io.StringIO()
    console = Console(vehicle, stdout=out)
    run_commands(console, f"wp load {path}")                   # as --cmd "wp load FILE" right after connecting
    assert eventually(lambda: "upload mission: " in out.getvalue(), 30), out.getvalue()
    assert "upload mission: accepted" in out.getvalue(), out.getvalue()
    assert len(sim.autopilot.plans[PlanKind.MISSION]) == 5
    s = vehicle.wait_for(lambda s: s.mission.limit_problems, 5)
    assert s is not None and s.home is None and "not checked" in s.mission.limit_problems[0]
    refused = vehicle.start_mission().result(5)
    assert refused.status is CommandStatus.REJECTED and "has not sent its home yet" in refused.reason, refused
    # home arrives: item 3 is 800 m away, beyond the 500 m limit; the pilot is told, the mission not started
    s = vehicle.wait_for(lambda s: s.home is not None and "800 m" in "".join(s.mission.limit_problems), 60)
    assert s is not None, vehicle.state().mission
    assert s.mission.limit_problems == ("item 3 (WAYPOINT): 800 m from home, beyond the 500 m limit",)
    assert any("beyond the limits" in m.text and "item 3 (WAYPOINT)" in m.text for m in s.messages)
    run_commands(console, "wp start")
    assert eventually(lambda: "mission start: rejected (the mission is not started: item 3 (WAYPOINT): 800 m"
                      in out.getvalue(), 10), out.getvalue()
    assert not sim.autopilot.armed


def test_a_mission_within_the_limits_is_cleared_for_start_once_home_is_known(ready_without_home):
    sim, vehicle = ready_without_home
    outcome = vehicle.upload_plan(mission(waypoint(100, 50))).result(30)
    assert outcome.result.status is CommandStatus.ACCEPTED, outcome.result
    assert vehicle.wait_for(lambda s: s.mission.limit_problems, 5)
    s = vehicle.wait_for(lambda s: s.home is not None and not s.mission.limit_problems, 60)
    assert s is not None
    assert any("every item within the limits" in m.text for m in s.messages)


def test_before_arducopter_is_ready_the_upload_is_refused_with_the_vehicles_reason(sim_factory, vehicle_factory,
                                                                                   monkeypatch):
    from driver.sim.autopilot import Autopilot
    monkeypatch.setattr(Autopilot, "initialised", property(lambda self: False))     # still booting
    sim = sim_factory(home=HOME)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.connected, 10)
    result = vehicle.upload_plan(mission()).result(10).result
    assert result.status is CommandStatus.REFUSED, result
    assert result.reason == ("NO_SPACE: more items than the vehicle can store; the vehicle says: Only 0 items are "
                             "supported"), result
