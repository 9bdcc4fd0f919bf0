"""The driver against real ArduCopter recordings (tests/data/recordings/), answered by the replay vehicle
(driver/sim/replay.py): the same answers to the same requests, in order, with the recorded timing (sped up).

Where the simulator answers as we believed ArduPilot answers, these answer as it did. Each test also checks
that no request of the driver went unanswered except the link's own upkeep (streams, message intervals, home,
version, the failsafe and fence parameters: the recorded ground stations did not ask for those) and what the
test names with its reason.
"""
from __future__ import annotations

from dataclasses import replace

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.mission.plan import Plan, PlanKind
from driver.mission.wire import from_wire
from driver.payload.control import MANAGER
from driver.params.model import ParamType
from driver.params.values import as_stored
from driver.sim.replay import ReplayVehicle, read_tlog
from driver.vehicle.state import CommandStatus
from driver.vehicle.supervision import WANTED_PARAMS

from recordings import FTP_PARAMS, FTP_PARAMS_SERIAL1, GIMBAL, MISSION, PARAMS, SETUP  # noqa: E402

#: Requests the driver makes by itself on every link (driver.vehicle.supervision, driver.payload) that the recorded
#: ground stations did not: (MAV_CMD, param1) of COMMAND_LONG, or any REQUEST_DATA_STREAM / those parameters.
UPKEEP_COMMANDS = {
    (mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, float(mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE)),
    (mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, float(mavlink.MAVLINK_MSG_ID_HOME_POSITION)),
    (mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, float(mavlink.MAVLINK_MSG_ID_ADSB_VEHICLE)),
    (mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, float(mavlink.MAVLINK_MSG_ID_GIMBAL_DEVICE_ATTITUDE_STATUS)),
    (mavlink.MAV_CMD_REQUEST_MESSAGE, float(mavlink.MAVLINK_MSG_ID_HOME_POSITION)),
    (mavlink.MAV_CMD_REQUEST_MESSAGE, float(mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION)),
    (mavlink.MAV_CMD_REQUEST_MESSAGE, float(mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_INFORMATION)),
    (mavlink.MAV_CMD_GET_HOME_POSITION, 0.0),
    (mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1.0),
}


def upkeep(request) -> bool:
    key = request.key
    if key[0] == "REQUEST_DATA_STREAM":
        return True
    if key[0] == "COMMAND_LONG":
        return (key[1], key[2]) in UPKEEP_COMMANDS
    return key[0] == "PARAM_REQUEST_READ" and key[1] in WANTED_PARAMS


def unexpected(replay: ReplayVehicle) -> list:
    """What the driver asked that the recording does not answer, besides the link's upkeep."""
    return [r for r in replay.unanswered if not upkeep(r)]


@pytest.fixture
def connect(vehicle_factory):
    """The driver on a replay vehicle, with its heartbeat seen; no parameter cache (the table comes from the
    recording alone)."""
    def make(replay: ReplayVehicle):
        v = vehicle_factory(f"tcp:127.0.0.1:{replay.tcp_port}", param_cache=None)
        assert v.wait_for(lambda s: s.connected, 10), "no heartbeat from the replay"
        return v
    return make


def listed(replay: ReplayVehicle, which: int) -> dict:
    """name -> (value, type, index) of the recording's ``which``-th PARAM_REQUEST_LIST answer."""
    ex = replay.recording.exchanges_of("PARAM_REQUEST_LIST")[which]
    return {p.param_id: (p.param_value, ParamType(p.param_type), p.param_index)
            for _, p, _ in ex.answers if p.get_type() == "PARAM_VALUE"}


def table_of(state) -> dict:
    return {name: (p.value, p.type, p.index) for name, p in state.parameters.values.items()}


def stored(params: dict) -> dict:
    """The recorded values as the driver holds them (integers rounded, floats as float32)."""
    return {name: (as_stored(t, value), t, index) for name, (value, t, index) in params.items()}


