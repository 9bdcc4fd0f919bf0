"""Missions, fences and rally points to and from the simulated ArduCopter through the embedded driver."""
from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.core import frames
from driver.mission.plan import MissionItem, Plan, PlanKind
from driver.vehicle.state import CommandStatus


def place(vehicle, north, east):
    home = vehicle.state().home
    return frames.offset_latlon(home.lat, home.lon, north, east)


def waypoint(vehicle, north, east, alt, hold=0.0):
    lat, lon = place(vehicle, north, east)
    return MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, param1=hold, lat=lat, lon=lon, alt=alt)


def survey_mission(vehicle, count: int) -> Plan:
    items = [MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=10)]
    items += [waypoint(vehicle, 5.0 * (i % 10), 5.0 * (i // 10), 10 + i % 3) for i in range(count - 2)]
    items.append(MissionItem(mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH, frame=mavlink.MAV_FRAME_MISSION))
    return Plan(PlanKind.MISSION, tuple(items))


def fence_plan(vehicle) -> Plan:
    corners = [place(vehicle, n, e) for n, e in ((-40, -40), (60, -40), (60, 60), (-40, 60))]
    items = [MissionItem(mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION, frame=mavlink.MAV_FRAME_GLOBAL,
                         param1=4, lat=lat, lon=lon) for lat, lon in corners]
    lat, lon = place(vehicle, -30, -30)
    items.append(MissionItem(mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION, frame=mavlink.MAV_FRAME_GLOBAL, param1=5,
                             lat=lat, lon=lon))
    return Plan(PlanKind.FENCE, tuple(items))


@pytest.fixture
def homed(vehicle):
    assert vehicle.wait_for(lambda s: s.home is not None and s.firmware, 20), "no home position"
    return vehicle


def test_upload_reads_back_and_the_vehicle_holds_it(homed, sim):
    plan = survey_mission(homed, 12)
    outcome = homed.upload_plan(plan).result(30)
    assert outcome.result.status is CommandStatus.ACCEPTED, str(outcome.result)
    assert "accepted and read back" in outcome.result.reason
    assert len(outcome.plan) == 12 and outcome.plan.items[0].command == mavlink.MAV_CMD_NAV_TAKEOFF
    # the vehicle's own store: home slot + 12, item 0 replaced by its home, RTL read back in frame 0
    stored = sim.autopilot.plan_items(PlanKind.MISSION)
    assert len(stored) == 13 and stored[0].x == round(sim.autopilot.home_lat * 1e7)
    assert stored[-1].frame == mavlink.MAV_FRAME_GLOBAL
    s = homed.wait_for(lambda s: s.mission.count == 12, 5)
    assert s is not None and s.mission.vehicle_plan(PlanKind.MISSION) == outcome.plan
    assert s.mission.transfers == ()


def test_download_fence_and_rally_then_clear(homed, sim):
    fence = fence_plan(homed)
    up = homed.upload_plan(fence).result(30)
    assert up.result.ok, str(up.result)
    lat, lon = place(homed, 20, 10)
    rally = Plan(PlanKind.RALLY, (MissionItem(mavlink.MAV_CMD_NAV_RALLY_POINT, lat=lat, lon=lon, alt=15),))
    assert homed.upload_plan(rally).result(30).result.ok
    down = homed.download_plan(PlanKind.FENCE).result(30)
    assert down.result.ok and len(down.plan) == 5
    assert all(not item.autocontinue for item in down.plan.items)          # ArduPilot's read-back
    assert homed.download_plan(PlanKind.RALLY).result(30).plan.items[0].alt == pytest.approx(15)
    cleared = homed.clear_plan(PlanKind.FENCE).result(10)
    assert cleared.status is CommandStatus.ACCEPTED, str(cleared)
    assert sim.autopilot.plans[PlanKind.FENCE] == [] and len(sim.autopilot.plans[PlanKind.RALLY]) == 1
    assert homed.download_plan(PlanKind.FENCE).result(30).plan == Plan(PlanKind.FENCE)


def test_upload_over_a_lossy_link_is_exact_or_reported(homed, sim):
    sim.faults.uplink.loss = 0.3
    sim.faults.downlink.loss = 0.3
    plan = survey_mission(homed, 12)
    outcome = homed.upload_plan(plan).result(120)
    sim.faults.uplink.loss = sim.faults.downlink.loss = 0.0
    assert outcome.result.status is CommandStatus.ACCEPTED, str(outcome.result)
    stored = sim.autopilot.plan_items(PlanKind.MISSION)[1:]
    assert [(s.command, s.x, s.y) for s in stored] == \
        [(i.command, round(i.lat * 1e7), round(i.lon * 1e7)) for i in plan.items]


def test_items_beyond_the_limits_are_refused_by_item(homed, sim):
    plan = Plan(PlanKind.MISSION, (MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=10),
                                   waypoint(homed, 800, 0, 20), waypoint(homed, 10, 0, 300)))
    result = homed.upload_plan(plan).result(5).result
    assert result.status is CommandStatus.REJECTED
    assert "item 2 (WAYPOINT): 800 m from home" in result.reason and "item 3 (WAYPOINT): 300 m" in result.reason
    assert sim.autopilot.plans[PlanKind.MISSION] == []                    # nothing went out


def test_a_transfer_can_be_cancelled_and_one_runs_per_kind(homed, sim):
    sim.faults.link_down = True
    first = homed.download_plan(PlanKind.MISSION)
    second = homed.download_plan(PlanKind.MISSION).result(5)
    assert second.result.status is CommandStatus.REJECTED and "running" in second.result.reason
    assert homed.wait_for(lambda s: s.mission.transfer(PlanKind.MISSION) is not None, 5)
    homed.cancel_transfer(PlanKind.MISSION)
    assert first.result(5).result.status is CommandStatus.ABORTED
    assert homed.wait_for(lambda s: s.mission.transfers == (), 5)


def test_the_vehicles_refusals_are_shown_with_their_meaning(homed, sim):
    from test_sim import GroundStation
    other = GroundStation(sim.tcp_port, system=254)           # another ground station starts an upload
    try:
        other.send(other.encoder.mission_count_encode(1, 1, 3, 0))
        assert other.wait(lambda m: m.get_type() == "MISSION_REQUEST" and m.target_system == 254, 5)
        refused = homed.download_plan(PlanKind.MISSION).result(10).result
        assert refused.status is CommandStatus.REFUSED
        assert refused.reason == "DENIED: the vehicle is busy with another transfer"
    finally:
        other.close()
    too_many = Plan(PlanKind.MISSION, tuple(waypoint(homed, 1, 1, 5) for _ in range(701)))
    sim.autopilot.uploads.clear()                               # the other station's upload given up
    refused = homed.upload_plan(too_many).result(30).result
    assert refused.status is CommandStatus.REFUSED
    assert refused.reason.startswith("NO_SPACE: more items than the vehicle can store")
    assert homed.wait_for(lambda s: any(m.text == "Only 700 items are supported" for m in s.messages), 5)


def test_an_error_for_the_last_item_sent_again_is_no_refusal_when_the_vehicle_holds_the_plan(homed, sim,
                                                                                           monkeypatch):
    """The relay loses the vehicle's MISSION_ACK ACCEPTED of a fence: the driver sends the last vertex again, and
    ArduPilot, no longer receiving, answers it MISSION_ACK ERROR (GCS_Common.cpp, GCS_MAVLINK::handle_mission_item:
    ``if (!prot->receiving)``). The vehicle holds the fence: the read-back decides, not that late ERROR."""
    autopilot = sim.autopilot
    ack, answers = autopilot._ack, []

    def relay(msg, result, kind, link=None):
        answers.append((kind, result))
        if (kind, result) == (PlanKind.FENCE, mavlink.MAV_MISSION_ACCEPTED) and answers.count((kind, result)) == 1:
            return                                              # lost on the way
        ack(msg, result, kind, link)
    monkeypatch.setattr(autopilot, "_ack", relay)
    plan = fence_plan(homed)
    outcome = homed.upload_plan(plan).result(30)
    assert (PlanKind.FENCE, mavlink.MAV_MISSION_ERROR) in answers          # the late answer did come
    assert outcome.result.status is CommandStatus.ACCEPTED, str(outcome.result)
    assert "read back as sent" in outcome.result.reason
    assert len(autopilot.plans[PlanKind.FENCE]) == 5
    assert homed.wait_for(lambda s: s.mission.vehicle_plan(PlanKind.FENCE) == outcome.plan, 5)


def test_clearing_a_running_mission_is_refused_with_the_vehicles_word_after_reading_it_back(homed, sim):
    """MISSION_CLEAR_ALL of a running mission: ArduPilot answers ERROR (AP_Mission::clear refuses). An ERROR may
    also be a late answer to a repeated item, so the plan is read back: it is still there, so refused."""
    plan = survey_mission(homed, 4)
    assert homed.upload_plan(plan).result(30).result.ok
    sim.autopilot.mission_running = lambda: True
    result = homed.clear_plan(PlanKind.MISSION).result(10)
    assert result.status is CommandStatus.REFUSED, str(result)
    assert result.reason == "ERROR: the vehicle reported an error; the vehicle still holds 4 items"
    assert len(sim.autopilot.plans[PlanKind.MISSION]) == 5


def test_a_land_item_is_held_as_arducopter_reads_it_back(homed, sim):
    """ArduPilot keeps NAV_LAND's param4 only as a yaw direction and reads it back as 1 or -1 (AP_Mission.cpp;
    ArduCopter 4.6.3 SITL read back 1 for the 0 sent): that is the plan sent, not another one."""
    lat, lon = place(homed, 0, 0)
    plan = Plan(PlanKind.MISSION, (MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=10), waypoint(homed, 20, 0, 10),
                                   MissionItem(mavlink.MAV_CMD_NAV_LAND, lat=lat, lon=lon)))
    outcome = homed.upload_plan(plan).result(30)
    assert sim.autopilot.plan_items(PlanKind.MISSION)[-1].params[3] == 1.0
    assert outcome.result.status is CommandStatus.ACCEPTED, str(outcome.result)


def test_an_upload_rides_out_a_second_of_silence_at_its_start(homed, sim):
    """A fast link's round trip makes MISSION_COUNT go again within 0.1 s; unanswered, each try waits twice as long,
    so a 1 s outage (a radio fading as Upload is pressed) costs a few tries, not the upload."""
    sim.faults.outage(1.0)
    outcome = homed.upload_plan(survey_mission(homed, 6)).result(60)
    assert outcome.result.status is CommandStatus.ACCEPTED, str(outcome.result)
    assert len(sim.autopilot.plan_items(PlanKind.MISSION)) == 7
