"""The command core on a real, lossy, shared link (issue 9 §1): each defect flown against the simulated
vehicle, checking what the vehicle did, not only what the driver said."""
from __future__ import annotations

import socket
import threading

import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.vehicle.state import CommandStatus

SOLO = dict(profile="solo", mavlink2=False)


def frame(build, system: int = 1, component: int = 1, v1: bool = False) -> bytes:
    """A MAVLink frame from (system, component), as another party on the link would send it."""
    enc = mavlink.MAVLink(None, srcSystem=system, srcComponent=component)
    return build(enc).pack(enc, force_mavlink1=v1)


def ack(command: int, result: int, to_system: int = 255, to_component: int = 190, **src) -> bytes:
    return frame(lambda e: e.command_ack_encode(command, result, 0, 0, to_system, to_component), **src)


def sent_commands(path: str, command: int) -> int:
    """How many COMMAND_LONG ``command`` the driver really put on the wire (its flight log says)."""
    log = mavutil.mavlink_connection(path)
    n = 0
    while (m := log.recv_match(type="COMMAND_LONG")) is not None:
        n += m.get_srcSystem() == 255 and m.command == command
    return n


def ready(vehicle):
    assert vehicle.wait_for(lambda s: s.connected and s.readiness.ready_to_arm, 30), vehicle.state()


def calibration_lost_once(vehicle, sim):
    """A level calibration whose first COMMAND_LONG the vehicle never heard (it hears no retry either)."""
    ready(vehicle)
    sim.faults.ignore_commands = {mavlink.MAV_CMD_PREFLIGHT_CALIBRATION}
    future = vehicle.calibrate_level()
    assert vehicle.wait_for(lambda s: mavlink.MAV_CMD_PREFLIGHT_CALIBRATION in sim.faults.ignored, 10)
    return future


# -- replies settle only what they answer ------------------------------------------------------------------
def test_a_late_ack_never_confirms_a_mode_change_the_vehicle_did_not_make(vehicle, sim):
    """The LOITER packet is lost; a late ACCEPTED for an earlier DO_SET_MODE arrives: only the heartbeat
    showing LOITER may confirm it, and the driver keeps trying until it does."""
    ready(vehicle)
    sim.faults.ignore_commands = {mavlink.MAV_CMD_DO_SET_MODE}
    modes_when_settled = []
    future = vehicle.set_mode("LOITER")
    future.add_done_callback(lambda f: modes_when_settled.append(sim.truth().mode))
    assert vehicle.wait_for(lambda s: mavlink.MAV_CMD_DO_SET_MODE in sim.faults.ignored, 10)
    sim.inject(ack(mavlink.MAV_CMD_DO_SET_MODE, mavlink.MAV_RESULT_ACCEPTED))      # the earlier switch's
    result = future.result(timeout=30)
    assert result.status is CommandStatus.ACCEPTED, str(result)
    assert modes_when_settled == ["LOITER"]                # confirmed only once the vehicle was in LOITER


def test_an_answer_to_another_ground_station_or_component_settles_nothing(vehicle, sim):
    ready(vehicle)
    sim.faults.ignore_commands = {mavlink.MAV_CMD_COMPONENT_ARM_DISARM}
    future = vehicle.arm()
    assert vehicle.wait_for(lambda s: mavlink.MAV_CMD_COMPONENT_ARM_DISARM in sim.faults.ignored, 10)
    # a second ground station (system 255, component 191) is answered; a gimbal answers us
    sim.inject(ack(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, mavlink.MAV_RESULT_ACCEPTED, to_component=191))
    sim.inject(ack(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, mavlink.MAV_RESULT_ACCEPTED, component=154))
    result = future.result(timeout=30)
    assert result.status is CommandStatus.TIMED_OUT, str(result)
    assert not sim.truth().armed and not vehicle.state().armed


