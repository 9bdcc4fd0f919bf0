"""Firmware profiles (ArduCopter 4.x as recorded, the stock 3DR Solo), the EKF origin that is not home, and the
other systems on a real link: a gimbal, a companion computer, a second ground station."""
from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.sim import MODES, ManualClock, OtherGroundStation, SimConfig, SimVehicle
from test_sim import FAST, GroundStation, angle_deg, connect, hold, make_sim, wait_until  # noqa: F401
from test_sim_recordings import Replay

ARM = mavlink.MAV_CMD_COMPONENT_ARM_DISARM
TAKEOFF = mavlink.MAV_CMD_NAV_TAKEOFF
ACCEPTED, FAILED, UNSUPPORTED = mavlink.MAV_RESULT_ACCEPTED, mavlink.MAV_RESULT_FAILED, mavlink.MAV_RESULT_UNSUPPORTED
ARMED = mavlink.MAV_MODE_FLAG_SAFETY_ARMED


def set_mode(gs: GroundStation, name: str) -> None:
    """SET_MODE, the one way both firmwares take; the HEARTBEAT confirms it."""
    mark = gs.mark()
    gs.send(gs.encoder.set_mode_encode(1, mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MODES[name]))
    assert gs.wait(lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == MODES[name], since=mark)


def take_off(sim: SimVehicle, gs: GroundStation, altitude: float = 3.0) -> None:
    assert wait_until(lambda: sim.truth().ready, 10)
    set_mode(gs, "GUIDED")
    assert gs.command(ARM, 1).result == ACCEPTED
    assert gs.command(TAKEOFF, 0, 0, 0, 0, 0, 0, altitude).result == ACCEPTED
    assert wait_until(lambda: sim.truth().landed_state == mavlink.MAV_LANDED_STATE_IN_AIR, 20), sim.truth()


# -- the EKF origin ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("profile", ["copter-4", "solo"])
def test_local_positions_are_from_the_ekf_origin_and_relative_alt_from_home(profile, make_sim, connect):
    sim = make_sim(profile=profile)
    gs = connect(sim, mav1=profile == "solo")
    on, oe, od = sim.config.origin_offset
    assert (on, oe, od) != (0, 0, 0)
    assert wait_until(lambda: sim.truth().ready, 10)
    gs.request_streams(10)
    mark = gs.mark()
    local = gs.wait("LOCAL_POSITION_NED", since=mark)
    position = gs.wait("GLOBAL_POSITION_INT", since=mark)
    assert (local.x, local.y, local.z) == pytest.approx((-on, -oe, -od), abs=0.01)     # home seen from the origin
    assert abs(position.relative_alt) < 20 and position.alt == pytest.approx(664000, abs=20)
    ack = gs.command(mavlink.MAV_CMD_GET_HOME_POSITION)
    assert ack.result == ACCEPTED
    home = gs.wait("HOME_POSITION", since=mark)
    assert (home.x, home.y, home.z) == pytest.approx((-on, -oe, -od))
    assert (home.latitude, home.longitude, home.altitude) == (round(40.2839e7), round(-3.7940e7), 664000)
    if profile == "copter-4":                  # 4.x sends the origin with home (GPS_GLOBAL_ORIGIN)
        origin = gs.wait("GPS_GLOBAL_ORIGIN")
        assert (origin.latitude - home.latitude) * 1e-7 * 6378137 * math.pi / 180 == pytest.approx(on, abs=0.05)
        assert (home.altitude - origin.altitude) / 1000 == pytest.approx(od, abs=0.01)
    take_off(sim, gs)
    # MAV_FRAME_LOCAL_NED (0, 0, -5): above the origin; 3.3 takes z above home (pv_alt_above_origin)
    gs.setpoint(mavlink.MAV_FRAME_LOCAL_NED, 3576, x=0.0, y=0.0, z=-5.0)
    altitude = 5.0 if profile == "solo" else 5.0 - od
    assert wait_until(lambda: math.hypot(sim.truth().north - on, sim.truth().east - oe) < 0.2
                      and abs(sim.truth().altitude - altitude) < 0.2 and sim.truth().ground_speed < 0.05, 30), \
        sim.truth()
    mark = gs.mark()
    local = gs.wait("LOCAL_POSITION_NED", since=mark)
    position = gs.wait("GLOBAL_POSITION_INT", since=mark)
    truth = sim.truth()
    assert local.x == pytest.approx(truth.north - on, abs=0.1) and local.z == pytest.approx(truth.down - od, abs=0.1)
    assert position.relative_alt / 1000 == pytest.approx(truth.altitude, abs=0.1)


