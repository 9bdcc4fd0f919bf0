"""Link robustness, wire safety, protocol versions, telemetry log and forwarding."""
from __future__ import annotations

import math
import os
import random
import socket
import subprocess
import sys

import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.core import frames
from driver.sim.autopilot import DEFAULT_PARAMS
from driver.vehicle.state import CommandStatus, LinkStatus
from driver.vehicle import VehicleConfig


def test_telemetry_fills_the_state(vehicle, sim):
    s = vehicle.wait_for(lambda s: s.position is not None and s.home is not None and s.local is not None
                         and s.battery.voltage and s.gps.fix_type >= 3 and s.readiness.ready_to_arm
                         and s.environment.pressure_hpa and s.environment.mag and s.link.packets_per_s > 0, 15)
    assert s is not None, vehicle.state()
    assert s.mode == sim.truth().mode and s.system_id == 1
    assert abs(s.home.lat - 40.2839) < 1e-4 and abs(s.home.lon + 3.7940) < 1e-4
    assert abs(s.local.north) < 0.5 and abs(s.local.east) < 0.5
    assert 14.0 < s.battery.voltage < 17.0 and 0 < s.battery.remaining <= 100
    w, x, y, z = s.attitude.quaternion
    assert abs(w * w + x * x + y * y + z * z - 1) < 1e-6
    assert s.link.packets_per_s > 0 and s.link.heartbeat_age is not None and s.link.status is LinkStatus.OK


def test_garbage_and_corrupt_frames_never_stop_the_reader(vehicle, sim):
    assert vehicle.wait_for(lambda s: s.attitude.roll != 0 or s.position is not None, 10)
    rnd = random.Random(7)
    for _ in range(50):
        sim.inject(bytes(rnd.getrandbits(8) for _ in range(2000)))
        sim.inject(b"\xfe\x09" + bytes(rnd.getrandbits(8) for _ in range(40)))   # frame-shaped, bad CRC
    sim.faults.corrupt_fraction = 0.3
    count = vehicle.state().link.packets_received
    assert vehicle.wait_for(lambda s: s.link.bad_crc > 5 and s.link.packets_received > count + 50, 15), \
        vehicle.state().link
    sim.faults.corrupt_fraction = 0.0
    assert vehicle.arm().result(timeout=10).ok      # still commanding the vehicle
    assert vehicle.state().connected



@pytest.mark.parametrize("cut", ["one frame per read", "two frames per read", "7 bytes per read", "with garbage"])
def test_every_way_a_link_cuts_the_bytes_gives_the_frames_pymavlink_gives(cut):
    """ingest() takes a shortcut past parse_buffer() for one-frame reads: it must not lose or invent a frame."""
    from driver.link.transport import frame_length
    from driver.vehicle import Vehicle, VehicleConfig
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    frames_ = [mavlink.MAVLink_heartbeat_message(2, 3, 217, 4, 4, 3).pack(mav)]
    for i in range(40):
        mav.seq = (mav.seq + 1) % 256
        frames_.append(mavlink.MAVLink_attitude_message(i, 0.01 * i, 0, 0, 0, 0, 0).pack(mav))
    data = b"".join(frames_)
    if cut == "one frame per read":
        reads = frames_
    elif cut == "two frames per read":
        reads = [b"".join(frames_[i:i + 2]) for i in range(0, len(frames_), 2)]
    elif cut == "7 bytes per read":
        reads = [data[i:i + 7] for i in range(0, len(data), 7)]
    else:
        reads = [f + b"\x00\x01garbage" if i % 3 == 0 else f for i, f in enumerate(frames_)]
    assert sum(frame_length(f, 0) for f in frames_) == len(data)
    codec = mavlink.MAVLink(None)
    codec.robust_parsing = True
    expected = [m.get_type() for r in reads for m in codec.parse_buffer(r) or ()]
    vehicle = Vehicle(VehicleConfig(connection="udpin:127.0.0.1:0"))   # not started: only the parser runs
    got = sum(vehicle.ingest(r) for r in reads)
    assert got == len(frames_) == expected.count("ATTITUDE") + expected.count("HEARTBEAT")
    assert vehicle.state().mode == "GUIDED"                             # the heartbeat was folded in

def test_dropped_packets_show_as_loss(vehicle, sim):
    sim.faults.drop_fraction = 0.3
    assert vehicle.wait_for(lambda s: s.link.loss_percent > 10 and s.link.packets_lost > 10, 15), \
        vehicle.state().link