def test_an_ack_before_the_command_went_out_settles_nothing(vehicle, sim):
    """Replies are matched to commands really sent: an ACK already on its way when the command is queued
    answers someone else."""
    ready(vehicle)
    sim.faults.ignore_commands = {mavlink.MAV_CMD_PREFLIGHT_CALIBRATION}
    with vehicle._store.lock:          # hold the ticker back: the command is queued, not yet sent
        future = vehicle.calibrate_level()
        vehicle.ingest(ack(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, mavlink.MAV_RESULT_ACCEPTED))
    result = future.result(timeout=30)
    assert result.status is CommandStatus.TIMED_OUT and result.attempts == 3, str(result)


def test_in_progress_waits_for_the_final_answer_and_never_resends(vehicle, sim):
    command = mavlink.MAV_CMD_PREFLIGHT_CALIBRATION
    future = calibration_lost_once(vehicle, sim)
    sim.inject(ack(command, mavlink.MAV_RESULT_IN_PROGRESS))
    # four of the driver's heartbeats (4 s) are more than three command timeouts (1 s each in tests)
    heartbeats = lambda: sum(1 for m in list(sim.received_messages) if m[1] == "HEARTBEAT")  # noqa: E731
    start = heartbeats()
    assert vehicle.wait_for(lambda s: heartbeats() >= start + 4, 20)
    assert list(sim.faults.ignored).count(command) == 1, "a command in progress was sent again"
    assert not future.done()
    sim.inject(ack(command, mavlink.MAV_RESULT_ACCEPTED))
    assert future.result(timeout=10).status is CommandStatus.ACCEPTED


# -- old firmware -----------------------------------------------------------------------------------------
def test_the_solo_sets_modes_with_set_mode_remembered_and_resent_until_its_heartbeat_shows_them(
        sim_factory, vehicle_factory, tmp_path):
    sim = sim_factory(**SOLO)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", tlog_path=str(tmp_path / "solo.tlog"))
    ready(vehicle)
    first = vehicle.set_mode("GUIDED").result(timeout=20)
    assert first.ok and sim.truth().mode == "GUIDED", str(first)
    assert any("DO_SET_MODE" in m.text for m in vehicle.state().messages)     # the pilot is told why
    # the next switch goes straight to SET_MODE, and one lost on the way is sent again
    sim.faults.uplink.loss = 1.0
    lost = sim.faults.counters.uplink.lost
    future = vehicle.set_mode("LOITER")
    assert vehicle.wait_for(lambda s: sim.faults.counters.uplink.lost > lost + 2, 10)
    sim.faults.uplink.loss = 0.0
    result = future.result(timeout=20)
    assert result.ok and sim.truth().mode == "LOITER", str(result)
    vehicle.close()
    assert sent_commands(str(tmp_path / "solo.tlog"), mavlink.MAV_CMD_DO_SET_MODE) == 1


def test_the_solo_flies_end_to_end_with_a_mavlink2_gimbal_on_its_link(sim_factory, vehicle_factory):
    """A MAVLink-2 gimbal must not switch the ground station to MAVLink 2: the autopilot would drop every
    command. Without EXTENDED_SYS_STATE, on the ground and in the air come from the heartbeat; home comes
    only from MAV_CMD_GET_HOME_POSITION."""
    sim = sim_factory(gimbal=True, **SOLO)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    ready(vehicle)
    assert vehicle.wait_for(lambda s: s.home is not None, 20), "no home from GET_HOME_POSITION"
    assert vehicle.state().in_air is False
    result = vehicle.takeoff(2.0).result(timeout=60)
    assert result.ok, str(result)
    s = vehicle.state()
    assert s.link.mavlink_version == 1 and sim.server.ignored_v2 == 0
    assert s.in_air is True and s.flying and 1.7 < -sim.truth().down
    assert vehicle.land().result(timeout=20).ok
    assert vehicle.wait_for(lambda s: not s.armed and s.in_air is False, 60)
    assert not sim.truth().armed and sim.truth().mode == "LAND"


def test_on_the_pad_without_extended_sys_state_a_drifting_barometer_is_not_flight():
    from driver.vehicle.state import MAV_STATE_ACTIVE, MAV_STATE_STANDBY, VehicleState
    pad = VehicleState(armed=True, altitude=0.6, system_status=MAV_STATE_STANDBY)
    assert pad.in_air is False and not pad.flying
    assert VehicleState(armed=True, altitude=0.0, system_status=MAV_STATE_ACTIVE).in_air is True
    unknown = VehicleState(armed=True, altitude=0.0, system_status=None)
    assert unknown.in_air is None and unknown.flying          # unknown while armed: treated as flying