# -- 4.x as recorded -------------------------------------------------------------------------------------------
def test_copter4_announces_a_new_mode_at_once_and_answers_a_repeated_one():
    clock = ManualClock()
    sim = SimVehicle(SimConfig(**FAST), clock=clock).start()
    gs = GroundStation(sim.tcp_port)
    try:
        assert wait_until(lambda: sim.clients == 1, 10)
        replay = Replay(sim, clock, gs)
        replay.advance_to(1.1)
        for mode, heartbeat in ((MODES["GUIDED"], True), (MODES["GUIDED"], False)):
            mark = replay.deliver(gs.encoder.command_long_encode(1, 1, mavlink.MAV_CMD_DO_SET_MODE, 0, 1, mode,
                                                                 0, 0, 0, 0, 0), mav1=True)
            end = replay.marker()
            said = [m for m, _ in gs.frames[mark:end] if m.get_type() in ("COMMAND_ACK", "HEARTBEAT")]
            assert said[0].get_type() == "COMMAND_ACK" and said[0].result == ACCEPTED
            # recording 7.03 s: ACK, then a HEARTBEAT with the new mode in the same instant; none if unchanged
            assert [m.custom_mode for m in said[1:]] == ([mode] if heartbeat else [])
    finally:
        gs.close()
        sim.stop()


@pytest.mark.parametrize("profile, retry", [("copter-4", ACCEPTED), ("solo", FAILED)])
def test_a_takeoff_retried_two_seconds_in(profile, retry):
    """4.7 (recording): still land_complete 2 s after NAV_TAKEOFF (arming delay, spool-up), so ACCEPTED;
    the Solo (3.3) has left the ground by then, so "can't takeoff again". Both refuse once climbing."""
    clock = ManualClock()
    sim = SimVehicle(SimConfig(**dict(FAST, profile=profile)), clock=clock).start()
    gs = GroundStation(sim.tcp_port, mav1=profile == "solo")
    try:
        assert wait_until(lambda: sim.clients == 1, 10)
        replay = Replay(sim, clock, gs)
        replay.advance_to(1.0)

        def ask(command: int, *params: float) -> int:
            p = list(params) + [0.0] * (7 - len(params))
            mark = replay.deliver(gs.encoder.command_long_encode(1, 1, command, 0, *p), gs.mav1)
            end = replay.marker()
            return next(m.result for m, _ in gs.frames[mark:end] if m.get_type() == "COMMAND_ACK")

        replay.deliver(gs.encoder.set_mode_encode(1, mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MODES["GUIDED"]),
                       gs.mav1)
        assert sim.truth().mode == "GUIDED"
        assert ask(ARM, 1) == ACCEPTED and ask(TAKEOFF, 0, 0, 0, 0, 0, 0, 5) == ACCEPTED
        replay.advance_to(sim.truth().time + 2.0)
        assert ask(TAKEOFF, 0, 0, 0, 0, 0, 0, 5) == retry
        replay.advance_to(sim.truth().time + 3.0)
        assert sim.truth().altitude > 0.5
        assert ask(TAKEOFF, 0, 0, 0, 0, 0, 0, 5) == FAILED
    finally:
        gs.close()
        sim.stop()