def test_nan_inf_and_huge_velocities_never_reach_the_wire(flying, sim):
    lim = flying.limits
    for bad in ((math.nan, 0, 0, 0), (0, math.inf, 0, 0), (0, 0, -math.inf, 0), (0, 0, 0, math.nan)):
        assert flying.set_velocity(*bad) is False
    assert flying.set_velocity(100.0, -100.0, 50.0, 10.0) is True
    assert flying.wait_for(lambda s: not s.setpoint.is_zero, 2)
    sp = flying.state().setpoint
    assert (sp.forward, sp.right, sp.up, sp.yaw_rate) == (lim.horizontal, -lim.horizontal, lim.vertical, lim.yaw_rate)
    end = sim.truth().time + 1.0
    while sim.truth().time < end:
        flying.set_velocity(100.0, -100.0, 50.0, 10.0)
        flying.set_velocity(math.nan, 1, 1, 1)
        flying.wait_for(lambda s: sim.truth().time >= end, 0.05)
    received = list(sim.received_setpoints)
    assert received
    for _, frame, mask, vx, vy, vz, yaw_rate in received:
        assert all(math.isfinite(v) for v in (vx, vy, vz, yaw_rate))
        assert abs(vx) <= lim.horizontal + 1e-6 and abs(vy) <= lim.horizontal + 1e-6
        assert abs(vz) <= lim.vertical + 1e-6 and abs(yaw_rate) <= lim.yaw_rate + 1e-6
    assert any(abs(r[3] - lim.horizontal) < 1e-6 for r in received)


def test_deadman_zeroes_a_stalled_stream(sim_factory, vehicle_factory):
    """The driver falls to zero before the autopilot's own 3 s guided timeout would stop the vehicle. The sim runs
    at the suite's speed-up and the driver's deadman is shortened by the same factor, so the two timeouts compare
    in vehicle time as they would at 1× (where the flight took 9 s)."""
    guided_timeout = DEFAULT_PARAMS["GUID_TIMEOUT"][0]                # ArduCopter's own failsafe, 3 s
    assert VehicleConfig().deadman < guided_timeout
    sim = sim_factory()
    speedup = sim.config.speedup
    flying = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", deadman=VehicleConfig().deadman / speedup)
    assert flying.takeoff(3.0).result(timeout=60).ok
    assert flying.set_velocity(1.5, 0, 0, 0)
    assert flying.wait_for(lambda s: not s.setpoint.is_zero, 2)
    assert flying.wait_for(lambda s: s.setpoint.is_zero, 5), "deadman did not zero the setpoint"
    received = list(sim.received_setpoints)
    moving = [i for i, r in enumerate(received) if abs(r[3] - 1.5) < 1e-6]
    assert moving, received[-5:]
    assert flying.wait_for(lambda s: any(r[3] == 0.0 and r[4] == 0.0 for r in list(sim.received_setpoints)[moving[-1]:]), 5)
    received = list(sim.received_setpoints)
    last_moving = max(r[0] for r in received if abs(r[3] - 1.5) < 1e-6)
    first_zero = min(r[0] for r in received if r[0] > last_moving and r[3] == 0.0)
    assert first_zero - last_moving < guided_timeout, (first_zero, last_moving)
    assert flying.wait_for(lambda s: math.hypot(sim.truth().vn, sim.truth().ve) < 0.2, 20)


def test_solo_style_mavlink1_vehicle(sim_factory, vehicle_factory):
    sim = sim_factory(mavlink2=False)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.readiness.ready_to_arm, 15)
    assert vehicle.arm().result(timeout=10).ok
    assert vehicle.state().link.mavlink_version == 1
    assert {v for _, _, v in list(sim.received_messages)} == {1}


def test_follows_a_mavlink2_vehicle_from_mavlink1(vehicle, sim):
    first = list(sim.received_messages)[0]
    assert first[2] == 1                               # we start on MAVLink 1
    assert vehicle.wait_for(lambda s: s.link.mavlink_version == 2, 5)
    assert vehicle.wait_for(lambda s: s.readiness.ready_to_arm, 15)
    since = sim.truth().time
    assert vehicle.set_mode("LOITER").result(timeout=10).ok
    assert sim.truth().mode == "LOITER"
    # the command went out in MAVLink 2 (heartbeats already on their way may still be MAVLink 1)
    commands = [version for t, kind, version in list(sim.received_messages) if t >= since and kind == "COMMAND_LONG"]
    assert commands and set(commands) == {2}, commands


