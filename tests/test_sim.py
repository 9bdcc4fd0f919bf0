"""The simulated ArduCopter, spoken to over real sockets with nothing but a raw pymavlink codec."""
from __future__ import annotations

import math
import random
import socket
import threading
import time

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.sim import MODES, Autopilot, ManualClock, SimConfig, SimVehicle
from driver.sim.gcs import first_message

FAST = dict(tcp_port=0, speedup=10.0, ready_after=0.5, seed=7)
PREARM = mavlink.MAV_SYS_STATUS_PREARM_CHECK


class GroundStation:
    """A bare MAVLink peer on a TCP socket: records every frame that reached the wire."""

    def __init__(self, port: int, mav1: bool = False, system: int = 255, component: int = 190) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=5)
        self.sock.settimeout(0.05)
        self.encoder = mavlink.MAVLink(None, srcSystem=system, srcComponent=component)
        self.parser = mavlink.MAVLink(None, srcSystem=system, srcComponent=component)
        self.parser.robust_parsing = True
        self.mav1 = mav1
        self.frames: list[tuple[object, int]] = []      # (message, MAVLink version)
        self.bad = 0
        self.cond = threading.Condition()
        self.running = True
        self.thread = threading.Thread(target=self._read, daemon=True)
        self.thread.start()

    def _read(self) -> None:
        while self.running:
            try:
                data = self.sock.recv(65536)
            except socket.timeout:
                continue
            except OSError:
                return
            if not data:
                return
            for msg in self.parser.parse_buffer(data) or []:
                with self.cond:
                    if msg.get_type() == "BAD_DATA":
                        self.bad += 1
                        continue
                    self.frames.append((msg, 2 if msg.get_msgbuf()[0] == 0xFD else 1))
                    self.cond.notify_all()

    def close(self) -> None:
        self.running = False
        self.sock.close()
        self.thread.join(timeout=2)

    # -- sending -------------------------------------------------------------------------------------
    def send(self, msg, mav1: bool | None = None) -> None:
        data = msg.pack(self.encoder, force_mavlink1=self.mav1 if mav1 is None else mav1)
        self.encoder.seq = (self.encoder.seq + 1) % 256
        self.sock.sendall(data)

    def send_raw(self, data: bytes) -> None:
        self.sock.sendall(data)

    def command(self, command: int, *params: float, timeout: float = 5.0, mav1: bool | None = None):
        """COMMAND_LONG, then the COMMAND_ACK that names it (None if none came)."""
        p = list(params) + [0.0] * (7 - len(params))
        mark = self.mark()
        self.send(self.encoder.command_long_encode(1, 1, command, 0, *p), mav1)
        return self.wait(lambda m: m.get_type() == "COMMAND_ACK" and m.command == command, timeout, since=mark)

    def set_mode(self, name: str):
        return self.command(mavlink.MAV_CMD_DO_SET_MODE, 1, MODES[name])

    def request_streams(self, rate: int, stream: int = mavlink.MAV_DATA_STREAM_ALL, start: int = 1) -> None:
        self.send(self.encoder.request_data_stream_encode(1, 1, stream, rate, start))

    def setpoint(self, frame: int, mask: int, vx=0.0, vy=0.0, vz=0.0, yaw_rate=0.0, x=0.0, y=0.0, z=0.0):
        self.send(self.encoder.set_position_target_local_ned_encode(
            0, 1, 1, frame, mask, x, y, z, vx, vy, vz, 0, 0, 0, 0, yaw_rate))

    # -- receiving -----------------------------------------------------------------------------------
    def mark(self) -> int:
        with self.cond:
            return len(self.frames)

    def messages(self, kind: str | None = None, since: int = 0) -> list:
        with self.cond:
            return [m for m, _ in self.frames[since:] if kind is None or m.get_type() == kind]

    def stamped(self, since: int = 0) -> list[tuple[float, object]]:
        """(sim seconds, message): each frame dated by the latest time_boot_ms heard before it."""
        out, now = [], None
        for msg in self.messages(since=since):
            if hasattr(msg, "time_boot_ms"):
                now = msg.time_boot_ms / 1000.0
            if now is not None:
                out.append((now, msg))
        return out

    def wait(self, predicate, timeout: float = 5.0, since: int = 0):
        """The first message from index ``since`` on that satisfies ``predicate`` (a type name works)."""
        return first_message(self.cond, self.frames, predicate, timeout, since, message=lambda frame: frame[0])


def wait_until(condition, timeout: float = 10.0) -> bool:
    """Poll a condition with a deadline (the sim runs in its own thread)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.005)
    return bool(condition())


def sim_wait(sim: SimVehicle, seconds: float, timeout: float = 20.0) -> None:
    """Let ``seconds`` of simulated time pass."""
    end = sim.truth().time + seconds
    assert wait_until(lambda: sim.truth().time >= end, timeout), "the simulated clock stalled"


def hold(gs: GroundStation, sim: SimVehicle, seconds: float, send) -> None:
    """Re-send a setpoint every 0.25 s of sim time for ``seconds`` (a pilot holding a stick)."""
    end = sim.truth().time + seconds
    while sim.truth().time < end:
        send()
        step_end = min(end, sim.truth().time + 0.25)
        assert wait_until(lambda: sim.truth().time >= step_end, 10)


def angle_deg(a: float, b: float) -> float:
    return abs(math.degrees(math.atan2(math.sin(a - b), math.cos(a - b))))


def local_ned(sim: SimVehicle, north: float, east: float, down: float) -> dict:
    """A point NED from home as MAV_FRAME_LOCAL_NED wants it: from the EKF origin, which is not home."""
    on, oe, od = sim.config.origin_offset
    return dict(x=north - on, y=east - oe, z=down - od)


@pytest.fixture
def make_sim(sim_factory):
    """conftest's simulated vehicles, run faster: each test here takes a second or two."""
    return lambda **overrides: sim_factory(**dict(FAST, **overrides))


