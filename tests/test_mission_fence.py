"""The polygon fence: uploaded, enforced by the simulated vehicle as AC_Fence does, and checked by the driver
before a mission goes up."""
from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.mission.plan import MissionItem, Plan, PlanKind
from driver.vehicle.state import CommandStatus
from test_driver_flight import STICK_DEADMAN, hold_velocity
from test_mission_transfer import place, waypoint


def square_fence(vehicle, half: float) -> Plan:
    corners = [place(vehicle, n, e) for n, e in ((-half, -half), (half, -half), (half, half), (-half, half))]
    return Plan(PlanKind.FENCE, tuple(MissionItem(mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                                                  mavlink.MAV_FRAME_GLOBAL, 4, lat=lat, lon=lon)
                                      for lat, lon in corners))


def test_the_vehicle_turns_back_at_its_polygon_fence_and_the_driver_checks_missions(sim, vehicle_factory):
    drone = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", deadman=STICK_DEADMAN)
    assert drone.wait_for(lambda s: s.connected and s.home is not None and s.fence.known, 20)
    assert drone.upload_plan(square_fence(drone, 15)).result(30).result.ok
    assert drone.set_parameter("FENCE_ENABLE", 1).result(10).ok
    assert drone.wait_for(lambda s: s.fence.enabled, 5)

    outside = Plan(PlanKind.MISSION, (MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=5), waypoint(drone, 10, 0, 5),
                                      waypoint(drone, 40, 0, 5)))
    refused = drone.upload_plan(outside).result(5).result
    assert refused.status is CommandStatus.REJECTED
    assert "item 3 (WAYPOINT): outside an inclusion polygon" in refused.reason and "item 2" not in refused.reason

    assert drone.takeoff(3.0).result(60).ok
    hold_velocity(drone, sim, 3.0, 0.0, 0.0, 0.0, 10.0)                  # north, out of the 15 m square
    s = drone.wait_for(lambda s: s.fence.breached and s.mode == "RTL", 10)
    assert s is not None, (drone.state().fence, drone.state().mode)
    assert sim.autopilot.fence_breaches & 4 and sim.truth().north > 15
    assert any("Fence breached" in m.text for m in s.messages)
