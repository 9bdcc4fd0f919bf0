"""An upload's read-back on a clock the test moves: what the pilot is told when the vehicle does not answer it.

The vehicle is scripted message by message (ArduCopter's MissionItemProtocol, as the simulator serves it) and the
driver is not started: ``ingest`` feeds what the vehicle says, ``step`` runs the ticker at the clock's time. So
"the read-back got no answer for 20 s" is exactly that, on a loaded machine as on an idle one.

At 30 % loss each way a read-back's MISSION_REQUEST_LIST and its MISSION_COUNT both arrive about half the time:
eight tries in a row lost happen, and the fault matrix's seeded link met them in one run of three (the same
frames lost whenever the upload took the same path). An upload the vehicle acknowledged is not "timed out" then,
and one whose last ACK was lost is still worth asking about: the vehicle is there, it answers in the end.
"""
from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.mission.plan import MissionItem, Plan, PlanKind
from driver.vehicle.state import CommandStatus
from test_driver_clock import at, clock, kinds, vehicle  # noqa: F401 (the driver on the test's clock, fixtures)

GCS = (255, 190)                                   # the driver's own ids, which the vehicle's answers target
PLAN = Plan(PlanKind.MISSION, (
    MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=10),
    MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, lat=40.2840, lon=-3.7941, alt=12),
    MissionItem(mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH, frame=mavlink.MAV_FRAME_MISSION)))
ON_WIRE = len(PLAN) + 1                            # the vehicle's home slot first


class Copter:
    """What the scripted ArduCopter says, packed as it sends it (system 1, component 1, MAVLink 2)."""

    def __init__(self) -> None:
        self.enc = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)

    def heartbeat(self) -> bytes:
        return self.enc.heartbeat_encode(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                         mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 4,
                                         mavlink.MAV_STATE_STANDBY).pack(self.enc)

    def request(self, seq: int) -> bytes:
        return self.enc.mission_request_int_encode(*GCS, seq, 0).pack(self.enc)

    def ack(self, result: int) -> bytes:
        return self.enc.mission_ack_encode(*GCS, result, 0).pack(self.enc)

    def count(self, n: int) -> bytes:
        return self.enc.mission_count_encode(*GCS, n, 0).pack(self.enc)

    def item(self, m) -> bytes:
        """Item ``m`` (what the driver sent) as the vehicle reads it back."""
        return self.enc.mission_item_int_encode(*GCS, m.seq, m.frame, m.command, 0, m.autocontinue, m.param1,
                                                m.param2, m.param3, m.param4, m.x, m.y, m.z, 0).pack(self.enc)


@pytest.fixture
def copter(vehicle) -> Copter:
    c = Copter()
    vehicle.ingest(c.heartbeat())
    return c


def upload_every_item(clock, vehicle, copter) -> tuple[object, dict]:
    """The upload up to its last item, each asked once and sent: the future, and the items as sent."""
    future = vehicle.upload_plan(PLAN)
    assert [m.count for m in kinds(at(clock, vehicle, 0.0), "MISSION_COUNT")] == [ON_WIRE]
    sent = {}
    for seq in range(ON_WIRE):
        vehicle.ingest(copter.request(seq))
        (item,) = kinds(at(clock, vehicle, 0.1 * (seq + 1)), "MISSION_ITEM_INT")
        assert item.seq == seq
        sent[seq] = item
    return future, sent


def unanswered(clock, vehicle, copter, start: float, end: float) -> list[float]:
    """The vehicle heard (a heartbeat a second) but never answering the read-back from ``start`` to ``end`` s:
    when the driver asked for the list."""
    asked = []
    for tenth in range(round(start * 10), round(end * 10)):
        t = tenth / 10
        if tenth % 10 == 0:
            vehicle.ingest(copter.heartbeat())
        asked += [t] * len(kinds(at(clock, vehicle, t), "MISSION_REQUEST_LIST"))
    return asked


def answer_read_back(clock, vehicle, copter, sent: dict, t: float) -> None:
    """The vehicle answers the next MISSION_REQUEST_LIST, then every item asked."""
    vehicle.ingest(copter.count(ON_WIRE))
    for _ in range(3 * ON_WIRE):
        t += 0.1
        for request in kinds(at(clock, vehicle, t), "MISSION_REQUEST_INT"):
            vehicle.ingest(copter.item(sent[request.seq]))


def test_an_acknowledged_upload_whose_read_back_gets_no_answer_is_sent_and_acknowledged_not_timed_out(
        clock, vehicle, copter):
    future, sent = upload_every_item(clock, vehicle, copter)
    vehicle.ingest(copter.ack(mavlink.MAV_MISSION_ACCEPTED))   # the vehicle has the plan and says so
    asked = unanswered(clock, vehicle, copter, 0.5, 20.0)      # ... and then every read-back is lost
    assert asked and asked[0] == 0.5
    result = future.result(timeout=10).result
    assert result.status is CommandStatus.ACCEPTED, str(result)
    assert result.reason.startswith("sent and acknowledged, not verified: the read-back got no answer"), result.reason
    assert vehicle.state().mission.vehicle_plan(PlanKind.MISSION) is None     # not claimed before it is read
    # it goes on verifying: the list is asked for after the verdict too, and the answer, when it comes, is taken
    assert [t for t in unanswered(clock, vehicle, copter, 20.0, 30.0)], "the read-back gave up"
    answer_read_back(clock, vehicle, copter, sent, 30.0)
    state = vehicle.state()
    held = state.mission.vehicle_plan(PlanKind.MISSION)
    assert held is not None and len(held) == len(PLAN)
    verified = [r for r in state.results if r.command == "verify mission"]
    assert [r.status for r in verified] == [CommandStatus.ACCEPTED], verified


def test_an_upload_whose_last_ack_was_lost_keeps_reading_back_while_the_vehicle_is_heard(clock, vehicle, copter):
    """The fault matrix's wrong report: the vehicle's ACCEPTED lost, ERROR to the last item sent again (the vehicle
    no longer receives it), then the read-back's first eight tries lost. The vehicle holds the plan: the driver
    must not have said "timed out" by the time the vehicle answers, 20 s on."""
    future, sent = upload_every_item(clock, vehicle, copter)
    assert kinds(at(clock, vehicle, 1.0), "MISSION_ITEM_INT")[0].seq == ON_WIRE - 1   # no ACK yet: the item again
    vehicle.ingest(copter.ack(mavlink.MAV_MISSION_ERROR))
    asked = unanswered(clock, vehicle, copter, 1.0, 21.0)
    assert len(asked) > 8, asked
    assert not future.done(), str(future.result().result)
    answer_read_back(clock, vehicle, copter, sent, 21.0)
    result = future.result(timeout=10).result
    assert result.status is CommandStatus.ACCEPTED, str(result)
    assert "read back as sent" in result.reason
    assert len(vehicle.state().mission.vehicle_plan(PlanKind.MISSION)) == len(PLAN)


def test_a_download_asks_for_the_list_for_half_a_minute_before_it_times_out(clock, vehicle, copter):
    future = vehicle.download_plan(PlanKind.MISSION)
    asked = unanswered(clock, vehicle, copter, 0.0, 40.0)
    result = future.result(timeout=10).result
    assert result.status is CommandStatus.TIMED_OUT, str(result)
    assert asked == [1.5 * i for i in range(20)], asked             # 1.5 s apart (no round trip measured yet)
    assert result.reason == "no answer to MISSION_REQUEST_LIST after 20 attempts in 30 s", result.reason
