"""The camera on the vehicle over Ice (issue 23): the Vehicle extension's payload operations, the gimbal in the
status the client shows, and a picture confirmed by the vehicle's camera, through a real MAVLinkServer."""
from __future__ import annotations

import pytest

from driver.payload import CameraKind, GimbalControl
from driver.vehicle.state import CommandStatus

from ice_fixtures import drone_factory, server_factory  # noqa: F401  (fixtures)


@pytest.fixture
def camera_vehicle(sim_factory, vehicle_factory):
    sim = sim_factory(camera=True)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.connected and s.gimbal.known and s.camera.kind is CameraKind.MAVLINK, 15)
    return sim, vehicle


def test_gimbal_roi_and_photo_through_the_mavlinkserver(camera_vehicle, server_factory, drone_factory):
    sim, vehicle = camera_vehicle
    drone = drone_factory(server_factory(vehicle))
    s = drone.wait_for(lambda s: s.connected and s.gimbal.known, 10)
    assert s is not None and s.gimbal.pitch_deg == pytest.approx(-90.0, abs=0.1), drone.state().gimbal
    assert s.camera.kind is CameraKind.MAVLINK and s.camera.name == "UavViewer SimCam"

    result = drone.point_gimbal(-45).result(10)
    assert result.status is CommandStatus.ACCEPTED and result.command.startswith("gimbal pitch -45"), str(result)
    s = drone.wait_for(lambda s: s.gimbal.pitch_deg is not None and abs(s.gimbal.pitch_deg + 45) < 1, 10)
    assert s is not None and s.gimbal.control is GimbalControl.ANGLE and s.gimbal.protocol == "gimbal manager"
    assert sim.autopilot.mount_pitch == pytest.approx(-45.0, abs=0.5)

    assert drone.gimbal_rate(10).result(10).ok                          # stepped angles: the mount climbs
    assert drone.wait_for(lambda s: s.gimbal.pitch_deg is not None and s.gimbal.pitch_deg > -40, 10)
    lat, lon = sim.autopilot.home_lat + 0.0002, sim.autopilot.home_lon
    assert drone.look_at(lat, lon).result(10).ok
    assert drone.wait_for(lambda s: s.gimbal.roi is not None, 10).gimbal.roi[:2] == (lat, lon)
    assert drone.stop_looking().result(10).ok
    assert drone.wait_for(lambda s: s.gimbal.roi is None and s.gimbal.control is GimbalControl.RC, 10)

    result = drone.take_photo().result(15)
    assert result.status is CommandStatus.ACCEPTED and "CAMERA_IMAGE_CAPTURED" in result.reason, str(result)
    assert drone.wait_for(lambda s: s.camera.photos == 1, 10)
    assert drone.record_video(True).result(15).ok and drone.wait_for(lambda s: s.camera.recording is True, 10)
    assert drone.record_video(False).result(15).ok
    assert drone.point_gimbal(float("inf")).result(1).status is CommandStatus.REJECTED