@pytest.fixture
def connect():
    stations = []

    def make(sim: SimVehicle, **kw) -> GroundStation:
        gs = GroundStation(sim.tcp_port, **kw)
        stations.append(gs)
        return gs

    yield make
    for gs in stations:
        gs.close()


def airborne(sim: SimVehicle, gs: GroundStation, altitude: float = 3.0) -> None:
    """Wait until ready, then GUIDED, arm and take off to ``altitude``."""
    assert wait_until(lambda: sim.truth().ready, 10)
    assert gs.set_mode("GUIDED").result == mavlink.MAV_RESULT_ACCEPTED
    assert gs.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == mavlink.MAV_RESULT_ACCEPTED
    assert gs.command(mavlink.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, altitude).result == mavlink.MAV_RESULT_ACCEPTED
    assert wait_until(lambda: sim.truth().landed_state == mavlink.MAV_LANDED_STATE_IN_AIR, 20), sim.truth()


# -- streams ---------------------------------------------------------------------------------------------
def test_only_heartbeats_until_streams_are_requested(make_sim, connect):
    sim = make_sim(ready_after=600.0)
    gs = connect(sim)
    assert wait_until(lambda: len(gs.messages("HEARTBEAT")) >= 3, 10)
    # the start-up lines come unasked, as in the 4.7 recording ("ArduPilot Ready", ...); no stream does
    assert {m.get_type() for m in gs.messages()} == {"HEARTBEAT", "STATUSTEXT"}
    hb = gs.messages("HEARTBEAT")[-1]
    assert hb.type == mavlink.MAV_TYPE_QUADROTOR and hb.autopilot == mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA
    assert hb.base_mode & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    assert not hb.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED
    assert hb.custom_mode == 0 and hb.system_status == mavlink.MAV_STATE_STANDBY
    assert hb.get_srcSystem() == 1 and hb.get_srcComponent() == 1


def test_streams_follow_request_data_stream_and_stop_at_rate_zero(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    assert gs.wait("HEARTBEAT")
    mark = gs.mark()
    gs.request_streams(4)
    wanted = {"SYS_STATUS", "GPS_RAW_INT", "GLOBAL_POSITION_INT", "LOCAL_POSITION_NED", "ATTITUDE", "VFR_HUD",
              "BATTERY_STATUS", "EKF_STATUS_REPORT", "WIND", "RAW_IMU", "SCALED_PRESSURE"}
    assert wait_until(lambda: wanted <= {m.get_type() for m in gs.messages(since=mark)}, 10), \
        wanted - {m.get_type() for m in gs.messages(since=mark)}
    # 4.7 recording: REQUEST_DATA_STREAM alone never brings EXTENDED_SYS_STATE (SET_MESSAGE_INTERVAL does)
    assert not gs.messages("EXTENDED_SYS_STATE", mark)
    # 4 Hz in simulated time, whatever the speedup
    assert wait_until(lambda: len(gs.messages("ATTITUDE", mark)) >= 14, 10)
    stamps = [m.time_boot_ms for m in gs.messages("ATTITUDE", mark)]
    span = (stamps[-1] - stamps[0]) / 1000.0
    assert abs((len(stamps) - 1) / span - 4.0) < 0.3, (len(stamps), span)

    gs.request_streams(0, mavlink.MAV_DATA_STREAM_EXTRA1)          # ATTITUDE off, the rest stays
    stop = gs.mark()
    first = gs.wait("HEARTBEAT", since=stop)
    assert first is not None
    after = gs.mark()
    for _ in range(2):
        assert gs.wait("HEARTBEAT", since=gs.mark())
    assert not gs.messages("ATTITUDE", after)
    assert gs.messages("GLOBAL_POSITION_INT", after)
    gs.request_streams(0, start=0)                                  # everything off
    stop = gs.mark()
    assert gs.wait("HEARTBEAT", since=stop)
    after = gs.mark()
    for _ in range(2):
        assert gs.wait("HEARTBEAT", since=gs.mark())
    assert {m.get_type() for m in gs.messages(since=after)} <= {"HEARTBEAT", "STATUSTEXT"}


def test_set_message_interval_and_request_message(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    ack = gs.command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, mavlink.MAVLINK_MSG_ID_VFR_HUD, 100000)
    assert ack.result == mavlink.MAV_RESULT_ACCEPTED
    assert ack.target_system == 255 and ack.target_component == 190
    mark = gs.mark()
    # ten VFR_HUD between two heartbeats (1 Hz): both rates are in simulated time
    assert wait_until(lambda: len(gs.messages("HEARTBEAT", mark)) >= 2, 10)
    between = gs.messages(since=mark)
    beats = [i for i, m in enumerate(between) if m.get_type() == "HEARTBEAT"]
    count = sum(1 for m in between[beats[0]:beats[1]] if m.get_type() == "VFR_HUD")
    assert 9 <= count <= 11, count
    assert gs.messages("ATTITUDE", mark) == []

    assert gs.command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, mavlink.MAVLINK_MSG_ID_VFR_HUD, -1).result == \
        mavlink.MAV_RESULT_ACCEPTED
    assert gs.wait("HEARTBEAT", since=gs.mark())
    after = gs.mark()
    assert gs.wait("HEARTBEAT", since=after) and gs.wait("HEARTBEAT", since=gs.mark())
    assert not gs.messages("VFR_HUD", after)

    assert gs.command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 9999, 100000).result == mavlink.MAV_RESULT_FAILED
    mark = gs.mark()
    ack = gs.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION)
    assert ack.result == mavlink.MAV_RESULT_ACCEPTED
    version = gs.wait("AUTOPILOT_VERSION", since=mark)
    assert version.capabilities & mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2
    assert gs.command(mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1).result == mavlink.MAV_RESULT_ACCEPTED
    assert wait_until(lambda: sim.truth().ready, 10)
    mark = gs.mark()
    assert gs.command(mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAVLINK_MSG_ID_HOME_POSITION).result == \
        mavlink.MAV_RESULT_ACCEPTED
    home = gs.wait("HOME_POSITION", since=mark)
    assert home.latitude == round(40.2839e7) and home.longitude == round(-3.7940e7) and home.altitude == 664000