# -- takeoff judged by the vehicle --------------------------------------------------------------------------
@pytest.mark.parametrize("profile", ["copter-4", "solo"])
def test_a_takeoff_whose_reply_was_lost_is_judged_by_the_climb(sim_factory, vehicle_factory, profile):
    """The vehicle takes off but the ACK is lost; the retry is answered ACCEPTED (ArduCopter 4.7) or refused
    ("can't takeoff again" on the Solo): the takeoff succeeds either way, and never reports FAILED."""
    sim = sim_factory(profile=profile, mavlink2=profile != "solo")
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    ready(vehicle)
    sim.faults.lose_replies = {mavlink.MAV_CMD_NAV_TAKEOFF}
    future = vehicle.takeoff(3.0)
    assert vehicle.wait_for(lambda s: mavlink.MAV_CMD_NAV_TAKEOFF in sim.faults.replies_lost, 30)
    sim.faults.lose_replies = set()                       # the retry's answer arrives
    result = future.result(timeout=60)
    assert result.status is CommandStatus.ACCEPTED, str(result)
    answers = [r for r in vehicle.state().results if r.command.startswith("NAV_TAKEOFF")]
    assert answers and answers[-1].attempts >= 2, answers
    assert 2.7 < -sim.truth().down


def test_the_climb_timeout_grows_with_the_altitude():
    from driver.vehicle.sequences.takeoff import climb_timeout
    assert climb_timeout(20.0, 100.0) > climb_timeout(20.0, 3.0) + 150.0


# -- hover is streamed ----------------------------------------------------------------------------------------
def zero_setpoints(sim, after: float) -> int:
    return sum(1 for t, *_, vx, vy, vz, rate in list(sim.received_setpoints)
               if t > after and vx == vy == vz == rate == 0.0)


def test_stop_streams_zeros_for_guided_timeout_not_three_packets(flying, sim):
    assert flying.set_velocity(1.5, 0, 0, 0)
    assert flying.wait_for(lambda s: any(sp[3] > 1.0 for sp in list(sim.received_setpoints)), 10)
    t0 = sim.truth().time
    assert flying.stop().result(timeout=5).ok
    # 3 s at 20 Hz is about 60 zeros; a burst of loss may eat three, never twenty
    assert flying.wait_for(lambda s: zero_setpoints(sim, t0) >= 20, 15), zero_setpoints(sim, t0)


def test_the_deadman_streams_zeros_too(flying, sim):
    t0 = sim.truth().time
    assert flying.set_velocity(1.0, 0, 0, 0)               # then the pilot's stream stalls
    assert flying.wait_for(lambda s: zero_setpoints(sim, t0) >= 20, 15), zero_setpoints(sim, t0)
    assert flying.state().setpoint.is_zero


# -- ground-only commands are checked as they go out ----------------------------------------------------------
def test_a_ground_only_command_is_not_resent_once_the_vehicle_is_armed(vehicle, sim):
    command = mavlink.MAV_CMD_PREFLIGHT_CALIBRATION
    future = calibration_lost_once(vehicle, sim)
    assert vehicle.set_mode("GUIDED").result(timeout=10).ok
    assert vehicle.arm().result(timeout=10).ok and vehicle.wait_for(lambda s: s.armed, 10)
    result = future.result(timeout=10)
    assert result.status is CommandStatus.REJECTED and "armed" in result.reason, str(result)
    assert list(sim.faults.ignored).count(command) == 1
    assert vehicle.disarm().result(timeout=10).ok


def test_forced_disarm_is_refused_in_the_air(flying, sim):
    result = flying.disarm(force=True).result(timeout=5)
    assert result.status is CommandStatus.REJECTED, str(result)
    assert sim.truth().armed and -sim.truth().down > 2.0


