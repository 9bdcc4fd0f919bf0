"""IceDrone: the Drone interface over Ice, against the real server, driver and simulated vehicle."""
from __future__ import annotations

import math

import pytest

from driver.ice.client import IceDrone, viewer_properties
from driver.vehicle.state import CommandStatus, LinkStatus

from ice_fixtures import (drone_factory, eventually, free_port, ice_server, jde, communicator,  # noqa: F401
                              server_factory)


def test_ice_drone_takes_off_flies_and_lands(vehicle, ice_server, drone_factory):
    drone = drone_factory(ice_server)
    assert drone.description == "Ice 127.0.0.1"
    s = drone.wait_for(lambda s: s.connected and s.mode, 10)
    assert s is not None and s.mode == vehicle.state().mode and s.system_id == 1
    assert drone.limits == vehicle.limits

    result = drone.takeoff(3.0).result(timeout=60)
    assert result.ok and result.command == "takeoff", str(result)
    assert drone.wait_for(lambda s: s.flying and s.altitude > 2.7, 5)

    assert drone.wait_for(lambda s: s.velocity.ground_speed < 0.3, 15)
    start, heading = drone.state().local, drone.state().attitude.yaw

    def moved():
        drone.set_velocity(1.5, 0.0, 0.0, 0.0)          # as the viewer re-sends a held stick
        here = drone.state().local
        dn, de = here.north - start.north, here.east - start.east
        along = abs(math.remainder(math.atan2(de, dn) - heading, 2 * math.pi)) < math.radians(30)
        return math.hypot(dn, de) > 2.0 and along
    assert eventually(moved, 20, interval=0.1)
    assert drone.state().setpoint.forward == pytest.approx(1.5)
    assert drone.wait_for(lambda s: s.setpoint.is_zero, 5)          # stopped calling: the deadman

    result = drone.land().result(timeout=10)
    assert result.ok, str(result)
    assert drone.wait_for(lambda s: not s.armed, 60)
    assert any(r.command.startswith("takeoff") for r in drone.state().results)


def test_commands_answer_with_the_vehicles_reason(vehicle, ice_server, drone_factory):
    drone = drone_factory(ice_server)
    assert drone.wait_for(lambda s: s.connected and s.mode, 10)
    unknown = drone.set_mode("NOSUCH").result(timeout=10)
    assert unknown.status is CommandStatus.REJECTED and "unknown mode" in unknown.reason
    grounded = drone.go_to(5.0, 5.0, 3.0).result(timeout=10)
    assert grounded.status is CommandStatus.REJECTED and "flying" in grounded.reason
    yaw = drone.set_yaw(float("nan")).result(timeout=10)
    assert yaw.status is CommandStatus.REJECTED
    # the Future's answer and the snapshot's result are the same entry (the window pairs them by index)
    assert unknown.index > 0
    assert drone.wait_for(lambda s: any(r.index == unknown.index and r.command.startswith("mode NOSUCH")
                                        for r in s.results), 5)
    server_lines = {m.text for m in vehicle.state().messages}       # the server's messages reach the client
    assert server_lines and drone.wait_for(lambda s: server_lines <= {m.text for m in s.messages}, 10)
    indices = [m.index for m in drone.state().messages]
    assert indices == sorted(set(indices))


def test_bad_velocity_refused_before_the_wire(vehicle, ice_server, drone_factory):
    drone = drone_factory(ice_server)
    assert not drone.set_velocity(float("nan"), 0, 0, 0)
    assert not drone.set_velocity(0, 0, float("inf"), 0)
    assert drone.wait_for(lambda s: s.connected, 10)
    assert drone.set_velocity(50.0, -0.5, 0.2, 0.1)               # clamped to the server's limits
    assert eventually(lambda: vehicle.state().setpoint.forward == pytest.approx(vehicle.limits.horizontal), 5)
    sp = vehicle.state().setpoint
    assert (sp.right, sp.up, sp.yaw_rate) == pytest.approx((-0.5, 0.2, 0.1))


def test_lost_server_shows_as_lost_link_and_recovers(vehicle, server_factory, drone_factory):
    port = free_port()
    server = server_factory(vehicle, port=port)
    drone = drone_factory(server, loss_timeout=1.0)
    assert drone.wait_for(lambda s: s.connected, 10)
    server.close()
    lost = drone.wait_for(lambda s: s.link.status is LinkStatus.LOST, 10)
    assert lost is not None and lost.link.lost_count >= 1
    assert any("lost the server" in m.text for m in lost.messages)
    failed = drone.arm().result(timeout=15)
    assert failed.status in (CommandStatus.REJECTED, CommandStatus.TIMED_OUT) and "server" in failed.reason

    server_factory(vehicle, port=port)                            # the server comes back on the same port
    back = drone.wait_for(lambda s: s.link.status is LinkStatus.OK, 15)
    assert back is not None and back.link.lost_count >= 1
    assert any("answering again" in m.text for m in back.messages)
    indices = [m.index for m in back.messages]
    assert indices == sorted(set(indices))