def test_telemetry_is_consistent(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    assert wait_until(lambda: sim.truth().ready, 10)
    gs.request_streams(10)
    mark = gs.mark()
    for kind in ("SYS_STATUS", "BATTERY_STATUS", "GPS_RAW_INT", "EKF_STATUS_REPORT", "RAW_IMU", "GLOBAL_POSITION_INT"):
        assert gs.wait(kind, since=mark), kind
    status = gs.messages("SYS_STATUS", mark)[-1]
    battery = gs.messages("BATTERY_STATUS", mark)[-1]
    assert status.onboard_control_sensors_health & PREARM
    assert 16000 < status.voltage_battery <= 16800 and status.battery_remaining > 95
    assert abs(battery.voltages[0] - status.voltage_battery) < 50
    assert battery.battery_remaining == status.battery_remaining
    gps = gs.messages("GPS_RAW_INT", mark)[-1]
    assert gps.fix_type == 3 and gps.satellites_visible >= 8
    ekf = gs.messages("EKF_STATUS_REPORT", mark)[-1]
    good = mavlink.EKF_ATTITUDE | mavlink.EKF_VELOCITY_HORIZ | mavlink.EKF_POS_HORIZ_ABS | mavlink.EKF_PRED_POS_HORIZ_ABS
    assert ekf.flags & good == good
    imu = gs.messages("RAW_IMU", mark)[-1]
    assert abs(math.degrees(math.atan2(-imu.ymag, imu.xmag))) < 3          # home heading is north
    assert -1050 < imu.zacc < -950
    pos = gs.messages("GLOBAL_POSITION_INT", mark)[-1]
    assert abs(pos.lat - 402839000) < 20 and abs(pos.lon + 37940000) < 20 and abs(pos.relative_alt) < 50


# -- readiness and arming -------------------------------------------------------------------------------
def test_arming_before_ready_is_refused_with_a_prearm_reason(make_sim, connect):
    sim = make_sim(ready_after=600.0)
    gs = connect(sim)
    gs.request_streams(4)
    assert gs.wait("SYS_STATUS")
    status = gs.messages("SYS_STATUS")[-1]
    assert not status.onboard_control_sensors_health & PREARM
    # as ArduPilot: a fence that has not failed is healthy, present or not (else MAVProxy says "fence breach")
    assert status.onboard_control_sensors_health & mavlink.MAV_SYS_STATUS_GEOFENCE
    assert not status.onboard_control_sensors_present & mavlink.MAV_SYS_STATUS_GEOFENCE
    assert gs.wait("GPS_RAW_INT").fix_type < 3
    mark = gs.mark()
    ack = gs.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1)
    assert ack.result == mavlink.MAV_RESULT_FAILED
    # 4.7 recording: the refusal reasons come as "Arm: ..." lines, severity CRITICAL, after the ACK
    text = gs.wait(lambda m: m.get_type() == "STATUSTEXT" and m.text.startswith("Arm:"), since=mark)
    assert text is not None and text.severity == mavlink.MAV_SEVERITY_CRITICAL
    assert not sim.truth().armed
    # disarmed, any mode may be set (recording: GUIDED ACCEPTED at 7 s, long before a position)
    assert gs.set_mode("GUIDED").result == mavlink.MAV_RESULT_ACCEPTED
    mark = gs.mark()
    assert gs.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == mavlink.MAV_RESULT_FAILED
    assert gs.wait(lambda m: m.get_type() == "STATUSTEXT" and m.text.startswith("Arm:"), since=mark)
    # forced arming (21196) bypasses the checks, as on ArduCopter
    ack = gs.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1, 21196)
    assert ack.result == mavlink.MAV_RESULT_ACCEPTED and sim.truth().armed
    assert gs.wait(lambda m: m.get_type() == "HEARTBEAT" and m.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED)


def test_ready_after_the_configured_time(make_sim, connect):
    sim = make_sim(ready_after=2.0)
    gs = connect(sim)
    gs.request_streams(4)
    text = gs.wait(lambda m: m.get_type() == "STATUSTEXT" and "is using GPS" in m.text, 10)
    assert text is not None and sim.truth().ready
    when = next(t for t, m in gs.stamped() if m is text)
    assert 1.7 <= when <= 2.1, when
    early = [m for t, m in gs.stamped() if t < 1.9]
    assert not any(m.onboard_control_sensors_health & PREARM for m in early if m.get_type() == "SYS_STATUS")
    assert not any(m.get_type() == "LOCAL_POSITION_NED" for m in early)     # no EKF position yet
    # as recorded, the GPS has its fix long before the EKF uses it: a fix alone is not "ready"
    assert any(m.fix_type >= 3 for m in early if m.get_type() == "GPS_RAW_INT")
    mark = gs.mark()
    assert gs.wait(lambda m: m.get_type() == "SYS_STATUS" and m.onboard_control_sensors_health & PREARM, since=mark)


