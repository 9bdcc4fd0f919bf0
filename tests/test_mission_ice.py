"""Missions through Ice (mavlinkserver.ice): the remote drone uploads, reads back and flies a mission exactly as
the embedded driver does, and the mission's progress arrives in its status."""
from __future__ import annotations

from ice_fixtures import drone_factory, server_factory  # noqa: F401
from driver.mission.plan import MissionRunState, Plan, PlanKind
from driver.vehicle.state import CommandStatus
from test_mission_flight import fly, quick_rtl, recorded_mission
from test_mission_transfer import fence_plan


def test_a_mission_through_ice(sim_factory, vehicle_factory, server_factory, drone_factory):  # noqa: F811
    sim = quick_rtl(sim_factory(speedup=8.0))
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.connected and s.home is not None, 20)
    drone = drone_factory(server_factory(vehicle))
    assert drone.wait_for(lambda s: s.connected and s.home is not None, 20)

    plan = recorded_mission(drone)
    uploaded = drone.upload_plan(plan).result(30)
    assert uploaded.result.status is CommandStatus.ACCEPTED, str(uploaded.result)
    assert uploaded.plan is not None and [i.command for i in uploaded.plan.items] == [i.command for i in plan.items]
    s = drone.wait_for(lambda s: s.mission.count == 6 and s.mission.state is MissionRunState.NOT_STARTED, 10)
    assert s is not None and s.mission.vehicle_plan(PlanKind.MISSION) == uploaded.plan
    fence = drone.upload_plan(fence_plan(drone)).result(30)
    assert fence.result.ok, str(fence.result)
    assert drone.download_plan(PlanKind.FENCE).result(30).plan == fence.plan
    assert drone.clear_plan(PlanKind.FENCE).result(10).status is CommandStatus.ACCEPTED
    assert sim.autopilot.plans[PlanKind.FENCE] == []

    texts = fly(drone, sim)
    assert "Mission: 6 RTL" in texts and "Disarming motors" in texts
    assert drone.clear_plan(PlanKind.MISSION).result(10).ok
    assert drone.download_plan(PlanKind.MISSION).result(30).plan == Plan(PlanKind.MISSION)


def test_a_plan_of_no_known_kind_is_refused_with_its_reason(sim, vehicle_factory, server_factory,  # noqa: F811
                                                            drone_factory):  # noqa: F811
    from driver.ice import load_slice
    _, mavlinkserver = load_slice()
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    drone = drone_factory(server_factory(vehicle))
    assert drone.wait_for(lambda s: s.connected, 20)
    answer = drone._vehicle.uploadPlan(mavlinkserver.Plan(kind=7, items=[]))   # as a foreign client could send
    assert answer.outcome.status == "REJECTED"
    assert answer.outcome.reason == "no plan kind 7", answer.outcome.reason
