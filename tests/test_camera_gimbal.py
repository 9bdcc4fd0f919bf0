"""Issue 23, the driver against the simulated vehicle: each gimbal, ROI and camera command, and each
confirmation, flown end to end over real sockets (docs/camera.md).

The simulated mount follows tests/data/recordings/arducopter-4.6-sitl-gimbal (ArduCopter 4.6.3, servo mount) and
the ``solo`` profile 3DR's ArduCopter 3.3 (MOUNT_CONTROL, MOUNT_STATUS, the GoPro on component 154).
"""
from __future__ import annotations

import io
import math

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.console.console import Console
from driver.payload import CameraKind, GimbalControl
from driver.vehicle.state import CommandStatus

from ice_fixtures import eventually


def pitch_near(value: float, tolerance: float = 1.0):
    return lambda s: s.gimbal.pitch_deg is not None and abs(s.gimbal.pitch_deg - value) <= tolerance


@pytest.fixture
def connected(sim_factory, vehicle_factory):
    def make(**sim_options):
        sim = sim_factory(**sim_options)
        vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
        assert vehicle.state().gimbal.pitch_deg is None            # unknown until the vehicle says
        assert vehicle.wait_for(lambda s: s.connected and s.gimbal.known, 15), vehicle.state().gimbal
        return sim, vehicle
    return make


def test_gimbal_by_angle_by_rate_and_level_with_the_gimbal_manager(connected):
    sim, vehicle = connected()
    s = vehicle.state()
    assert s.gimbal.source == "GIMBAL_DEVICE_ATTITUDE_STATUS" and s.gimbal.component == 1
    assert s.gimbal.pitch_deg == pytest.approx(-90.0, abs=0.1)        # RC targeting's -90, as recorded

    result = vehicle.point_gimbal(-45).result(10)
    assert result.status is CommandStatus.ACCEPTED, str(result)
    assert result.command == "gimbal pitch -45° (DO_GIMBAL_MANAGER_PITCHYAW)"
    s = vehicle.wait_for(pitch_near(-45), 10)
    assert s is not None, vehicle.state().gimbal
    assert s.gimbal.control is GimbalControl.ANGLE and s.gimbal.protocol == "gimbal manager"
    assert sim.autopilot.mount_pitch == pytest.approx(-45.0, abs=0.5)

    result = vehicle.gimbal_rate(20).result(10)                        # up at 20 deg/s: stepped angles, no NaN
    assert result.status is CommandStatus.ACCEPTED, str(result)
    assert sim.autopilot.mount_rate is None                            # the vehicle is sent angles only
    s = vehicle.wait_for(lambda s: s.gimbal.pitch_deg > -30, 10)
    assert s is not None and s.gimbal.control is GimbalControl.RATE, vehicle.state().gimbal

    result = vehicle.point_gimbal(0).result(10)                        # "level"
    assert result.ok, str(result)
    assert vehicle.wait_for(pitch_near(0), 10), vehicle.state().gimbal
    assert sim.autopilot.mount_rate is None
    # nothing the pilot asks leaves the mount's range
    assert vehicle.point_gimbal(-400).result(10).ok
    assert vehicle.wait_for(pitch_near(-90), 10), vehicle.state().gimbal
    assert vehicle.point_gimbal(float("nan")).result(1).status is CommandStatus.REJECTED


def test_look_at_a_point_and_stop_looking(connected):
    sim, vehicle = connected()
    assert vehicle.point_gimbal(0).result(10).ok
    home_lat, home_lon = sim.autopilot.home_lat, sim.autopilot.home_lon
    result = vehicle.look_at(home_lat + 0.0002, home_lon).result(10)    # 22 m north, on the ground
    assert result.status is CommandStatus.ACCEPTED, str(result)
    assert sim.autopilot.mount_mode == mavlink.MAV_MOUNT_MODE_GPS_POINT
    s = vehicle.state()
    assert s.gimbal.control is GimbalControl.ROI and s.gimbal.roi[:2] == (home_lat + 0.0002, home_lon)

    result = vehicle.stop_looking().result(10)
    assert result.status is CommandStatus.ACCEPTED, str(result)
    # back to the mount's default (RC targeting): pitch -90 again, as the recording at 95.5 s
    s = vehicle.wait_for(pitch_near(-90), 10)
    assert s is not None and s.gimbal.control is GimbalControl.RC and s.gimbal.roi is None, vehicle.state().gimbal