# -- flight ------------------------------------------------------------------------------------------------
def test_takeoff_climbs_to_the_target(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    assert wait_until(lambda: sim.truth().ready, 10)
    assert gs.command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE, 100000).result \
        == mavlink.MAV_RESULT_ACCEPTED
    # takeoff is refused unless GUIDED and armed
    assert gs.command(mavlink.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 3).result == mavlink.MAV_RESULT_FAILED
    assert gs.set_mode("GUIDED").result == mavlink.MAV_RESULT_ACCEPTED
    assert gs.command(mavlink.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 3).result == mavlink.MAV_RESULT_FAILED
    assert gs.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == mavlink.MAV_RESULT_ACCEPTED
    mark = gs.mark()
    assert gs.command(mavlink.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 3).result == mavlink.MAV_RESULT_ACCEPTED
    assert gs.wait(lambda m: m.get_type() == "EXTENDED_SYS_STATE" and m.landed_state == 3, since=mark)
    assert gs.wait(lambda m: m.get_type() == "EXTENDED_SYS_STATE" and m.landed_state == 2, 20, since=mark)
    truth = sim.truth()
    assert truth.armed and truth.mode == "GUIDED" and 2.85 < truth.altitude < 3.2, truth
    sim_wait(sim, 2.0)
    assert abs(sim.truth().altitude - 3.0) < 0.15 and sim.truth().landed_state == 2
    # a second takeoff while flying is refused, as ArduCopter's "can't takeoff again"
    assert gs.command(mavlink.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 5).result == mavlink.MAV_RESULT_FAILED