def test_server_never_reached_stays_waiting_and_says_why():
    port = free_port()                                            # nothing listens there
    props = viewer_properties()
    for name in ("Vehicle", "CMDVel"):
        props.setProperty(f"UAVViewer.{name}.Proxy", f"{name}:tcp -h 127.0.0.1 -p {port}")
    drone = IceDrone(props, loss_timeout=0.5).start()
    try:
        s = drone.wait_for(lambda s: s.messages, 10)
    finally:
        drone.close()
    assert drone.state().link.status is LinkStatus.CLOSED
    assert s is not None and s.link.status is LinkStatus.WAITING
    assert "not answering" in s.messages[-1].text


def test_takeoff_altitude_setting(vehicle, jde):
    ext = jde.Vehicle
    assert ext.getTakeoffAltitude() == pytest.approx(3.0)
    assert ext.setTakeoffAltitude(4.5) == 0 and ext.getTakeoffAltitude() == pytest.approx(4.5)
    assert ext.setTakeoffAltitude(float("nan")) != 0 and ext.setTakeoffAltitude(1e6) != 0
    assert ext.getTakeoffAltitude() == pytest.approx(4.5)
    assert ext.getDescription() == vehicle.description


def test_plain_jderobot_server_without_extension(vehicle, ice_server, drone_factory):
    """Only JdeRobot's keys configured (a 2017 viewer.cfg): state from Pose3D/Navdata, commands through Extra."""
    props = viewer_properties()
    for name in ("Pose3D", "CMDVel", "Navdata", "Extra", "WP"):
        props.setProperty(f"UAVViewer.{name}.Proxy", ice_server.proxy(name))
    drone = IceDrone(props).start()
    try:
        assert drone.wait_for(lambda s: s.connected and not s.flying, 10)
        refused = drone.arm().result(timeout=5)
        assert refused.status is CommandStatus.REJECTED and "no mavlinkserver extension" in refused.reason
        sent = drone.takeoff().result(timeout=10)
        assert sent.status is CommandStatus.ACCEPTED and "Extra" in sent.reason
        assert drone.wait_for(lambda s: s.can_fly_velocity and s.altitude > 2.7, 60)
        assert drone.wait_for(lambda s: s.velocity.ground_speed < 0.3, 15)
        s, truth = drone.state(), vehicle.state()
        assert abs(math.remainder(s.attitude.yaw - truth.attitude.yaw, 2 * math.pi)) < math.radians(3)
        assert (s.local.north, s.local.east) == pytest.approx((truth.local.north, truth.local.east), abs=0.3)
        start, heading = s.local, s.attitude.yaw

        def moved():
            drone.set_velocity(1.5, 0.0, 0.0, 0.0)
            here = drone.state().local
            dn, de = here.north - start.north, here.east - start.east
            return math.hypot(dn, de) > 2.0 and abs(math.remainder(math.atan2(de, dn) - heading,
                                                                   2 * math.pi)) < math.radians(30)
        assert eventually(moved, 20, interval=0.1)
        v, truth_v = drone.state().velocity, vehicle.state().velocity
        assert (v.north, v.east) == pytest.approx((truth_v.north, truth_v.east), abs=0.4)   # Navdata, body axes
        assert drone.land().result(timeout=10).ok
        assert drone.wait_for(lambda s: not s.flying and s.altitude < 0.3, 60)     # Navdata: landed
        assert vehicle.wait_for(lambda s: not s.armed, 30)
    finally:
        drone.close()


def test_viewer_clamps_from_jderobot_keys(vehicle, ice_server):
    props = viewer_properties()
    for key, value in ice_server.client_properties().items():
        props.setProperty(key, value)
    props.setProperty("UAVViewer.CMDVel.Xmax", "0.5")
    props.setProperty("UAVViewer.CMDVel.Yawmax", "0.2")
    drone = IceDrone(props).start()
    try:
        assert drone.wait_for(lambda s: s.connected, 10)
        assert eventually(lambda: drone.limits.horizontal == 0.5, 5)
        assert drone.limits.yaw_rate == 0.2 and drone.limits.vertical == vehicle.limits.vertical
        assert drone.set_velocity(2.0, 0.0, 0.0, -1.0)
        assert eventually(lambda: vehicle.state().setpoint.forward == pytest.approx(0.5), 5)
        assert vehicle.state().setpoint.yaw_rate == pytest.approx(-0.2)
    finally:
        drone.close()


def test_an_operation_the_server_lacks_is_named_in_the_refusal(vehicle, server_factory):
    """A MAVLinkServer from before an operation existed answers OperationNotExist: the pilot reads which operation
    it lacks ("startMission"), not a guess ("has no missions") that is wrong for arm or takeoff."""
    server = server_factory(vehicle)
    props = viewer_properties()
    for key, value in server.client_properties().items():
        props.setProperty(key, value)
    # the Vehicle interface's calls reach an object that has none of them, as an older server's would
    props.setProperty("UAVViewer.Vehicle.Proxy", server.client_properties()["UAVViewer.Pose3D.Proxy"])
    drone = IceDrone(props).start()
    try:
        result = drone.start_mission().result(timeout=10)
        assert result.status is CommandStatus.REJECTED and "startMission" in result.reason, result
        assert "missions" not in result.reason, result
    finally:
        drone.close()