def test_tlog_reads_back_with_pymavlink_and_replays(flying, sim, vehicle_factory, tmp_path):
    flying.land().result(timeout=10)
    assert flying.wait_for(lambda s: not s.armed, 60)
    path = flying.config.tlog_path
    flying.close()
    log = mavutil.mavlink_connection(path)
    types, stamps, ours = {}, [], []
    while (m := log.recv_match()) is not None:
        types[m.get_type()] = types.get(m.get_type(), 0) + 1
        stamps.append(m._timestamp)
        if m.get_srcSystem() == 255 and m.get_type() == "COMMAND_LONG":
            ours.append((m.command, round(m.param2)))
    assert "BAD_DATA" not in types, types
    assert stamps == sorted(stamps)
    assert types.get("HEARTBEAT", 0) > 5 and types.get("ATTITUDE", 0) > 5 and types.get("COMMAND_ACK", 0) > 2
    # both ways: the flight's own commands as they went out (takeoff, then LAND), not only what came in
    assert (mavlink.MAV_CMD_NAV_TAKEOFF, 0) in ours and (mavlink.MAV_CMD_DO_SET_MODE, 9) in ours, ours
    dump = subprocess.run([sys.executable, "-m", "pymavlink.tools.mavlogdump", "--types", "HEARTBEAT", path],
                          capture_output=True, text=True, timeout=60)
    assert dump.returncode == 0 and dump.stdout.count("HEARTBEAT") > 5

    replay = vehicle_factory(path, tlog_path=None, replay_speed=4.0)   # the takeoff was flown at 16x (the fixture)
    assert replay.replay is not None and replay.replay.duration > 2
    assert replay.wait_for(lambda s: s.armed and s.altitude > 2.0, 30), replay.state()
    assert replay.wait_for(lambda s: not s.armed and s.mode == "LAND", 30)
    assert replay.takeoff().result(timeout=2).status is CommandStatus.REJECTED


def vehicle_frames_until(path: str, seconds: float, system: int = 1) -> int:
    """Frames of the vehicle in the first ``seconds`` of a .tlog (from its first heartbeat on), counted by pymavlink:
    what a replay paused there has delivered."""
    log = mavutil.mavlink_connection(path)
    start, count = None, 0
    while (m := log.recv_match()) is not None:
        start = m._timestamp if start is None else start
        if m._timestamp - start > seconds:
            break
        if m.get_srcSystem() == system and m.get_type() != "BAD_DATA" and (count or m.get_type() == "HEARTBEAT"):
            count += 1
    return count


def test_replay_pauses_and_resumes(flying, vehicle_factory):
    path = flying.config.tlog_path
    flying.close()
    replay = vehicle_factory(path, tlog_path=None, replay_speed=1.0)
    assert replay.wait_for(lambda s: s.connected, 10)
    replay.replay.pause()
    at = replay.replay.position
    # the state catches up with exactly what was recorded up to the pause, and not one frame more
    expected = vehicle_frames_until(path, at)
    s = replay.wait_for(lambda s: s.link.packets_received >= expected, 10)
    assert s is not None and s.link.packets_received == expected, (replay.state().link, expected)
    for _ in range(3):          # three link-health refreshes later, still there (nothing changes without one)
        s = replay.wait_for(lambda new, old=s: new is not old, 1) or replay.state()
        assert s.link.packets_received == expected, s.link
    assert replay.replay.paused and replay.replay.position == at
    assert s.connected                                          # a pause is not a lost link
    replay.replay.resume()
    assert replay.wait_for(lambda s: s.link.packets_received > expected, 5)


def test_forwarding_to_another_ground_station(sim, vehicle_factory):
    gcs = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    gcs.bind(("127.0.0.1", 0))
    gcs.settimeout(5)
    port = gcs.getsockname()[1]
    try:
        vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", outputs=(f"udp:127.0.0.1:{port}",))
        assert vehicle.wait_for(lambda s: s.connected, 10)
        codec = mavlink.MAVLink(None)
        codec.robust_parsing = True
        seen = set()
        while "HEARTBEAT" not in seen:
            data, addr = gcs.recvfrom(65536)
            seen |= {m.get_type() for m in codec.parse_buffer(data) or ()}
        # the other ground station commands the vehicle through us
        out = mavlink.MAVLink(None, srcSystem=254, srcComponent=190)
        cmd = mavlink.MAVLink_command_long_message(1, 1, mavlink.MAV_CMD_DO_SET_MODE, 0, 1, 5, 0, 0, 0, 0, 0)
        gcs.sendto(cmd.pack(out), addr)
        assert vehicle.wait_for(lambda s: s.mode == "LOITER", 10)
    finally:
        gcs.close()


def test_battery_estimate_from_cell_voltage():
    assert frames.battery_percent_from_cell(4.2) == 100
    assert frames.battery_percent_from_cell(3.81) == pytest.approx(17)
    assert frames.battery_percent_from_cell(3.955) == pytest.approx(17 + 83 * 0.5)
    assert frames.battery_percent_from_cell(3.505) == pytest.approx(8.5)
    assert frames.battery_percent_from_cell(3.0) == 0