def test_a_trigger_with_no_camera_is_never_counted(connected):
    """The recording: DO_DIGICAM_CONTROL ACCEPTED with no camera configured. An ACK is not a picture."""
    sim, vehicle = connected()
    result = vehicle.take_photo().result(15)
    assert result.status is CommandStatus.TIMED_OUT, str(result)
    assert "no camera confirmed a picture" in result.reason
    assert any(r.command == "DO_DIGICAM_CONTROL shoot" and r.status is CommandStatus.ACCEPTED
               for r in vehicle.state().results)                      # the vehicle did ACK it
    assert vehicle.state().camera.photos == 0
    result = vehicle.record_video(True).result(5)
    assert result.status is CommandStatus.REJECTED and "records video" in result.reason, str(result)


def test_a_trigger_camera_is_confirmed_by_camera_feedback(connected):
    sim, vehicle = connected(camera="trigger")
    result = vehicle.take_photo().result(15)
    assert result.status is CommandStatus.ACCEPTED, str(result)
    assert "CAMERA_FEEDBACK" in result.reason
    s = vehicle.state()
    assert s.camera.photos == 1 == sim.autopilot.images and s.camera.kind is CameraKind.UNKNOWN
    assert s.camera.last_photo_at == pytest.approx((sim.autopilot.home_lat, sim.autopilot.home_lon), abs=1e-5)


def test_a_mavlink_camera_takes_pictures_and_video_with_the_camera_protocol(connected):
    sim, vehicle = connected(camera=True)
    s = vehicle.wait_for(lambda s: s.camera.kind is CameraKind.MAVLINK, 10)
    assert s is not None and s.camera.can_record and s.camera.name == "UavViewer SimCam", vehicle.state().camera
    result = vehicle.take_photo().result(15)
    assert result.status is CommandStatus.ACCEPTED and "CAMERA_IMAGE_CAPTURED" in result.reason, str(result)
    assert any(r.command == "IMAGE_START_CAPTURE" for r in vehicle.state().results)
    assert vehicle.state().camera.photos == 1 == sim.autopilot.images      # FEEDBACK too, counted once

    result = vehicle.record_video(True).result(15)
    assert result.status is CommandStatus.ACCEPTED and "CAMERA_CAPTURE_STATUS" in result.reason, str(result)
    assert sim.autopilot.video and vehicle.state().camera.recording is True
    result = vehicle.record_video(False).result(15)
    assert result.ok and not sim.autopilot.video and vehicle.state().camera.recording is False, str(result)