# -- the stock Solo ----------------------------------------------------------------------------------------
def test_solo_speaks_mavlink1_only_and_lacks_the_newer_commands(make_sim, connect):
    sim = make_sim(profile="solo")              # SimConfig.mavlink2 stays True: the profile decides
    gs = connect(sim, mav1=True)
    assert gs.wait("HEARTBEAT")
    mark = gs.mark()
    gs.send(gs.encoder.command_long_encode(1, 1, mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 0, 2, 0, 0),
            mav1=False)
    assert gs.command(mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1).result == ACCEPTED
    assert [m.command for m in gs.messages("COMMAND_ACK", mark)] == [mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES]
    version = gs.wait("AUTOPILOT_VERSION", since=mark)
    assert not version.capabilities & mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2
    assert version.flight_sw_version >> 16 == 0x0303                         # ArduCopter 3.3
    for command, *params in ((mavlink.MAV_CMD_DO_SET_MODE, 1, MODES["LOITER"]),
                             (mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_HOME_POSITION),
                             (mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE, 1e5),
                             (mavlink.MAV_CMD_GET_MESSAGE_INTERVAL, mavlink.MAVLINK_MSG_ID_ATTITUDE)):
        assert gs.command(command, *params).result == UNSUPPORTED, command
    assert sim.truth().mode == "STABILIZE"
    set_mode(gs, "LOITER")                                     # SET_MODE works, no ACK: the HEARTBEAT says it
    assert not [m for m in gs.messages("COMMAND_ACK", mark) if m.command == mavlink.MAV_CMD_DO_SET_MODE
                and m.result == ACCEPTED]
    assert {v for _, v in gs.frames} == {1}


def test_solo_refuses_to_arm_with_3dr_texts_before_the_ack():
    """3.3 sent "PreArm: ..." at once (severity 3, its SEVERITY_HIGH) and the ACK after; GET_HOME_POSITION
    is FAILED until home exists."""
    sim = SimVehicle(SimConfig(**dict(FAST, profile="solo", ready_after=600.0))).start()
    gs = GroundStation(sim.tcp_port, mav1=True)
    try:
        assert gs.wait("HEARTBEAT")
        assert gs.command(mavlink.MAV_CMD_GET_HOME_POSITION).result == FAILED
        set_mode(gs, "GUIDED")
        mark = gs.mark()
        assert gs.command(ARM, 1).result == FAILED
        said = [m for m in gs.messages(since=mark) if m.get_type() in ("STATUSTEXT", "COMMAND_ACK")]
        assert said[0].get_type() == "STATUSTEXT" and said[0].text.startswith("PreArm: ")
        assert said[0].severity == 3 and said[-1].get_type() == "COMMAND_ACK"
    finally:
        gs.close()
        sim.stop()


def test_solo_never_sends_home_or_extended_sys_state_unasked(make_sim, connect):
    sim = make_sim(profile="solo")
    gs = connect(sim, mav1=True)
    gs.request_streams(10)
    take_off(sim, gs)
    mark = gs.mark()
    assert gs.command(mavlink.MAV_CMD_GET_HOME_POSITION).result == ACCEPTED
    assert gs.wait("HOME_POSITION", since=mark)
    kinds = [m.get_type() for m in gs.messages()]
    assert kinds.count("HOME_POSITION") == 1                  # only the answer; nothing at origin set or arming
    assert "EXTENDED_SYS_STATE" not in kinds and "GPS_GLOBAL_ORIGIN" not in kinds


@pytest.mark.parametrize("profile", ["copter-4", "solo"])
def test_velocity_setpoints_yaw_and_frames_by_firmware(profile, make_sim, connect):
    """3.3 reads neither the yaw rate nor the frame of SET_POSITION_TARGET_LOCAL_NED (3DR's GCS_Mavlink.pde:
    "for future use"): body-frame forward flies north, a yaw rate turns nothing. 4.x does both."""
    sim = make_sim(profile=profile)
    gs = connect(sim, mav1=profile == "solo")
    take_off(sim, gs)
    gs.setpoint(mavlink.MAV_FRAME_LOCAL_NED, 3527)                            # a first movement command
    assert gs.command(mavlink.MAV_CMD_CONDITION_YAW, 90, 45, 1, 0).result == ACCEPTED
    assert wait_until(lambda: angle_deg(sim.truth().yaw, math.pi / 2) < 2, 20), sim.truth()
    before = sim.truth()
    hold(gs, sim, 2.0, lambda: gs.setpoint(mavlink.MAV_FRAME_BODY_OFFSET_NED, 1479, yaw_rate=0.5))
    turned = angle_deg(sim.truth().yaw, before.yaw)
    assert (turned < 2) if profile == "solo" else (turned > 30), turned
    gs.setpoint(mavlink.MAV_FRAME_BODY_OFFSET_NED, 1479)
    assert gs.command(mavlink.MAV_CMD_CONDITION_YAW, 90, 45, 1, 0).result == ACCEPTED
    assert wait_until(lambda: angle_deg(sim.truth().yaw, math.pi / 2) < 2 and sim.truth().ground_speed < 0.05, 20)
    before = sim.truth()
    hold(gs, sim, 3.0, lambda: gs.setpoint(mavlink.MAV_FRAME_BODY_OFFSET_NED, 3527, vx=2.0))
    dn, de = sim.truth().north - before.north, sim.truth().east - before.east
    heading = math.atan2(de, dn)
    assert math.hypot(dn, de) > 3.0
    assert angle_deg(heading, 0.0 if profile == "solo" else math.pi / 2) < 10, (dn, de)