# -- the link's writes ---------------------------------------------------------------------------------------------
def test_a_blocked_link_write_stalls_neither_the_reader_nor_the_sticks(flying, sim):
    """A write that blocks (a 57600-baud radio) happens outside the state lock."""
    entered, release = threading.Event(), threading.Event()
    transport = flying._transport
    write = transport.write

    def slow_write(data):
        if not release.is_set():
            entered.set()
            release.wait(20)
        return write(data)

    transport.write = slow_write
    try:
        assert flying.set_velocity(0.5, 0, 0, 0)
        assert entered.wait(10)                           # the ticker is stuck in a write
        count = flying.state().link.packets_received
        done = threading.Event()
        worker = threading.Thread(target=lambda: (flying.set_velocity(0.0, 0.5, 0, 0), done.set()), daemon=True)
        worker.start()
        assert done.wait(10), "set_velocity waited for the link"
        assert flying.wait_for(lambda s: s.link.packets_received > count + 10, 10), "the reader stalled"
    finally:
        release.set()
        transport.write = write


def test_tcp_writes_never_leave_half_a_frame_on_the_wire():
    from driver.link.transport import MavutilTransport
    server = socket.socket()
    server.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)     # a peer that barely reads
    server.bind(("127.0.0.1", 0))
    server.listen(1)
    transport = MavutilTransport(f"tcp:127.0.0.1:{server.getsockname()[1]}")
    transport.open()
    peer, _ = server.accept()
    enc = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
    accepted = 0
    try:
        transport._sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)
        offered = 0
        while offered - accepted < 10 and offered < 100000:    # until the link has dropped frames
            msg = enc.statustext_encode(6, f"frame {offered:05d} ".ljust(50, "x").encode())
            accepted += transport.write(msg.pack(enc))
            offered += 1
        assert accepted < offered                         # the peer stopped reading: some were dropped...
        transport.write(frame(lambda e: e.heartbeat_encode(6, 8, 0, 0, 4, 3), 255, 190))
        data = bytearray()
        peer.settimeout(2.0)
        while True:
            try:
                chunk = peer.recv(1 << 20)
            except socket.timeout:
                break
            if not chunk:
                break
            data += chunk
            transport.write(b"")                          # let the held-back tail go out
    finally:
        transport.close()
        peer.close()
        server.close()
    parser = mavlink.MAVLink(None)
    parser.robust_parsing = True
    msgs = parser.parse_buffer(bytes(data)) or []
    assert not [m for m in msgs if m.get_type() == "BAD_DATA"], "a frame was cut"
    assert sum(m.get_type() == "STATUSTEXT" for m in msgs) >= accepted - 1   # ...whole, never in part


def test_the_flight_log_reaches_the_disk_within_a_second(vehicle_factory, tmp_path):
    """A crash loses at most a second of the log: a quiet link's frames are on disk without closing it."""
    listener = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    listener.bind(("127.0.0.1", 0))
    port = listener.getsockname()[1]
    listener.close()
    path = tmp_path / "quiet.tlog"
    vehicle = vehicle_factory(f"udpin:127.0.0.1:{port}", tlog_path=str(path))
    out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        # sent again until the link, which the driver's own thread opens, is there to hear it
        def send_and_see() -> bool:
            out.sendto(frame(lambda e: e.heartbeat_encode(2, 3, 0, 4, 3, 3)), ("127.0.0.1", port))
            out.sendto(frame(lambda e: e.statustext_encode(6, b"flush marker")), ("127.0.0.1", port))
            return vehicle.wait_for(lambda s: any(m.text == "flush marker" for m in s.messages), 0.5) is not None
        assert any(send_and_see() for _ in range(20))
        assert vehicle.wait_for(lambda s: path.exists() and b"flush marker" in path.read_bytes(), 5)
    finally:
        out.close()


# -- what the vehicle is, read from the vehicle ------------------------------------------------------------------
def test_a_three_cell_pack_is_not_shown_low(sim_factory, vehicle_factory):
    sim = sim_factory(battery_cells=3)                    # ArduPilot SITL's pack: 12.6 V full
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    s = vehicle.wait_for(lambda s: s.battery.voltage is not None and s.battery.cells, 20)
    assert s is not None
    assert s.battery.cells == 3 and s.battery.cells_source == "inferred"
    assert not s.battery.low and 4.0 < s.battery.cell_voltage < 4.25, s.battery


