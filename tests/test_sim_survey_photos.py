"""The simulated ArduCopter takes a survey's photos as ArduPilot does (issue 29, item 21): DO_SET_CAM_TRIGG_DIST in
a mission sets the trigger distance (AP_Mission::start_command_camera; param3 1: a picture at once) and
AP_Camera_Backend::update takes one each time the vehicle has moved that far, confirmed by CAMERA_FEEDBACK; 0
stops it, and without a camera nothing is taken."""
from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.mission.plan import MissionItem, MissionRunState, Plan, PlanKind
from test_mission_flight import quick_rtl
from test_mission_transfer import waypoint

pytestmark = pytest.mark.timeout(120)


def trigger(distance: float) -> MissionItem:
    return MissionItem(mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST, frame=mavlink.MAV_FRAME_MISSION, param1=distance,
                       param3=1.0 if distance > 0 else 0.0)


def one_pass(drone) -> Plan:
    """A survey's pass as the viewer plans it: entry, camera every 5 m (one at once), 30 m along, camera off."""
    return Plan(PlanKind.MISSION, (
        MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=6), waypoint(drone, 0, 0, 6), trigger(5.0),
        waypoint(drone, 30, 0, 6), trigger(0.0), waypoint(drone, 30, 20, 6),
        MissionItem(mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH, frame=mavlink.MAV_FRAME_MISSION)))


def fly(drone):
    assert drone.wait_for(lambda s: s.connected and s.home is not None, 20)
    assert drone.upload_plan(one_pass(drone)).result(30).result.ok
    assert drone.start_mission().result(60).ok
    done = drone.wait_for(lambda s: s.mission.state is MissionRunState.COMPLETE and not s.armed, 100)
    assert done is not None, drone.state().mission
    return done


def test_a_survey_pass_takes_its_photos(sim_factory, vehicle_factory):
    sim = quick_rtl(sim_factory(speedup=8.0, camera="trigger"))
    drone = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    done = fly(drone)
    # one at the pass's start, then one each 5 m of its 30 m (the waypoint counts as reached up to its radius
    # before it: 5 or 6 more), none after the camera went off (the last leg is 20 m)
    assert done.camera.photos == sim.autopilot.images, (done.camera.photos, sim.autopilot.images)
    assert 6 <= done.camera.photos <= 7, done.camera.photos


def test_without_a_camera_no_photos(sim_factory, vehicle_factory):
    sim = quick_rtl(sim_factory(speedup=8.0))
    drone = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    done = fly(drone)
    assert done.camera.photos == 0 and sim.autopilot.images == 0