# -- parameters -------------------------------------------------------------------------------------------------
def test_parameter_list_read_and_sets_as_recorded(replay_factory, connect):
    replay = replay_factory(PARAMS)
    v = connect(replay)
    # the driver reads FS_GCS_ENABLE by name on every link (its failsafe warning): the recorded read answers it
    assert v.wait_for(lambda s: s.gcs_failsafe is not None, 10), "FS_GCS_ENABLE unanswered"
    result = v.fetch_parameters().result(timeout=10)
    assert result.status is CommandStatus.ACCEPTED, result
    first = listed(replay, 0)
    assert len(first) == 1392
    assert table_of(v.state()) == stored(first)            # every name, value, type and index as listed
    kinds = [t for _, t, _ in first.values()]
    assert [kinds.count(t) for t in (ParamType.INT8, ParamType.INT16, ParamType.INT32, ParamType.REAL32)] == \
        [418, 328, 86, 560]
    read = next(r for r in replay.requests if r.key == ("PARAM_REQUEST_READ", "FS_GCS_ENABLE"))
    assert read.answered_by == pytest.approx(4.003, abs=0.001)
    assert v.state().gcs_failsafe == 0

    # writes, all at once: a float, an int8 (sent in its own type, echoed in it), an int32 far out of any
    # sensible range (the vehicle does not range-check), and a name the vehicle does not have
    sets = {name: v.set_parameter(name, value, allow_out_of_bounds=True)
            for name, value in (("WPNAV_SPEED", 750.0), ("FS_GCS_ENABLE", 1.0), ("RTL_ALT", 1e9),
                                ("NO_SUCH_PARAM", 1.0))}
    results = {name: f.result(timeout=10) for name, f in sets.items()}
    for name in ("WPNAV_SPEED", "FS_GCS_ENABLE", "RTL_ALT"):
        assert results[name].status is CommandStatus.ACCEPTED, results[name]
    table = v.state().parameters
    assert (table.get("FS_GCS_ENABLE").value, table.get("FS_GCS_ENABLE").type) == (1.0, ParamType.INT8)
    assert table.get("RTL_ALT").value == 1e9 and table.get("WPNAV_SPEED").value == 750.0
    # the complete list says the vehicle has no NO_SUCH_PARAM: only then may the driver say so
    assert results["NO_SUCH_PARAM"].status is not CommandStatus.ACCEPTED
    assert "not in the vehicle's list" in results["NO_SUCH_PARAM"].reason, results["NO_SUCH_PARAM"]

    # the list again: the vehicle's own second list, with the new values
    result = v.fetch_parameters(refresh=True).result(timeout=10)
    assert result.status is CommandStatus.ACCEPTED, result
    second = listed(replay, 1)
    assert (second["WPNAV_SPEED"][0], second["FS_GCS_ENABLE"][0], second["RTL_ALT"][0]) == (750.0, 1.0, 1e9)
    assert table_of(v.state()) == stored(second)
    # unanswered: only the repeats of the set of the unknown name (its one recorded try had no answer)
    assert [(r.key, r.why) for r in unexpected(replay)] == \
        [(("PARAM_SET", "NO_SUCH_PARAM", 1.0), "its 1 recorded answer(s) are used up")] * 2


def test_an_unanswered_set_before_the_list_is_not_called_an_unknown_name(replay_factory, connect):
    """ArduPilot answers an unknown name with silence, and so does a lost link: before the complete list says
    the name is not there, silence proves nothing."""
    replay = replay_factory(PARAMS)
    v = connect(replay)
    result = v.set_parameter("NO_SUCH_PARAM", 1.0).result(timeout=15)
    assert result.status is CommandStatus.TIMED_OUT, result
    assert "has no parameter" not in result.reason, result.reason
    # the set's repeats, and reads by name of it (its one recorded read had no answer either)
    assert {r.key for r in unexpected(replay)} <= {("PARAM_SET", "NO_SUCH_PARAM", 1.0),
                                                   ("PARAM_REQUEST_READ", "NO_SUCH_PARAM")}, unexpected(replay)


def test_parameters_over_mavlink_ftp_as_recorded(replay_factory, connect):
    replay = replay_factory(FTP_PARAMS)
    v = connect(replay)
    # this recording's ground station never asked for AUTOPILOT_VERSION; the same firmware (4.6.3, the mission
    # recording) advertises MAVLink FTP there
    version = next(m for _, m in read_tlog(MISSION + ".tlog") if m.get_type() == "AUTOPILOT_VERSION")
    assert version.capabilities & mavlink.MAV_PROTOCOL_CAPABILITY_FTP
    with v._lock:
        v._params.ftp_capable = True
    result = v.fetch_parameters().result(timeout=3)      # the recorded read took 0.4 s (0.04 s here)
    assert result.status is CommandStatus.ACCEPTED and "FTP" in result.reason, result
    # the same session's PARAM_REQUEST_LIST on SERIAL1: 1,397 parameters, equal to param.pck (the README)
    recorded = {m.param_id: (as_stored(ParamType(m.param_type), m.param_value), ParamType(m.param_type),
                             m.param_index)
                for _, m in read_tlog(FTP_PARAMS_SERIAL1 + ".tlog") if m.get_type() == "PARAM_VALUE"}
    assert len(recorded) == 1397
    assert table_of(v.state()) == recorded
    assert unexpected(replay) == []