def test_body_velocity_moves_along_the_heading_also_after_turning(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    airborne(sim, gs)
    gs.request_streams(10, mavlink.MAV_DATA_STREAM_EXTRA1)
    before = sim.truth()
    mark = gs.mark()
    hold(gs, sim, 3.0, lambda: gs.setpoint(mavlink.MAV_FRAME_BODY_OFFSET_NED, 1479, vx=2.0))
    after = sim.truth()
    dn, de = after.north - before.north, after.east - before.east
    assert 4.0 < math.hypot(dn, de) <= 2.0 * (after.time - before.time) and \
        angle_deg(math.atan2(de, dn), before.yaw) < 5
    # nose down while accelerating forward
    assert min(m.pitch for m in gs.messages("ATTITUDE", mark)) < -0.05
    gs.setpoint(mavlink.MAV_FRAME_BODY_OFFSET_NED, 1479)                  # sticks released
    assert wait_until(lambda: sim.truth().ground_speed < 0.05, 10)

    ack = gs.command(mavlink.MAV_CMD_CONDITION_YAW, 90, 45, 1, 1)
    assert ack.result == mavlink.MAV_RESULT_ACCEPTED
    assert wait_until(lambda: angle_deg(sim.truth().yaw, before.yaw + math.pi / 2) < 2, 20), sim.truth()
    before = sim.truth()
    hold(gs, sim, 3.0, lambda: gs.setpoint(mavlink.MAV_FRAME_BODY_NED, 1479, vx=2.0))
    after = sim.truth()
    dn, de = after.north - before.north, after.east - before.east
    assert math.hypot(dn, de) > 4.0 and angle_deg(math.atan2(de, dn), math.pi / 2) < 8, (dn, de)
    assert sim.received_setpoints[-1][1:4] == (mavlink.MAV_FRAME_BODY_NED, 1479, 2.0)


def test_local_velocity_moves_north_east_and_the_nose_follows(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    airborne(sim, gs)
    before = sim.truth()
    hold(gs, sim, 4.0, lambda: gs.setpoint(mavlink.MAV_FRAME_LOCAL_NED, 3527, vx=0.0, vy=2.0, vz=-0.5))
    after = sim.truth()
    assert after.east - before.east > 5.0 and abs(after.north - before.north) < 0.5
    assert after.altitude - before.altitude > 1.0
    assert angle_deg(after.yaw, math.pi / 2) < 10           # no yaw in the mask: nose turns to the travel


def test_yaw_rate_turns_clockwise(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    airborne(sim, gs)
    before = sim.truth()
    hold(gs, sim, 2.0, lambda: gs.setpoint(mavlink.MAV_FRAME_BODY_OFFSET_NED, 1479, yaw_rate=0.5))
    after = sim.truth()
    turned = math.atan2(math.sin(after.yaw - before.yaw), math.cos(after.yaw - before.yaw))
    assert 0.75 < turned <= 0.5 * (after.time - before.time), math.degrees(turned)
    assert math.hypot(after.north - before.north, after.east - before.east) < 0.3


def test_velocity_stops_three_seconds_after_the_last_setpoint(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    airborne(sim, gs)
    assert gs.command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED, 100000).result \
        == mavlink.MAV_RESULT_ACCEPTED
    n = len(sim.received_setpoints)
    gs.setpoint(mavlink.MAV_FRAME_LOCAL_NED, 3527, vx=2.0)
    assert wait_until(lambda: len(sim.received_setpoints) > n)
    sent_at = sim.received_setpoints[-1][0]
    assert wait_until(lambda: sim.truth().time >= sent_at + 8.0, 20)
    track = [(m.time_boot_ms / 1000.0, m) for m in gs.messages("LOCAL_POSITION_NED")]
    obeying = [m.vx for t, m in track if sent_at + 2.0 <= t <= sent_at + 3.0]
    stopped = [m for t, m in track if t >= sent_at + 6.5]
    assert obeying and min(obeying) > 1.8                      # still obeying until GUID_TIMEOUT
    assert stopped and all(abs(m.vx) < 0.1 for m in stopped)  # then stopped and holding
    assert max(m.x for m in stopped) - min(m.x for m in stopped) < 0.2
    assert sim.truth().mode == "GUIDED"


def test_velocity_is_ignored_on_the_ground_and_outside_guided(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    assert wait_until(lambda: sim.truth().ready, 10)
    gs.setpoint(mavlink.MAV_FRAME_LOCAL_NED, 3527, vx=2.0)
    assert wait_until(lambda: len(sim.received_setpoints) == 1)
    sim_wait(sim, 1.0)
    assert sim.truth().north == 0.0
    airborne(sim, gs)
    assert gs.set_mode("LOITER").result == mavlink.MAV_RESULT_ACCEPTED
    before = sim.truth()
    hold(gs, sim, 2.0, lambda: gs.setpoint(mavlink.MAV_FRAME_LOCAL_NED, 3527, vx=2.0))
    assert abs(sim.truth().north - before.north) < 0.2


def test_position_target_goes_there(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    airborne(sim, gs)
    gs.setpoint(mavlink.MAV_FRAME_LOCAL_NED, 3576, **local_ned(sim, 6.0, -4.0, -5.0))     # from the EKF origin
    assert wait_until(lambda: math.hypot(sim.truth().north - 6, sim.truth().east + 4) < 0.3
                      and abs(sim.truth().altitude - 5) < 0.3, 20), sim.truth()


def test_land_touches_down_and_disarms(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    airborne(sim, gs)
    gs.command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE, 200000)
    mark = gs.mark()
    assert gs.set_mode("LAND").result == mavlink.MAV_RESULT_ACCEPTED
    assert gs.wait(lambda m: m.get_type() == "EXTENDED_SYS_STATE" and m.landed_state == 4, since=mark)
    # 4.7 recording: no "Land complete"; SITL's "SIM Hit ground at 0.499819 m/s", then "Disarming motors"
    assert gs.wait(lambda m: m.get_type() == "STATUSTEXT" and m.text.startswith("SIM Hit ground"), 30, since=mark)
    assert gs.wait(lambda m: m.get_type() == "STATUSTEXT" and m.text == "Disarming motors", 10, since=mark)
    assert gs.wait(lambda m: m.get_type() == "HEARTBEAT" and not m.base_mode & 128, 10, since=mark)
    assert not any("Land complete" in m.text for m in gs.messages("STATUSTEXT", mark))
    truth = sim.truth()
    assert not truth.armed and truth.down == 0.0 and truth.landed_state == 1 and truth.mode == "LAND"


def test_rtl_returns_home_and_lands(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    mark = gs.mark()
    gs.send(gs.encoder.param_set_encode(1, 1, b"RTL_ALT", 600, mavlink.MAV_PARAM_TYPE_INT32))
    echo = gs.wait(lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == "RTL_ALT", since=mark)
    assert echo is not None and echo.param_value == 600
    airborne(sim, gs)
    gs.setpoint(mavlink.MAV_FRAME_LOCAL_NED, 3576, **local_ned(sim, 8.0, 3.0, -3.0))
    assert wait_until(lambda: math.hypot(sim.truth().north - 8, sim.truth().east - 3) < 0.2
                      and sim.truth().ground_speed < 0.1, 20)
    assert gs.command(mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH).result == mavlink.MAV_RESULT_ACCEPTED
    assert wait_until(lambda: sim.truth().altitude > 5.0, 20)          # climbs to RTL_ALT first, in place
    assert math.hypot(sim.truth().north - 8, sim.truth().east - 3) < 0.5
    assert wait_until(lambda: not sim.truth().armed, 60), sim.truth()
    truth = sim.truth()
    assert math.hypot(truth.north, truth.east) < 0.5 and truth.down == 0.0 and truth.mode == "RTL"


def test_brake_stops_and_holds(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    airborne(sim, gs)
    hold(gs, sim, 2.0, lambda: gs.setpoint(mavlink.MAV_FRAME_LOCAL_NED, 3527, vx=3.0))
    assert gs.set_mode("BRAKE").result == mavlink.MAV_RESULT_ACCEPTED
    assert wait_until(lambda: sim.truth().ground_speed < 0.05, 10)
    held = sim.truth()
    sim_wait(sim, 2.0)
    assert math.hypot(sim.truth().north - held.north, sim.truth().east - held.east) < 0.3


def test_auto_disarm_on_the_ground_without_takeoff(make_sim, connect):
    sim = make_sim(auto_disarm_after=3.0)
    gs = connect(sim)
    assert wait_until(lambda: sim.truth().ready, 10)
    gs.request_streams(10, mavlink.MAV_DATA_STREAM_EXTRA1)          # ATTITUDE dates the heartbeats
    assert gs.set_mode("GUIDED").result == mavlink.MAV_RESULT_ACCEPTED
    mark = gs.mark()
    assert gs.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == mavlink.MAV_RESULT_ACCEPTED
    armed_at = [t for t, kind, _ in sim.received_messages if kind == "COMMAND_LONG"][-1]
    # (the HEARTBEAT GUIDED announced at once, disarmed, may arrive after the mark: wait past an armed one)
    assert gs.wait(lambda m: m.get_type() == "HEARTBEAT" and m.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED,
                   since=mark)
    armed_mark = gs.mark()
    assert wait_until(lambda: not sim.truth().armed, 10)
    assert gs.wait(lambda m: m.get_type() == "STATUSTEXT" and m.text.startswith("Disarming"), since=mark)
    assert gs.wait(lambda m: m.get_type() == "HEARTBEAT" and not m.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED,
                   since=armed_mark)
    beats = [(t, m.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED) for t, m in gs.stamped(mark)
             if m.get_type() == "HEARTBEAT"]
    last_armed = max(t for t, armed in beats if armed)
    first_disarmed = min(t for t, armed in beats if not armed and t > armed_at)
    assert last_armed >= armed_at + 1.9 and armed_at + 2.9 <= first_disarmed <= armed_at + 4.2, \
        (armed_at, beats)


def test_disarm_in_the_air_is_refused_unless_forced(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    airborne(sim, gs)
    assert gs.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0).result == mavlink.MAV_RESULT_FAILED
    assert sim.truth().armed
    assert gs.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0, 21196).result == mavlink.MAV_RESULT_ACCEPTED
    assert wait_until(lambda: sim.truth().down == 0.0, 10)             # motors off: it falls
    assert not sim.truth().armed and sim.truth().landed_state == 1


def test_parachute_release_stops_the_motors_and_it_floats_down(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    assert gs.command(mavlink.MAV_CMD_DO_PARACHUTE, mavlink.PARACHUTE_ENABLE).result == mavlink.MAV_RESULT_ACCEPTED
    mark = gs.mark()                         # (off by default, as ArduCopter 4.6.3's CHUTE_ENABLED is)
    gs.send(gs.encoder.param_set_encode(1, 1, b"CHUTE_ALT_MIN", 3, mavlink.MAV_PARAM_TYPE_INT16))
    assert gs.wait(lambda m: m.get_type() == "PARAM_VALUE" and m.param_id == "CHUTE_ALT_MIN", since=mark)
    airborne(sim, gs, altitude=2.0)
    mark = gs.mark()
    assert gs.command(mavlink.MAV_CMD_DO_PARACHUTE, mavlink.PARACHUTE_RELEASE).result == mavlink.MAV_RESULT_ACCEPTED
    assert gs.wait(lambda m: m.get_type() == "STATUSTEXT" and m.text == "Parachute: Too low", since=mark)
    assert sim.truth().armed
    truth = sim.truth()
    gs.setpoint(mavlink.MAV_FRAME_LOCAL_NED, 3576, **local_ned(sim, truth.north, truth.east, -6.0))
    assert wait_until(lambda: sim.truth().altitude > 5.5, 20)
    mark = gs.mark()
    assert gs.command(mavlink.MAV_CMD_DO_PARACHUTE, mavlink.PARACHUTE_RELEASE).result == mavlink.MAV_RESULT_ACCEPTED
    assert gs.wait(lambda m: m.get_type() == "STATUSTEXT" and m.text == "Parachute: Released", since=mark)
    assert not sim.truth().armed
    assert wait_until(lambda: sim.truth().vd > 3.0, 10) and sim.truth().vd < 5.0      # under a canopy
    assert wait_until(lambda: sim.truth().down == 0.0, 20)


def test_global_position_target_and_manual_control(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    airborne(sim, gs)
    lat = 40.2839 + 10.0 / (6378137 * math.pi / 180)                # 10 m north of home
    gs.send(gs.encoder.set_position_target_global_int_encode(
        0, 1, 1, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, 3576, int(lat * 1e7), int(-3.7940 * 1e7), 4.0,
        0, 0, 0, 0, 0, 0, 0, 0))
    assert wait_until(lambda: abs(sim.truth().north - 10) < 0.2 and abs(sim.truth().altitude - 4) < 0.2
                      and sim.truth().ground_speed < 0.05, 20), sim.truth()
    assert gs.set_mode("LOITER").result == mavlink.MAV_RESULT_ACCEPTED
    before = sim.truth()
    hold(gs, sim, 2.0, lambda: gs.send(gs.encoder.manual_control_encode(1, 0, 600, 500, 0, 0)))   # stick right
    after = sim.truth()
    assert after.east - before.east > 2.0 and abs(after.north - before.north) < 0.3


def test_other_commands_are_answered(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    assert gs.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 2).result == mavlink.MAV_RESULT_ACCEPTED
    assert gs.command(mavlink.MAV_CMD_DO_PARACHUTE, mavlink.PARACHUTE_ENABLE).result == mavlink.MAV_RESULT_ACCEPTED
    assert gs.command(mavlink.MAV_CMD_DO_SET_MODE, 1, 99).result == mavlink.MAV_RESULT_FAILED   # no such mode
    assert gs.command(mavlink.MAV_CMD_DO_FENCE_ENABLE, 1).result == mavlink.MAV_RESULT_UNSUPPORTED
    assert gs.command(mavlink.MAV_CMD_DO_SET_MODE, mavlink.MAV_MODE_FLAG_DECODE_POSITION_SAFETY, 0).result == \
        mavlink.MAV_RESULT_ACCEPTED
    mark = gs.mark()
    gs.send(gs.encoder.set_mode_encode(1, mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 2))     # SET_MODE: no ACK
    assert gs.wait(lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == 2, since=mark)
    assert sim.truth().mode == "ALT_HOLD" and sim.truth().last_command == "MAV_CMD_DO_SET_MODE"
    airborne(sim, gs)
    mark = gs.mark()                                       # 4.7 recording, 44.50 s: FAILED and why
    assert gs.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 2).result == mavlink.MAV_RESULT_FAILED
    text = gs.wait(lambda m: m.get_type() == "STATUSTEXT" and m.text == "Disarm to allow calibration", since=mark)
    assert text is not None and text.severity == mavlink.MAV_SEVERITY_NOTICE
    assert gs.command(mavlink.MAV_CMD_NAV_LAND).result == mavlink.MAV_RESULT_ACCEPTED
    assert wait_until(lambda: not sim.truth().armed, 30)
    mark = gs.mark()
    assert gs.command(mavlink.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN, 1).result == mavlink.MAV_RESULT_ACCEPTED
    banner = gs.wait(lambda m: m.get_type() == "STATUSTEXT" and m.text.startswith("ArduCopter"), since=mark)
    assert banner is not None                                           # it starts over ...
    after = gs.messages(since=mark)
    assert gs.wait(lambda m: m.get_type() == "HEARTBEAT" and m.custom_mode == 0, since=mark)
    assert gs.wait(lambda m: m.get_type() == "STATUSTEXT" and "is using GPS" in m.text,  # ... and gets ready again
                   since=mark + after.index(banner))


# -- faults -------------------------------------------------------------------------------------------------
def test_ignored_commands_get_no_ack(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    sim.faults.ignore_commands = {mavlink.MAV_CMD_COMPONENT_ARM_DISARM}
    assert gs.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1, timeout=1.0) is None
    assert sim.truth().last_command == "MAV_CMD_COMPONENT_ARM_DISARM" and not sim.truth().armed
    assert gs.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 2).result == mavlink.MAV_RESULT_ACCEPTED
    sim.faults.ignore_commands = True
    assert gs.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 2, timeout=1.0) is None
    sim.faults.ignore_commands = set()
    assert gs.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 2) is not None


def test_link_down_silences_both_ways(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    assert gs.wait("HEARTBEAT")
    sim.faults.link_down = True
    sim_wait(sim, 0.2)
    mark = gs.mark()
    heard = len(sim.received_messages)
    gs.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 2, timeout=0.01)
    sim_wait(sim, 3.0)
    assert gs.mark() == mark and len(sim.received_messages) == heard
    sim.faults.link_down = False
    assert gs.wait("HEARTBEAT", since=mark)                            # same TCP connection, alive again
    assert gs.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 2).result == mavlink.MAV_RESULT_ACCEPTED


def test_refuse_arm_gives_the_reason(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    assert wait_until(lambda: sim.truth().ready, 10)
    sim.faults.refuse_arm = "Compass not calibrated"
    mark = gs.mark()
    assert gs.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == mavlink.MAV_RESULT_FAILED
    assert gs.wait(lambda m: m.get_type() == "STATUSTEXT" and m.text == "PreArm: Compass not calibrated", since=mark)
    sim.faults.refuse_arm = None
    assert gs.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1).result == mavlink.MAV_RESULT_ACCEPTED


def test_heartbeats_fault_and_lossy_link(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    gs.request_streams(10)
    assert gs.wait("HEARTBEAT")
    sim.faults.heartbeats = False
    sim_wait(sim, 0.2)
    mark = gs.mark()
    sim_wait(sim, 2.5)
    assert gs.messages("ATTITUDE", mark) and not gs.messages("HEARTBEAT", mark)
    sim.faults.heartbeats = True
    sim.faults.drop_fraction = 0.5
    sim.faults.corrupt_fraction = 0.2
    mark, bad = gs.mark(), gs.bad
    sim_wait(sim, 3.0)
    attitude = gs.messages("ATTITUDE", mark)
    assert 0 < len(attitude) < 28 and gs.bad > bad
    seqs = [m.get_seq() for m, _ in gs.frames[mark:]]
    assert any((b - a) % 256 > 1 for a, b in zip(seqs, seqs[1:]))        # gaps show the loss


# -- protocol ----------------------------------------------------------------------------------------------
def test_mavlink2_vehicle_accepts_both_versions(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    assert gs.wait("HEARTBEAT")
    assert {v for _, v in gs.frames} == {2}
    assert gs.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 2, mav1=True) is not None
    assert gs.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 2, mav1=False) is not None
    assert [v for _, kind, v in sim.received_messages if kind == "COMMAND_LONG"] == [1, 2]


def test_solo_like_vehicle_speaks_mavlink1_and_ignores_mavlink2(make_sim, connect):
    sim = make_sim(mavlink2=False)
    gs = connect(sim, mav1=True)
    gs.request_streams(4)
    assert wait_until(lambda: len(gs.messages("SYS_STATUS")) >= 2, 10)
    assert {v for _, v in gs.frames} == {1}
    assert gs.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 2, mav1=False, timeout=1.0) is None
    assert "COMMAND_LONG" not in {kind for _, kind, _ in sim.received_messages}
    ack = gs.command(mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1)
    assert ack is not None and ack.result == mavlink.MAV_RESULT_ACCEPTED
    version = gs.wait("AUTOPILOT_VERSION")
    assert not version.capabilities & mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2


def test_garbage_input_never_stops_the_vehicle(make_sim, connect):
    sim = make_sim()
    gs = connect(sim)
    rnd = random.Random(3)
    for _ in range(20):
        gs.send_raw(bytes(rnd.getrandbits(8) for _ in range(1000)))
        gs.send_raw(b"\xfd\x20\x00\x00" + bytes(rnd.getrandbits(8) for _ in range(40)))    # frame-shaped, bad CRC
        gs.send_raw(b"\xfe\x21" + bytes(rnd.getrandbits(8) for _ in range(38)))
    frame = bytearray(gs.encoder.command_long_encode(1, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0).pack(gs.encoder))
    frame[-1] ^= 0xFF                                                          # bad CRC: must not arm
    gs.send_raw(bytes(frame) + b"\x00" * 300)
    # a NaN takeoff altitude and NaN setpoints are refused or ignored, never flown
    assert gs.command(mavlink.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, float("nan")).result == mavlink.MAV_RESULT_FAILED
    gs.setpoint(mavlink.MAV_FRAME_LOCAL_NED, 3527, vx=float("nan"))
    assert gs.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 2).result == mavlink.MAV_RESULT_ACCEPTED
    assert not sim.truth().armed and math.isfinite(sim.truth().north)
    # and the other way: garbage injected toward the ground station
    mark = gs.mark()
    sim.inject(bytes(rnd.getrandbits(8) for _ in range(5000)))
    assert gs.wait("HEARTBEAT", since=mark) and gs.bad > 0


# -- sockets and clock --------------------------------------------------------------------------------------
def test_several_tcp_clients_each_get_everything(make_sim, connect):
    sim = make_sim()
    first, second = connect(sim), connect(sim, system=254, component=1)
    assert first.wait("HEARTBEAT") and second.wait("HEARTBEAT")
    assert wait_until(lambda: sim.clients == 2)
    ack = second.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 2)
    assert ack.target_system == 254 and ack.target_component == 1
    assert first.wait(lambda m: m.get_type() == "COMMAND_ACK" and m.target_system == 254)
    first.close()
    assert wait_until(lambda: sim.clients == 1)
    mark = second.mark()
    assert second.wait("HEARTBEAT", since=mark)