# -- other systems on the link ---------------------------------------------------------------------------------
def test_a_solo_gimbal_speaks_mavlink2_beside_a_mavlink1_autopilot(make_sim, connect):
    sim = make_sim(profile="solo", gimbal=True, companion=True)
    gs = connect(sim, mav1=True)
    assert wait_until(lambda: {m.get_srcComponent() for m in gs.messages("HEARTBEAT")} >= {1, 154, 191}, 10)
    beats = {}
    for msg, version in gs.frames:
        if msg.get_type() == "HEARTBEAT":
            beats.setdefault(msg.get_srcComponent(), set()).add((msg.get_srcSystem(), version, msg.type,
                                                                  msg.autopilot))
    assert beats[1] == {(1, 1, mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA)}
    assert beats[154] == {(1, 2, mavlink.MAV_TYPE_GIMBAL, mavlink.MAV_AUTOPILOT_INVALID)}
    assert beats[191] == {(1, 1, mavlink.MAV_TYPE_ONBOARD_CONTROLLER, mavlink.MAV_AUTOPILOT_INVALID)}
    gimbal = [m.get_seq() for m, _ in gs.frames if m.get_srcComponent() == 154]
    assert all((b - a) % 256 == 1 for a, b in zip(gimbal, gimbal[1:]))        # its own sequence numbers
    # a command for the gimbal is not the autopilot's to answer
    mark = gs.mark()
    gs.send(gs.encoder.command_long_encode(1, 154, mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 0, 2, 0, 0))
    assert gs.command(mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1).result == ACCEPTED
    assert [m.command for m in gs.messages("COMMAND_ACK", mark)] == [mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES]


def test_a_second_ground_station_sees_acks_addressed_to_someone_else(make_sim, connect):
    sim = make_sim(companion=True)
    mine = connect(sim)                                               # 255/190
    assert wait_until(lambda: sim.truth().ready, 10)
    with OtherGroundStation(f"tcp:127.0.0.1:{sim.tcp_port}", component=195) as other:
        assert other.wait("HEARTBEAT")
        assert wait_until(lambda: any(kind == "HEARTBEAT" for _, kind, _ in sim.received_messages))
        mark = mine.mark()
        ack = other.set_mode(MODES["LOITER"])
        assert ack.result == ACCEPTED and (ack.target_system, ack.target_component) == (255, 195)
        seen = mine.wait(lambda m: m.get_type() == "COMMAND_ACK" and m.command == mavlink.MAV_CMD_DO_SET_MODE,
                         since=mark)
        assert (seen.target_system, seen.target_component) == (255, 195)      # on the link, but not mine
        assert sim.truth().mode == "LOITER"
        mark = other.mark()
        mine_ack = mine.command(mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1)
        assert (mine_ack.target_system, mine_ack.target_component) == (255, 190)
        theirs = other.wait(lambda m: m.get_type() == "COMMAND_ACK" and not other.addressed(m), since=mark)
        assert theirs is not None and theirs.target_component == 190
        assert other.wait(lambda m: m.get_type() == "HEARTBEAT" and m.get_srcComponent() == 191)