# -- missions, fences, rally points -----------------------------------------------------------------------------
def recorded_plan(replay: ReplayVehicle, kind: PlanKind, at: float) -> Plan:
    """The plan the recorded ground station uploaded from ``at`` (mission: less the home slot). An item it sent as
    a float MISSION_ITEM has the position the vehicle stored for it (read back: float32 rounding, 8 cm here),
    which is what the driver's MISSION_ITEM_INT of the same place leaves."""
    items = [ex.request for ex in replay.recording.exchanges if ex.t >= at
             and ex.request.get_type() in ("MISSION_ITEM", "MISSION_ITEM_INT")
             and ex.request.mission_type == int(kind)]
    count = next(ex.request.count for ex in replay.recording.exchanges_of("MISSION_COUNT")
                 if ex.t >= at and ex.request.mission_type == int(kind))
    held = read_back(replay, kind, at, count)
    items = [from_wire(m) if m.get_type() == "MISSION_ITEM_INT" else
             replace(from_wire(m), lat=held[m.seq].lat, lon=held[m.seq].lon) for m in items[:count]]
    return Plan(kind, tuple(items[1:] if kind is PlanKind.MISSION else items))


def read_back(replay: ReplayVehicle, kind: PlanKind, at: float, count: int) -> list:
    """The ``count`` items the vehicle sent when the recorded ground station read the plan back after ``at``."""
    items = [m for ex in replay.recording.exchanges_of("MISSION_REQUEST_INT") if ex.t >= at
             and ex.request.mission_type == int(kind) for _, m, _ in ex.answers if m.get_type() == "MISSION_ITEM_INT"]
    return [from_wire(m) for m in items[:count]]


def test_mission_fence_and_rally_transfers_as_recorded(replay_factory, connect):
    # the upload with an item out of order (19.998-35.0 s) tests the vehicle, not a driver that sends in order
    replay = replay_factory(MISSION, skip=((19.5, 34.5),))
    v = connect(replay)
    # the driver asks MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, the recorded station REQUEST_MESSAGE: the same answer
    assert v.wait_for(lambda s: s.firmware, 10) and v.state().firmware == "4.6.3", v.state().firmware
    outcome = v.download_plan(PlanKind.MISSION).result(timeout=10)       # the empty mission (count 0)
    assert outcome.result.status is CommandStatus.ACCEPTED and len(outcome.plan) == 0, outcome
    # the recorded ground station uploaded once home was set (HOME_POSITION at 19 s): the driver checks the
    # plan's distances from it
    assert v.wait_for(lambda s: s.home is not None, 10), "no HOME_POSITION in the replayed telemetry"
    for kind, at in ((PlanKind.MISSION, 35.0), (PlanKind.FENCE, 37.0), (PlanKind.RALLY, 38.0)):
        plan = recorded_plan(replay, kind, at)
        assert len(plan) == {PlanKind.MISSION: 6, PlanKind.FENCE: 5, PlanKind.RALLY: 1}[kind]
        outcome = v.upload_plan(plan).result(timeout=10)
        assert outcome.result.status is CommandStatus.ACCEPTED, outcome.result
        # the vehicle's own items, as it sent them (mission: less home)
        held = read_back(replay, kind, at, len(plan) + (kind is PlanKind.MISSION))
        assert list(outcome.plan.items) == (held[1:] if kind is PlanKind.MISSION else held)
        # the driver sent what the recorded ground station sent
        sent = {r.key[2]: from_wire(r.message) for r in replay.requests
                if r.type == "MISSION_ITEM_INT" and r.key[1] == int(kind)}
        first = 1 if kind is PlanKind.MISSION else 0                      # the mission's item 0 is home
        assert [sent[first + i] for i in range(len(plan))] == list(plan.items)
    texts = [m.text for m in v.state().messages if m.source == "vehicle"]
    assert "Flight plan received" in texts and "Fence Indexed OK" in texts
    # the float MISSION_ITEM the recording has for item 4 answered the driver's MISSION_ITEM_INT, less its text
    item4 = next(r for r in replay.requests if r.key == ("MISSION_ITEM_INT", 0, 4))
    assert item4.answered_by is not None and "MISSION_ITEM" in item4.why
    assert not any("MISSION_ITEM_INT" in t for t in texts), texts
    result = v.clear_plan(PlanKind.MISSION).result(timeout=10)
    assert result.status is CommandStatus.ACCEPTED, result
    outcome = v.download_plan(PlanKind.MISSION).result(timeout=10)
    assert outcome.result.status is CommandStatus.ACCEPTED and len(outcome.plan) == 0, outcome
    assert unexpected(replay) == []