def test_udp_out_pushes_like_the_solo_and_takes_replies(make_sim):
    ground = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    ground.bind(("127.0.0.1", 0))
    ground.settimeout(5)
    try:
        sim = make_sim(tcp_port=None, udp_out=f"127.0.0.1:{ground.getsockname()[1]}", mavlink2=False)
        parser = mavlink.MAVLink(None, 255, 190)
        parser.robust_parsing = True
        while True:                                     # start-up STATUSTEXT may come first
            data, vehicle_address = ground.recvfrom(4096)
            assert data[0] == 0xFE                      # MAVLink 1 only
            if parser.parse_buffer(data)[0].get_type() == "HEARTBEAT":
                break
        encoder = mavlink.MAVLink(None, 255, 190)
        ground.sendto(encoder.command_long_encode(1, 1, 241, 0, 0, 0, 0, 0, 2, 0, 0).pack(encoder, True),
                      vehicle_address)
        deadline = time.monotonic() + 5
        ack = None
        while ack is None and time.monotonic() < deadline:
            for msg in parser.parse_buffer(ground.recvfrom(4096)[0]) or []:
                if msg.get_type() == "COMMAND_ACK":
                    ack = msg
        assert ack is not None and ack.command == 241 and ack.result == mavlink.MAV_RESULT_ACCEPTED
    finally:
        ground.close()


