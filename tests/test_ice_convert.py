"""The frame conversions between the driver (NED/FRD) and JdeRobot (ENU/FLU), checked without a network."""
from __future__ import annotations

import math

import numpy as np
import pytest
from pymavlink.quaternion import QuaternionBase

from driver.ice import convert, load_slice
from driver.mission.plan import MissionProgress, MissionRunState
from driver.vehicle.state import (Attitude, Battery, Boot, CommandResult, CommandStatus, Environment, GlobalPosition, Gps,
                          LandedState, LinkHealth, LinkStatus, LocalPosition, Message, Readiness, SequencePhase,
                          SequenceProgress, SequenceState, Setpoint, Severity, VehicleState, Velocity)

NED_TO_ENU = np.array([[0, 1, 0], [1, 0, 0], [0, 0, -1]], dtype=float)
FRD_TO_FLU = np.diag([1.0, -1.0, -1.0])


def rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Body-to-world rotation of ZYX Euler angles."""
    cr, sr, cp, sp, cy, sy = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw), \
        math.sin(yaw)
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


def jderobot_yaw(q0, q1, q2, q3) -> float:
    return math.atan2(2 * (q1 * q2 + q0 * q3), q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3)


def flying(**changes) -> VehicleState:
    base = dict(link=LinkHealth(status=LinkStatus.OK), mode="GUIDED", armed=True, landed_state=LandedState.IN_AIR,
                altitude=3.0, local=LocalPosition(4.0, -2.0, -3.0))
    base.update(changes)
    return VehicleState(**base)


ANGLES = [(r, p, y) for r in (0.0, 0.3, -0.2) for p in (0.0, 0.25, -0.4) for y in (0.0, 0.5, -2.0, math.pi, 1.6)]


@pytest.mark.parametrize("roll,pitch,yaw", ANGLES)
def test_pose_quaternion_is_flu_body_in_enu(roll, pitch, yaw):
    state = flying(attitude=Attitude(roll=roll, pitch=pitch, yaw=yaw))
    x, y, z, h, *q = convert.pose_enu(state)
    expected = NED_TO_ENU @ rotation(roll, pitch, yaw) @ FRD_TO_FLU
    got = np.array(QuaternionBase(q).dcm)
    np.testing.assert_allclose(got, expected, atol=1e-9)
    heading_enu = math.atan2(math.sin(math.pi / 2 - yaw), math.cos(math.pi / 2 - yaw))
    assert math.isclose(math.remainder(jderobot_yaw(*q) - heading_enu, 2 * math.pi), 0.0, abs_tol=1e-9)
    assert (x, y, z, h) == (-2.0, 4.0, 3.0, 1.0)


def test_facing_east_is_yaw_zero_and_north_is_quarter_turn_left():
    east = convert.pose_enu(flying(attitude=Attitude(yaw=math.pi / 2)))
    north = convert.pose_enu(flying(attitude=Attitude(yaw=0.0)))
    assert math.isclose(jderobot_yaw(*east[4:]), 0.0, abs_tol=1e-9)
    assert math.isclose(jderobot_yaw(*north[4:]), math.pi / 2, abs_tol=1e-9)


def test_cmdvel_is_forward_left_up_counter_clockwise():
    assert convert.body_from_cmdvel(1.0, 0.0, 0.0, 0.0) == (1.0, -0.0, 0.0, -0.0)
    forward, right, up, yaw_rate = convert.body_from_cmdvel(0.0, 0.5, 0.3, 0.2)
    assert (right, up, yaw_rate) == (-0.5, 0.3, -0.2)       # left is negative right; CCW is nose left
    assert convert.cmdvel_from_body(*convert.body_from_cmdvel(0.7, -0.4, 0.1, 0.3)) == (0.7, -0.4, 0.1, 0.3)
    assert convert.clamp_cmdvel((5.0, -5.0, 3.0, -2.0), (2.0, 1.5, 1.0, 0.5)) == (2.0, -1.5, 1.0, -0.5)


def test_waypoint_enu_to_north_east_altitude():
    assert convert.waypoint_from_enu(3.0, 4.0, 5.0) == (4.0, 3.0, 5.0)
    assert convert.waypoint_from_enu(float("nan"), 0.0, 2.0) is None


def test_navdata_fields_body_velocity_and_units():
    # facing east (yaw 90 deg NED), moving north at 1 m/s and climbing 0.5 m/s: that is to the left
    state = flying(attitude=Attitude(roll=0.1, pitch=0.2, yaw=math.pi / 2), velocity=Velocity(1.0, 0.0, -0.5),
                   altitude=3.25, battery=Battery(voltage=15.9, remaining=72.0),
                   environment=Environment(mag=(120, -40, 300), accel_g=(0.01, 0.02, -0.98), pressure_hpa=1013.2,
                                           temperature_c=24.6, wind_speed=3.5, wind_direction_deg=270.0))
    f = convert.navdata_fields(state, vehicle=1, clock=12.5)
    assert f["vx"] == pytest.approx(0.0, abs=1e-9) and f["vy"] == pytest.approx(1000.0)
    assert f["vz"] == pytest.approx(500.0)
    assert f["altd"] == 3250 and f["batteryPercent"] == 72.0
    assert f["rotX"] == pytest.approx(math.degrees(0.1)) and f["rotY"] == pytest.approx(-math.degrees(0.2))
    assert f["rotZ"] == pytest.approx(0.0, abs=1e-9)                     # ENU yaw: facing east
    assert (f["magX"], f["magY"], f["magZ"]) == (120, -40, 300)
    assert (f["ax"], f["ay"], f["az"]) == pytest.approx((0.01, -0.02, 0.98))   # FLU: +1 g up at rest
    assert f["pressure"] == 101320 and f["temp"] == 25
    assert (f["windSpeed"], f["windAngle"]) == (3.5, 270.0)
    assert f["state"] == convert.NAV_FLYING and f["tm"] == 12.5 and f["tagsCount"] == 0
    jderobot, _ = load_slice()
    jderobot.NavdataData(**f)                                             # every field named right


@pytest.mark.parametrize("changes,expected", [
    (dict(link=LinkHealth(status=LinkStatus.LOST)), convert.NAV_UNKNOWN),
    (dict(armed=False, landed_state=LandedState.ON_GROUND, altitude=0.0), convert.NAV_LANDED),
    (dict(landed_state=LandedState.TAKEOFF), convert.NAV_TAKING_OFF),
    (dict(takeoff=SequenceProgress(SequencePhase.CLIMBING)), convert.NAV_TAKING_OFF),
    (dict(mode="LAND", landed_state=LandedState.LANDING), convert.NAV_LANDING),
    (dict(mode="RTL"), convert.NAV_GOTO),
    (dict(), convert.NAV_HOVERING),
    (dict(velocity=Velocity(1.5, 0.0, 0.0)), convert.NAV_FLYING),
])
def test_navdata_state_mapping(changes, expected):
    assert convert.navdata_state(flying(**changes)) == expected


def test_navdata_and_pose_never_carry_nan():
    broken = flying(altitude=float("nan"), attitude=Attitude(roll=float("inf")),
                    local=LocalPosition(float("nan"), 0.0, 0.0))
    f = convert.navdata_fields(broken)
    assert all(not isinstance(v, float) or math.isfinite(v) for v in f.values())
    assert all(math.isfinite(v) for v in convert.pose_enu(broken))


def test_status_round_trip_keeps_every_field():
    _, ms = load_slice()
    state = flying(time=123.5, system_id=1, vehicle_type=2, attitude=Attitude(0.1, -0.2, 1.3, 0.01, 0.02, 0.03),
                   position=GlobalPosition(-35.36, 149.16, 584.0), home=GlobalPosition(-35.36, 149.17, 581.0),
                   velocity=Velocity(1.0, -2.0, 0.5), heading_deg=74.5, airspeed=2.5,
                   battery=Battery(15.2, 9.5, 55.0, True, 4, False),                   # its alarm derived on both sides
                   gps=Gps(3, 12, 0.8),
                   readiness=Readiness(False, True, True, reasons=("3D Accel calibration needed",)),
                   boot=Boot(restarts=2),
                   environment=Environment((1, 2, 3), (0.0, 0.1, -1.0), 1001.0, 21.0, 2.0, 90.0, 45),
                   messages=(Message(4, 99.0, Severity.WARNING, "PreArm: Need 3D Fix", "vehicle"),),
                   results=(CommandResult("arm", CommandStatus.REFUSED, "denied", 1, 7),),
                   takeoff=SequenceProgress(SequencePhase.DONE, "reached", 3.0),
                   sequence=SequenceState("stop", "watching", ""), lifted=True,
                   mission=MissionProgress(count=5, current=1, state=MissionRunState.COMPLETE, flown=True),
                   setpoint=Setpoint(0.5, -0.5, 0.2, 0.1))
    status = convert.status_from_state(ms, state)
    back = convert.state_from_status(status, state.messages, state.results)
    assert back == state
    assert convert.status_from_state(ms, state, messages_since=4, results_since=7).messages == []


@pytest.mark.parametrize("roll,pitch,yaw", ANGLES)
def test_attitude_from_pose_quaternion_inverts_it(roll, pitch, yaw):
    *_, q0, q1, q2, q3 = convert.pose_enu(flying(attitude=Attitude(roll=roll, pitch=pitch, yaw=yaw)))
    r, p, y = convert.attitude_from_enu_quaternion(q0, q1, q2, q3)
    assert (r, p) == pytest.approx((roll, pitch), abs=1e-9)
    assert math.remainder(y - yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)


def test_state_from_jderobot_pose_and_navdata():
    jderobot, _ = load_slice()
    truth = flying(attitude=Attitude(yaw=math.pi / 2), velocity=Velocity(1.0, 0.0, -0.5),
                   battery=Battery(remaining=64.0))
    pose = jderobot.Pose3DData(*convert.pose_enu(truth))
    nav = jderobot.NavdataData(**convert.navdata_fields(truth))
    s = convert.state_from_jderobot(pose, nav)
    assert (s.local.north, s.local.east, s.altitude) == pytest.approx((4.0, -2.0, 3.0))
    assert (s.velocity.north, s.velocity.east, s.velocity.down) == pytest.approx((1.0, 0.0, -0.5), abs=1e-6)
    assert s.armed and s.flying and s.mode == "GUIDED" and s.battery.remaining == 64.0
    landed = convert.state_from_jderobot(pose, jderobot.NavdataData(**convert.navdata_fields(
        flying(armed=False, landed_state=LandedState.ON_GROUND))))
    assert not landed.armed and landed.landed_state is LandedState.ON_GROUND
    unknown = convert.state_from_jderobot(jderobot.Pose3DData(0, 0, 0, 1, 0, 0, 0, 0), None)
    assert unknown.attitude == Attitude() and unknown.connected