def test_enu_pose_follows_jderobot_convention():
    for yaw_ned, yaw_enu in ((0, 90), (90, 0), (180, -90), (-90, 180)):
        w, x, y, z = frames.enu_quaternion(0.0, 0.0, math.radians(yaw_ned))
        got = math.degrees(math.atan2(2 * (x * y + w * z), w * w + x * x - y * y - z * z))
        assert abs(math.atan2(math.sin(math.radians(got - yaw_enu)), math.cos(math.radians(got - yaw_enu)))) < 1e-6


def test_forwarded_traffic_keeps_the_tlog_clean(sim, vehicle_factory, tmp_path):
    gcs = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    gcs.bind(("127.0.0.1", 0))
    gcs.settimeout(5)
    try:
        path = str(tmp_path / "forward.tlog")
        vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", tlog_path=path,
                                  outputs=(f"udp:127.0.0.1:{gcs.getsockname()[1]}",))
        assert vehicle.wait_for(lambda s: s.connected, 10)
        _, addr = gcs.recvfrom(65536)
        out = mavlink.MAVLink(None, srcSystem=254, srcComponent=190)
        beat = mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3)
        two = beat.pack(out) + beat.pack(out)
        gcs.sendto(two, addr)                                           # two frames in one datagram
        gcs.sendto(b"\xfe\x09garbage-not-a-frame" * 3, addr)           # and noise
        cmd = mavlink.MAVLink_command_long_message(1, 1, mavlink.MAV_CMD_DO_SET_MODE, 0, 1, 5, 0, 0, 0, 0, 0)
        gcs.sendto(cmd.pack(out), addr)
        assert vehicle.wait_for(lambda s: s.mode == "LOITER", 10)
        vehicle.close()
    finally:
        gcs.close()
    log = mavutil.mavlink_connection(path)
    seen = []
    while (m := log.recv_match()) is not None:
        seen.append((m.get_type(), m.get_srcSystem()))
    assert ("BAD_DATA", 254) not in seen and not any(t == "BAD_DATA" for t, _ in seen)
    assert seen.count(("HEARTBEAT", 254)) == 2


def test_a_failing_flight_log_stops_with_a_warning_and_flying_goes_on(sim, vehicle_factory):
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", tlog_path="/dev/full")   # every write: ENOSPC
    s = vehicle.wait_for(lambda s: any(m.text.startswith("Flight log stopped") for m in s.messages), 10)
    assert s is not None, [m.text for m in vehicle.state().messages]
    assert vehicle.wait_for(lambda s: s.readiness.ready_to_arm, 15)
    assert vehicle.arm().result(timeout=10).ok                           # commands, heartbeat, ticker alive
    count = vehicle.state().link.packets_received
    assert vehicle.wait_for(lambda s: s.link.packets_received > count + 10, 10)


def test_serial_link_over_a_pseudo_terminal(sim, vehicle_factory):
    """A serial device (a pty here) bridged to the simulated vehicle: the driver flies through it."""
    import pty
    import select
    import threading
    import tty
    master, slave = pty.openpty()
    tty.setraw(slave)
    device = os.ttyname(slave)
    vehicle_side = socket.create_connection(("127.0.0.1", sim.tcp_port))
    stop = threading.Event()

    def bridge():
        while not stop.is_set():
            ready, _, _ = select.select([master, vehicle_side], [], [], 0.1)
            try:
                if master in ready:
                    vehicle_side.sendall(os.read(master, 4096))
                if vehicle_side in ready:
                    os.write(master, vehicle_side.recv(4096))
            except OSError:
                return

    t = threading.Thread(target=bridge, daemon=True)
    t.start()
    try:
        vehicle = vehicle_factory(device, baud=115200)
        assert vehicle.wait_for(lambda s: s.connected and s.readiness.ready_to_arm, 15), vehicle.state().link
        assert vehicle.arm().result(timeout=10).ok
    finally:
        stop.set()
        t.join(2)
        vehicle_side.close()
        os.close(master)
        os.close(slave)


def test_a_link_that_cannot_open_says_why(vehicle_factory):
    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()                                                     # nothing listens there
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{port}")
    s = vehicle.wait_for(lambda s: any("cannot open" in m.text for m in s.messages), 10)
    assert s is not None and s.link.status is LinkStatus.WAITING


def test_the_flight_log_is_never_written_through_a_planted_symlink(tmp_path):
    """A shared log folder: another user's link at our log's name must not make us truncate its target."""
    from driver.link.tlog import TlogWriter
    victim = tmp_path / "victim"
    victim.write_bytes(b"someone else's file")
    (tmp_path / "mav.tlog").symlink_to(victim)
    for append in (False, True):
        with pytest.raises(OSError, match="cannot write the flight log"):
            TlogWriter(str(tmp_path / "mav.tlog"), append)
    assert victim.read_bytes() == b"someone else's file"