def test_udp_listen_serves_whoever_spoke(make_sim):
    sim = make_sim(tcp_port=None, udp_listen="127.0.0.1:0")
    ground = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    ground.settimeout(5)
    try:
        encoder, parser = mavlink.MAVLink(None, 255, 190), mavlink.MAVLink(None, 255, 190)
        ground.sendto(encoder.heartbeat_encode(6, 8, 0, 0, 0).pack(encoder), ("127.0.0.1", sim.udp_port))
        heard = set()
        while "HEARTBEAT" not in heard:             # recvfrom times out (fails) if nothing comes back
            heard |= {m.get_type() for m in parser.parse_buffer(ground.recvfrom(4096)[0]) or []}
    finally:
        ground.close()


def test_speedup_runs_the_clock_faster():
    """``speedup`` sim seconds per real second, checked on a hand-driven clock: no wall-clock ratio that a
    loaded machine could spoil, and it fails if the speed-up were ignored (1 real s would be 1 sim s)."""
    clock = ManualClock()
    sim = SimVehicle(SimConfig(**dict(FAST, speedup=10.0)), clock=clock).start()
    try:
        assert clock.settle()                          # the sim waits for time to pass
        start, steps = sim.truth().time, sim.steps
        for _ in range(10):                            # one real second, in tenths the sim keeps up with
            clock.advance(0.1)
            assert clock.settle()
        dt = 1.0 / sim.config.rate_hz
        assert sim.steps - steps == pytest.approx(10.0 / dt, abs=1)
        assert sim.truth().time - start == pytest.approx(10.0, abs=1.5 * dt)
    finally:
        sim.stop()