# -- gimbal, setup ----------------------------------------------------------------------------------------------
def recorded_result(replay: ReplayVehicle, command: int, *params: float) -> int:
    """The final COMMAND_ACK result of the first recorded ``command`` whose first parameters are ``params``."""
    ex = next(ex for ex in replay.recording.exchanges_of("COMMAND_LONG")
              if ex.key[1] == command and ex.key[2:2 + len(params)] == params)
    return [m.result for _, m, _ in ex.answers if m.get_type() == "COMMAND_ACK"][-1]


def test_gimbal_commands_answered_as_recorded(replay_factory, connect):
    replay = replay_factory(GIMBAL)
    v = connect(replay)
    s = v.wait_for(lambda s: s.gimbal.pitch_deg is not None, 10)       # GIMBAL_DEVICE_ATTITUDE_STATUS
    assert s is not None, v.state().gimbal
    pitchyaw = mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW
    assert recorded_result(replay, pitchyaw, -90.0) == recorded_result(replay, pitchyaw, 0.0) == \
        mavlink.MAV_RESULT_ACCEPTED
    for pitch in (-90.0, 0.0):
        result = v.point_gimbal(pitch, 0.0).result(timeout=10)
        assert result.status is CommandStatus.ACCEPTED, result
    assert v.state().gimbal.protocol == MANAGER
    roi = next(ex.request for ex in replay.recording.exchanges_of("COMMAND_LONG")
               if ex.request.command == mavlink.MAV_CMD_DO_SET_ROI_LOCATION)
    result = v.look_at(roi.param5, roi.param6, roi.param7).result(timeout=10)
    assert result.status is CommandStatus.ACCEPTED, result
    assert recorded_result(replay, mavlink.MAV_CMD_DO_SET_ROI_LOCATION) == mavlink.MAV_RESULT_ACCEPTED
    result = v.stop_looking().result(timeout=10)
    assert result.status is CommandStatus.ACCEPTED, result
    # no camera configured: DO_DIGICAM_CONTROL is still ACCEPTED (the vehicle's ACK; no picture confirms it)
    v.take_photo()
    s = v.wait_for(lambda s: any(r.command == "DO_DIGICAM_CONTROL shoot" for r in s.results), 10)
    assert s is not None, v.state().results
    shoot = next(r for r in s.results if r.command == "DO_DIGICAM_CONTROL shoot")
    assert shoot.status is CommandStatus.ACCEPTED, shoot
    # the driver's own gimbal requests at connect were recorded too: the 5 Hz attitude interval was ACCEPTED,
    # GIMBAL_MANAGER_INFORMATION and CAMERA_INFORMATION answered as recorded
    answered = {r.key[1:3] for r in replay.requests if r.key[0] == "COMMAND_LONG" and r.answered_by is not None}
    assert {(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 285.0), (mavlink.MAV_CMD_REQUEST_MESSAGE, 259.0),
            (mavlink.MAV_CMD_REQUEST_MESSAGE, 280.0)} <= answered
    assert unexpected(replay) == []


def test_level_calibration_and_arming_answered_as_recorded(replay_factory, connect):
    replay = replay_factory(SETUP)
    v = connect(replay)
    assert v.wait_for(lambda s: s.in_air is False, 10)       # no calibration before it says it is on the ground
    assert recorded_result(replay, mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0.0, 0.0, 0.0, 0.0, 2.0) == \
        mavlink.MAV_RESULT_ACCEPTED
    result = v.calibrate_level().result(timeout=10)
    assert result.status is CommandStatus.ACCEPTED, result
    s = v.wait_for(lambda s: any(m.text.startswith("Trim OK") for m in s.messages), 10)
    assert s is not None, [m.text for m in v.state().messages]
    # the recording armed twice: accepted (58.7 s), then refused after the failed accel calibration (133.3 s),
    # with the vehicle's own reasons; the driver tells them as the vehicle said them
    result = v.arm().result(timeout=10)
    assert result.status is CommandStatus.ACCEPTED, result
    assert v.wait_for(lambda s: not s.armed, 10)          # disarmed by itself on the ground (DISARM_DELAY)
    result = v.arm().result(timeout=10)
    assert result.status is CommandStatus.REFUSED, result
    assert "Arm: 3D Accel calibration needed" in result.reason and "MAV_RESULT_FAILED" in result.reason, result
    assert unexpected(replay) == []