def test_solo_gimbal_and_gopro_the_way_3dr_pointed_them(connected):
    """ArduCopter 3.3 (3DR's fork): no mount command in COMMAND_LONG; MOUNT_CONTROL confirmed by MOUNT_STATUS,
    a rate stepped as angles, ROI by DO_SET_ROI, the GoPro through GOPRO_SET_REQUEST to component 154."""
    sim, vehicle = connected(profile="solo")
    s = vehicle.state()
    assert s.gimbal.source == "MOUNT_STATUS" and s.gimbal.pitch_deg == pytest.approx(-90.0), s.gimbal

    result = vehicle.point_gimbal(-30).result(10)
    assert result.status is CommandStatus.ACCEPTED and "MOUNT_STATUS shows -30" in result.reason, str(result)
    assert s.firmware == "3.3.1" and vehicle.state().gimbal.protocol == "MOUNT_CONTROL"
    assert sim.autopilot.mount_mode == mavlink.MAV_MOUNT_MODE_MAVLINK_TARGETING

    assert vehicle.gimbal_rate(-20).result(5).ok                        # tilting down, stepped at 10 Hz
    assert vehicle.wait_for(lambda s: s.gimbal.pitch_deg < -40, 10), vehicle.state().gimbal
    assert vehicle.gimbal_rate(0).result(5).ok

    result = vehicle.look_at(sim.autopilot.home_lat + 0.0002, sim.autopilot.home_lon).result(10)
    assert result.ok and result.command.endswith("(DO_SET_ROI)"), str(result)
    assert sim.autopilot.mount_mode == mavlink.MAV_MOUNT_MODE_GPS_POINT
    assert vehicle.stop_looking().result(10).ok
    assert sim.autopilot.mount_roi is None and sim.autopilot.mount_mode == mavlink.MAV_MOUNT_MODE_RC_TARGETING

    s = vehicle.wait_for(lambda s: s.camera.kind is CameraKind.GOPRO, 10)
    assert s is not None and s.camera.component == 154 and s.camera.status == "connected", vehicle.state().camera
    result = vehicle.take_photo().result(15)                           # video mode at power-on: photo first
    assert result.status is CommandStatus.ACCEPTED and "GoPro" in result.reason, str(result)
    assert sim.autopilot.gopro_mode == mavlink.GOPRO_CAPTURE_MODE_PHOTO and sim.autopilot.images == 1
    result = vehicle.record_video(True).result(15)
    assert result.status is CommandStatus.ACCEPTED and "heartbeat" in result.reason, str(result)
    assert sim.autopilot.gopro_recording and vehicle.state().camera.recording is True
    assert vehicle.record_video(False).result(15).ok and not sim.autopilot.gopro_recording


def test_console_verbs(connected):
    sim, vehicle = connected(camera=True)
    out = io.StringIO()
    console = Console(vehicle, stdout=out)
    lat, lon = sim.autopilot.home_lat + 0.0002, sim.autopilot.home_lon
    for line, expected in (("gimbal pitch -30", "gimbal pitch -30°"), ("gimbal rate 10", "gimbal rate +10°/s"),
                           ("gimbal level", "gimbal pitch 0°"), (f"roi {lat} {lon}", "look at"),
                           ("roi none", "stop looking"), ("camera shoot", "photo: accepted"),
                           ("camera record on", "record on: accepted"), ("camera record off", "record off: accepted")):
        console.onecmd(line)
        assert eventually(lambda: expected in out.getvalue(), 15), (line, out.getvalue())
    console.onecmd("gimbal")
    assert eventually(lambda: "1 pictures, not recording" in out.getvalue(), 5), out.getvalue()
    console.onecmd("gimbal sideways")
    assert "usage: gimbal pitch DEG" in out.getvalue()


def test_flying_the_nose_turns_to_the_point_of_interest(sim, flying):
    """The recorded mount has no yaw axis: ArduCopter's auto_yaw ROI mode turns the vehicle to face the point,
    and the gimbal pitches down to it."""
    s = flying.state()
    east_point = (sim.autopilot.home_lat, sim.autopilot.home_lon + 30 / sim.autopilot.m_per_deg_lon)   # 30 m east
    assert flying.look_at(*east_point).result(10).ok
    assert flying.wait_for(lambda s: abs(s.heading_deg - 90.0) < 5.0, 20), flying.state().heading_deg
    expected = -math.degrees(math.atan2(s.altitude, 30.0 - s.local.east))
    assert flying.wait_for(lambda s: s.gimbal.pitch_deg is not None and abs(s.gimbal.pitch_deg - expected) < 2, 10)
    assert flying.stop_looking().result(10).ok and not sim.autopilot.roi_yaw