def test_stop_is_clean_and_idempotent():
    sim = SimVehicle(SimConfig(**FAST)).start()
    port = sim.tcp_port
    gs = GroundStation(port)
    assert gs.wait("HEARTBEAT")
    sim.stop()
    sim.stop()
    with pytest.raises(OSError):
        socket.create_connection(("127.0.0.1", port), timeout=1).close()
    gs.close()
    again = SimVehicle(SimConfig(**dict(FAST, tcp_port=port))).start()    # the port is free again
    again.stop()


def test_autopilot_steps_without_sockets():
    """The physics and autopilot logic are testable directly: a takeoff to 5 m takes the recording's ~8 s
    (2 s arming delay and spool-up on the ground, then the climb: 4.99 m 8.08 s after NAV_TAKEOFF)."""
    sent = []
    ap = Autopilot(SimConfig(ready_after=0.0), emit=sent.append)
    ap.step(0.02)
    factory = mavlink.MAVLink(None, 255, 190)

    def command(cmd, *p):
        msg = factory.command_long_encode(1, 1, cmd, 0, *(list(p) + [0] * (7 - len(p))))
        msg.pack(factory)
        ap.handle(msg)
        return [m for m in sent if m.get_type() == "COMMAND_ACK"][-1].result

    assert command(176, 1, 4) == 0 and command(400, 1) == 0 and command(22, 0, 0, 0, 0, 0, 0, 5) == 0
    start = ap.t
    while ap.landed_state() != mavlink.MAV_LANDED_STATE_IN_AIR and ap.t - start < 30:
        ap.step(0.02)
    assert ap.truth().altitude >= 4.75                       # takeoff over at 95 %
    while ap.truth().altitude < 4.95 and ap.t - start < 30:
        ap.step(0.02)
    assert 7.0 < ap.t - start < 9.0, ap.t - start