@pytest.mark.parametrize("enabled", [0, 1])
def test_the_pilot_is_warned_when_the_vehicle_has_no_gcs_failsafe(sim_factory, vehicle_factory, enabled):
    sim = sim_factory()
    sim.autopilot.params["FS_GCS_ENABLE"] = enabled
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    s = vehicle.wait_for(lambda s: s.gcs_failsafe is not None, 20)
    assert s is not None and s.gcs_failsafe == enabled
    warned = any("FS_GCS_ENABLE=0" in m.text for m in s.messages)
    assert warned is (enabled == 0)


def test_go_to_flies_to_metres_from_home_although_the_ekf_origin_is_elsewhere(flying, sim):
    assert sim.config.origin_offset != (0.0, 0.0, 0.0)
    assert flying.go_to(6.0, -4.0, 5.0).result(timeout=5).ok
    assert flying.wait_for(lambda s: abs(sim.truth().north - 6.0) < 0.4 and abs(sim.truth().east + 4.0) < 0.4
                           and abs(-sim.truth().down - 5.0) < 0.4, 40), sim.truth()
    s = flying.wait_for(lambda s: s.local is not None and abs(s.local.north - 6.0) < 0.5, 10)
    assert s is not None and abs(s.altitude - 5.0) < 0.5, s.local


def test_the_solo_flies_the_sticks_along_its_nose(sim_factory, vehicle_factory):
    """Stock Solo firmware reads neither the frame nor the yaw rate of a velocity setpoint: the driver turns
    the stick to north/east itself and steers the nose with CONDITION_YAW, so forward is still forward."""
    import math
    sim = sim_factory(home=(40.2839, -3.7940, 664.0, 90.0), **SOLO)          # nose east
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    ready(vehicle)
    assert vehicle.wait_for(lambda s: s.firmware.startswith("3.3"), 20), vehicle.state().firmware
    assert vehicle.takeoff(3.0).result(timeout=60).ok
    start = sim.truth()
    end = start.time + 3.0
    while sim.truth().time < end:
        assert vehicle.set_velocity(2.0, 0.0, 0.0, 0.0)
        vehicle.wait_for(lambda s: sim.truth().time >= end, 0.1)
    moved = sim.truth()
    dn, de = moved.north - start.north, moved.east - start.east
    assert math.hypot(dn, de) > 2.0 and abs(math.degrees(math.atan2(de, dn)) - 90.0) < 15.0, (dn, de)
    assert abs(math.degrees(moved.yaw) - 90.0) < 10.0            # the nose held east
    vehicle.stop()
    end = sim.truth().time + 3.0
    while sim.truth().time < end:                                # yaw stick right at 0.5 rad/s
        assert vehicle.set_velocity(0.0, 0.0, 0.0, 0.5)
        vehicle.wait_for(lambda s: sim.truth().time >= end, 0.1)
    turned = math.degrees(sim.truth().yaw - moved.yaw) % 360.0
    assert 45.0 < turned < 120.0, turned                         # 3 s at ~29°/s, clockwise


def test_a_takeoff_asks_again_when_arming_got_no_answer_at_all(vehicle, sim):
    """On a bad link all three ARMs can be lost: no answer is not a refusal, so the sequence asks again
    (a refusal still ends it, see test_driver_flight.py::test_takeoff_reports_a_refusal)."""
    ready(vehicle)
    arm = mavlink.MAV_CMD_COMPONENT_ARM_DISARM
    sim.faults.ignore_commands = {arm}
    future = vehicle.takeoff(2.0)
    assert vehicle.wait_for(lambda s: list(sim.faults.ignored).count(arm) >= 3, 30)
    sim.faults.ignore_commands = set()                       # the link gets better
    result = future.result(timeout=60)
    assert result.ok, str(result)
    timed_out = [r for r in vehicle.state().results if r.command == "arm" and r.status is CommandStatus.TIMED_OUT]
    assert timed_out and sim.truth().armed and -sim.truth().down > 1.5
