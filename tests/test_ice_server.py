"""The MAVLinkServer's JdeRobot interfaces, flown through real Ice proxies against the simulated ArduCopter."""
from __future__ import annotations

import json
import logging
import math
import os
import subprocess
import sys
import textwrap
import time

import Ice
import pytest

from driver.ice import SLICE_DIR, convert, slice_files
from driver.ice.server import DEFAULT_PORTS, default_properties, default_record_dir, planned_endpoints
from driver.vehicle.state import CommandStatus

from ice_fixtures import (communicator, eventually, free_port, ice_server, jde, jderobot,  # noqa: F401
                              mavlinkserver, server_factory)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def enu_yaw(pose) -> float:
    """JdeRobot's own formula."""
    q0, q1, q2, q3 = pose.q0, pose.q1, pose.q2, pose.q3
    return math.atan2(2 * (q1 * q2 + q0 * q3), q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3)


def angle_between(a: float, b: float) -> float:
    return abs(math.remainder(a - b, 2 * math.pi))


def fly(cmdvel, command, until, timeout: float = 20.0) -> bool:
    """Send ``command`` at 10 Hz (as a viewer holding a stick) until ``until()`` holds; then zero."""
    deadline = time.monotonic() + timeout
    try:
        while time.monotonic() < deadline:
            assert cmdvel.setCMDVelData(command) == 0
            if until():
                return True
            time.sleep(0.1)
        return False
    finally:
        cmdvel.setCMDVelData(jderobot.CMDVelData(0, 0, 0, 0, 0, 0))


# -- configuration ----------------------------------------------------------------------------
def test_default_identities_and_ports_are_the_2017_servers():
    plan = planned_endpoints(default_properties([]))
    assert plan == {name: (name, f"default -h 127.0.0.1 -p {port}") for name, port in DEFAULT_PORTS.items()}
    assert (plan["Camera"][1], plan["Pose3D"][1], plan["CMDVel"][1], plan["Navdata"][1], plan["Extra"][1],
            plan["WP"][1]) == tuple(f"default -h 127.0.0.1 -p {p}" for p in (9999, 9998, 9997, 9996, 9995, 9994))
    shipped = planned_endpoints(default_properties([f"--Ice.Config={ROOT}/config/server.cfg"]))
    assert shipped == plan
    one = planned_endpoints(default_properties(["--MAVLinkServer.Endpoints=default -h 127.0.0.1 -p 9000",
                                                "--MAVLinkServer.WP.Name=waypoint"]))
    assert set(e for _, e in one.values()) == {"default -h 127.0.0.1 -p 9000"}
    assert one["WP"][0] == "waypoint"


def test_viewer_config_names_every_interface_with_jderobot_keys():
    props = Ice.createProperties()
    props.load(os.path.join(ROOT, "config", "viewer.cfg"))
    for name, port in DEFAULT_PORTS.items():
        assert props.getProperty(f"UAVViewer.{name}.Proxy") == f"{name}:default -h 127.0.0.1 -p {port}"


def test_each_interface_on_its_own_port(vehicle, server_factory, communicator):
    ports = {name: free_port() for name in DEFAULT_PORTS}
    server = server_factory(vehicle, port=None, **{f"MAVLinkServer.{n}.Endpoints": f"tcp -h 127.0.0.1 -p {p}"
                                                   for n, p in ports.items()})
    type_ids = {"Camera": "::jderobot::Camera", "Pose3D": "::jderobot::Pose3D", "CMDVel": "::jderobot::CMDVel",
                "Navdata": "::jderobot::Navdata", "Extra": "::jderobot::ArDroneExtra", "WP": "::jderobot::Pose3D",
                "Vehicle": "::mavlinkserver::Vehicle", "Shots": "::mavlinkserver::Shots"}
    for name, port in ports.items():
        prx = communicator.stringToProxy(f"{name}:tcp -h 127.0.0.1 -p {port}")
        assert prx.ice_isA(type_ids[name]), name
        assert f"-p {port}" in server.proxy(name)


# -- flight -----------------------------------------------------------------------------------
def test_extra_takeoff_reset_flattrim_and_land(vehicle, sim, jde, caplog):
    caplog.set_level(logging.INFO, logger="driver.ice")
    extra, pose3d, navdata = jde.Extra, jde.Pose3D, jde.Navdata
    assert vehicle.wait_for(lambda s: s.in_air is False, 10)
    extra.takeoff()                                     # returns at once; the sequence runs in the driver
    assert sim.truth().altitude < 0.2 and not sim.truth().armed, sim.truth()    # returned before anything flew
    assert vehicle.state().takeoff.active
    assert eventually(lambda: navdata.getNavdata().state == convert.NAV_TAKING_OFF
                      or pose3d.getPose3DData().z > 2.0, 30)
    assert eventually(lambda: pose3d.getPose3DData().z > 2.8 and not vehicle.state().takeoff.active, 60)
    assert eventually(lambda: navdata.getNavdata().state in (convert.NAV_HOVERING, convert.NAV_FLYING), 10)

    extra.flatTrim()                                    # flying: refused, logged
    assert eventually(lambda: "flatTrim refused" in caplog.text, 5)
    assert not any(r.command == "level calibration" for r in vehicle.state().results)

    count = len(vehicle.state().results)
    extra.reset()                                       # stop and hold
    assert eventually(lambda: any(r.command == "stop" and r.ok for r in vehicle.state().results[count - 1:]), 10)

    extra.land()
    assert eventually(lambda: navdata.getNavdata().state == convert.NAV_LANDING, 20)
    assert eventually(lambda: not vehicle.state().armed and navdata.getNavdata().state == convert.NAV_LANDED, 60)
    assert pose3d.getPose3DData().z < 0.3


def test_cmdvel_moves_forward_left_up_and_turns(flying, jde):
    cmdvel, pose3d, navdata = jde.CMDVel, jde.Pose3D, jde.Navdata

    def settled():
        assert eventually(lambda: navdata.getNavdata().state == convert.NAV_HOVERING, 15)
        return pose3d.getPose3DData()

    start = settled()
    heading = enu_yaw(start)

    def moved_towards(p0, direction: float, distance: float):
        def check():
            p = pose3d.getPose3DData()
            dx, dy = p.x - p0.x, p.y - p0.y
            return math.hypot(dx, dy) >= distance and angle_between(math.atan2(dy, dx), direction) < math.radians(30)
        return check

    # forward: along the heading (ENU yaw), not north/east
    assert fly(cmdvel, jderobot.CMDVelData(1.5, 0, 0, 0, 0, 0), moved_towards(start, heading, 2.0))
    assert angle_between(enu_yaw(pose3d.getPose3DData()), heading) < math.radians(10)
    # left: a quarter turn counter-clockwise from the heading
    p1 = settled()
    assert fly(cmdvel, jderobot.CMDVelData(0, 1.5, 0, 0, 0, 0), moved_towards(p1, heading + math.pi / 2, 2.0))
    # up
    p2 = settled()
    assert fly(cmdvel, jderobot.CMDVelData(0, 0, 0.8, 0, 0, 0), lambda: pose3d.getPose3DData().z > p2.z + 1.0)
    p3 = settled()
    assert math.hypot(p3.x - p2.x, p3.y - p2.y) < 0.5
    # yaw: angularZ positive turns counter-clockwise (ENU yaw grows, compass heading falls)
    yaw0, heading0 = enu_yaw(p3), flying.state().heading_deg
    assert fly(cmdvel, jderobot.CMDVelData(0, 0, 0, 0, 0, 0.5),
               lambda: math.remainder(enu_yaw(pose3d.getPose3DData()) - yaw0, 2 * math.pi) > math.radians(30))
    assert math.remainder(flying.state().heading_deg - heading0, 360.0) < -20.0
    # and the deadman: calls stopped, the setpoint falls to zero by itself
    cmdvel.setCMDVelData(jderobot.CMDVelData(1.0, 0, 0, 0, 0, 0))
    assert flying.wait_for(lambda s: s.setpoint.is_zero, 5)


def test_waypoint_flies_to_enu_position(flying, jde):
    wp, pose3d = jde.WP, jde.Pose3D
    p0 = pose3d.getPose3DData()
    target = (p0.x + 4.0, p0.y - 3.0, 4.0)
    assert wp.setPose3DData(jderobot.Pose3DData(*target, 1.0, 1.0, 0.0, 0.0, 0.0)) == 0

    def arrived():
        p = pose3d.getPose3DData()
        return math.dist((p.x, p.y, p.z), target) < 0.6
    assert eventually(arrived, 40)
    s = flying.state()
    assert s.local.east == pytest.approx(target[0], abs=0.6) and s.local.north == pytest.approx(target[1], abs=0.6)
    assert pose3d.setPose3DData(jderobot.Pose3DData(float("nan"), 0, 3, 1, 1, 0, 0, 0)) != 0


def test_pose_and_navdata_match_the_vehicle(flying, jde):
    # every value the autopilot sends is carried: wait until the vehicle has sent each one
    assert flying.wait_for(lambda s: None not in (s.environment.pressure_hpa, s.environment.mag,
                                                  s.environment.accel_g, s.environment.wind_speed), 15), \
        flying.state().environment
    assert eventually(lambda: jde.Navdata.getNavdata().state == convert.NAV_HOVERING, 15)   # settled
    pose, nav = jde.Pose3D.getPose3DData(), jde.Navdata.getNavdata()
    s = flying.state()
    assert (pose.x, pose.y, pose.z) == pytest.approx((s.local.east, s.local.north, s.altitude), abs=0.3)
    assert pose.h == 1.0
    assert angle_between(enu_yaw(pose), math.pi / 2 - s.attitude.yaw) < math.radians(3)
    assert nav.vehicle == 1 and nav.state == convert.NAV_HOVERING
    assert nav.altd == pytest.approx(s.altitude * 1000, abs=300)
    assert s.battery.remaining is not None and nav.batteryPercent == pytest.approx(s.battery.remaining, abs=1)
    assert angle_between(math.radians(nav.rotZ), math.pi / 2 - s.attitude.yaw) < math.radians(3)
    assert nav.rotX == pytest.approx(math.degrees(s.attitude.roll), abs=2)
    assert abs(nav.vx) < 300 and abs(nav.vy) < 300 and abs(nav.vz) < 300
    env = s.environment
    assert nav.pressure == pytest.approx(env.pressure_hpa * 100, rel=0.01)          # Pa
    assert (nav.magX, nav.magY, nav.magZ) == pytest.approx(env.mag, abs=20) and env.mag != (0, 0, 0)
    assert nav.az == pytest.approx(1.0, abs=0.2)                                     # hovering: 1 g up (FLU)
    assert nav.windSpeed == pytest.approx(env.wind_speed, abs=0.5)
    assert (nav.tagsCount, list(nav.tagsType), list(nav.tagsDistance)) == (0, [], [])


# -- refusals and answers ---------------------------------------------------------------------
def test_cmdvel_refuses_nan_and_huge_and_clamps_the_rest(vehicle, jde):
    cmdvel = jde.CMDVel
    for bad in ((float("nan"), 0, 0, 0, 0, 0), (0, 0, float("inf"), 0, 0, 0), (0, 0, 0, 0, 0, float("-inf")),
                (1e9, 0, 0, 0, 0, 0), (0, -5e6, 0, 0, 0, 0), (0, 0, 0, 0, 0, 3e4)):
        assert cmdvel.setCMDVelData(jderobot.CMDVelData(*bad)) != 0, bad
        assert vehicle.state().setpoint.is_zero, bad
    assert cmdvel.setCMDVelData(jderobot.CMDVelData(9.0, 1.0, -0.5, 0, 0, 0.3)) == 0
    sp = vehicle.state().setpoint
    lim = vehicle.limits
    assert (sp.forward, sp.right, sp.up, sp.yaw_rate) == pytest.approx((lim.horizontal, -1.0, -0.5, -0.3))


def test_every_extra_operation_answers_on_the_ground(vehicle, sim, jde, caplog):
    caplog.set_level(logging.INFO, logger="driver.ice")
    extra = jde.Extra
    assert vehicle.wait_for(lambda s: s.readiness.ready_to_arm, 15)
    # the operations return nothing: each is seen by what it did (this server has no camera)
    for call, said in ((extra.toggleCam, "Extra.toggleCam: no camera configured; nothing to switch"),
                       (lambda: extra.recordOnUsb(True), "Extra.recordOnUsb(True): no camera to record"),
                       (lambda: extra.recordOnUsb(False), "Extra.recordOnUsb(False): no camera to record"),
                       (lambda: extra.ledAnimation(3, 2.0, 1.0), "Extra.ledAnimation(3, 2.0, 1.0): not supported "
                                                                 "on ArduCopter"),
                       (lambda: extra.flightAnimation(1, 1.0), "Extra.flightAnimation(1, 1.0): not supported on "
                                                              "ArduCopter")):
        call()
        assert said in caplog.text, (said, caplog.text)
    # flatTrim disarmed on the ground reaches the vehicle as a level calibration, which it accepts (the
    # driver's own requests of the start-up, home and streams, are answered by now: none follows it)
    assert vehicle.wait_for(lambda s: s.home is not None, 15)
    extra.flatTrim()
    assert eventually(lambda: sim.truth().last_command == "MAV_CMD_PREFLIGHT_CALIBRATION", 10, interval=0.01), \
        sim.truth().last_command
    result = eventually(lambda: next((r for r in vehicle.state().results if r.command == "level calibration"
                                      and r.status is not CommandStatus.IN_PROGRESS), None), 15)
    assert result is not None and result.status is CommandStatus.ACCEPTED, result
    # reset is Stop: on the ground, nothing to stop, and the vehicle stays as it was
    extra.reset()
    stop = eventually(lambda: next((r for r in vehicle.state().results if r.command == "stop"), None), 10)
    assert stop is not None and stop.status is CommandStatus.ACCEPTED, stop
    assert not sim.truth().armed and sim.truth().mode == "STABILIZE"
    extra.land()
    assert eventually(lambda: sim.truth().mode == "LAND", 10), sim.truth()
    assert vehicle.wait_for(lambda s: s.mode == "LAND", 10)


def test_closing_the_server_answers_commands_still_waiting(vehicle_factory, server_factory, communicator):
    grounded = vehicle_factory(f"tcp:127.0.0.1:{free_port()}")      # no vehicle: a takeoff waits for it
    server = server_factory(grounded)
    ext = mavlinkserver.VehiclePrx.checkedCast(communicator.stringToProxy(server.proxy("Vehicle")))
    waiting = ext.takeoffAsync(3.0)
    assert eventually(lambda: grounded.state().takeoff.active, 5)
    server.close()                                      # must not wait for the vehicle's answer
    answer = waiting.result(10)
    assert (answer.command, answer.status, answer.reason) == ("takeoff", "ABORTED", "server shutting down")


def test_waypoint_on_the_ground_is_refused(vehicle, jde):
    assert vehicle.wait_for(lambda s: s.connected, 10)
    assert jde.WP.setPose3DData(jderobot.Pose3DData(3.0, 3.0, 3.0, 1.0, 1.0, 0.0, 0.0, 0.0)) != 0
    assert any(r.command.startswith("go to") and "flying" in r.reason for r in vehicle.state().results)


def test_camera_without_a_source_says_why(jde):
    with pytest.raises(jderobot.DataNotExistException) as raised:
        jde.Camera.getImageData("RGB8")
    assert "no camera source" in raised.value.what
    assert jde.Camera.getImageFormat() == []


def test_toggle_cam_with_one_camera_says_there_is_nothing_to_switch(vehicle, server_factory, communicator, caplog):
    caplog.set_level(logging.INFO, logger="driver")
    one = server_factory(vehicle, **{"MAVLinkServer.Camera.Uri": "sim"})
    extra = jderobot.ArDroneExtraPrx.checkedCast(communicator.stringToProxy(one.proxy("Extra")))
    source = one.camera.source
    extra.toggleCam()
    assert one.camera.source is source
    assert "only one camera configured; nothing to switch" in caplog.text
    caplog.clear()
    two = server_factory(vehicle, **{"MAVLinkServer.Camera.Uri": "sim", "MAVLinkServer.Camera.Uri.2": "sim"})
    extra = jderobot.ArDroneExtraPrx.checkedCast(communicator.stringToProxy(two.proxy("Extra")))
    source = two.camera.source
    extra.toggleCam()
    assert two.camera.source is not source
    assert "nothing to switch" not in caplog.text and "camera switched to sim" in caplog.text


def test_record_on_usb_defaults_to_the_per_user_data_folder(vehicle, server_factory, communicator, tmp_path,
                                                            monkeypatch):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    monkeypatch.setenv("APPDATA", str(tmp_path / "data"))
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    folder = default_record_dir()
    assert folder.endswith(os.path.join("UavViewerPy", "recordings")) and folder.startswith(str(tmp_path))
    if sys.platform.startswith("linux"):
        assert folder == str(tmp_path / "data" / "UavViewerPy" / "recordings")
    server = server_factory(vehicle, **{"MAVLinkServer.Camera.Uri": "sim"})
    extra = jderobot.ArDroneExtraPrx.checkedCast(communicator.stringToProxy(server.proxy("Extra")))
    assert eventually(lambda: server.camera.source.latest() is not None, 10)
    extra.recordOnUsb(True)
    def encoded() -> bool:                    # the name is reserved at once; video goes to a private work folder
        work = [os.path.join(folder, d) for d in os.listdir(folder) if d.startswith(".recording-")]
        return any(os.path.getsize(os.path.join(d, f)) > 0 for d in work for f in os.listdir(d))
    assert eventually(lambda: os.path.isdir(folder) and encoded(), 10)
    extra.recordOnUsb(False)
    files = os.listdir(folder)
    assert len(files) == 1 and files[0].endswith(".mp4") and os.path.getsize(os.path.join(folder, files[0])) > 0


# -- an unmodified JdeRobot client ------------------------------------------------------------
CLIENT = textwrap.dedent("""
    import json, sys
    sys.path.insert(0, sys.argv[1])
    import Ice, jderobot
    assert jderobot.__file__.startswith(sys.argv[1])
    com = Ice.initialize(sys.argv)
    props = com.getProperties()
    def prx(name, cast):
        return cast.checkedCast(com.propertyToProxy("UAVViewer." + name + ".Proxy"))
    pose = prx("Pose3D", jderobot.Pose3DPrx).getPose3DData()
    nav = prx("Navdata", jderobot.NavdataPrx).getNavdata()
    cmd = prx("CMDVel", jderobot.CMDVelPrx)
    answers = [cmd.setCMDVelData(jderobot.CMDVelData(0.5, 0.0, 0.0, 0.0, 0.0, 0.0)),
               cmd.setCMDVelData(jderobot.CMDVelData(float("nan"), 0.0, 0.0, 0.0, 0.0, 0.0))]
    extra = prx("Extra", jderobot.ArDroneExtraPrx)
    extra.ledAnimation(1, 1.0, 1.0)
    wp = prx("WP", jderobot.Pose3DPrx)
    try:
        prx("Camera", jderobot.CameraPrx).getImageData("RGB8")
        camera = "image"
    except jderobot.DataNotExistException as e:
        camera = e.what
    print(json.dumps(dict(pose=[pose.x, pose.y, pose.z, pose.h, pose.q0, pose.q1, pose.q2, pose.q3],
                          nav=dict(state=nav.state, altd=nav.altd, battery=nav.batteryPercent, rotZ=nav.rotZ,
                                   vehicle=nav.vehicle, tags=list(nav.tagsType)),
                          answers=answers, camera=camera, wp=wp.ice_id())))
    com.destroy()
""")


def test_client_generated_by_slice2py_from_jderobot_files_only(vehicle, sim, ice_server, tmp_path):
    assert vehicle.wait_for(lambda s: s.position is not None and s.home is not None, 15)   # telemetry flows
    jderobot_files = [f for f in slice_files(extension=False)]
    assert all("/jderobot/" in f for f in jderobot_files)
    generated = tmp_path / "generated"
    generated.mkdir()
    subprocess.run([os.path.join(os.path.dirname(sys.executable), "slice2py"), f"-I{SLICE_DIR}",
                    "--prefix", "jderobot_", "--output-dir", str(generated), *jderobot_files], check=True)
    assert not list(generated.glob("*mavlinkserver*"))
    script = tmp_path / "client.py"
    script.write_text(CLIENT)
    config = tmp_path / "viewer.cfg"                    # a JdeRobot-style config file
    config.write_text("".join(f"{k}={v}\n" for k, v in ice_server.client_properties().items()))
    done = subprocess.run([sys.executable, str(script), str(generated), f"--Ice.Config={config}"],
                          capture_output=True, text=True,
                          timeout=60, cwd=str(tmp_path))
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout)
    truth = sim.truth()                                 # on the ground at home, disarmed, still
    x, y, z, h, q0, q1, q2, q3 = out["pose"]
    assert (x, y, z, h) == pytest.approx((truth.east, truth.north, truth.altitude, 1.0), abs=0.05)   # ENU
    assert q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3 == pytest.approx(1.0, abs=1e-6)
    assert math.degrees(angle_between(enu_yaw(jderobot.Pose3DData(*out["pose"])), math.pi / 2 - truth.yaw)) < 1
    assert out["nav"]["vehicle"] == 1 and out["nav"]["tags"] == []
    assert out["nav"]["state"] == 2                     # the AR.Drone's "landed"
    assert out["answers"][0] == 0 and out["answers"][1] != 0
    assert "no camera source" in out["camera"]
    assert out["wp"] == "::jderobot::Pose3D"


def test_getters_share_one_conversion_per_snapshot_with_the_same_values(vehicle):
    """Pose3D and WP (and Navdata) answer a prepared value converted once per driver snapshot: the very
    object for every call until the driver publishes a new snapshot, holding what the conversion gives."""
    from driver.ice import servants
    settings = servants.ServerSettings()
    shared = servants.Snapshots(vehicle, settings)
    pose3d, wp = servants.Pose3DI(vehicle, "Pose3D", settings, shared), servants.Pose3DI(vehicle, "WP", settings, shared)
    nav = servants.NavdataI(vehicle, settings, shared)

    def one_snapshot():
        state = vehicle.state()
        answers = (pose3d.getPose3DData(), wp.getPose3DData(), nav.getNavdata(), nav.getNavdata())
        return (state, answers) if vehicle.state() is state else None

    state, (a, b, n1, n2) = eventually(one_snapshot, 5)
    assert a is b and n1 is n2
    assert (a.x, a.y, a.z, a.h, a.q0, a.q1, a.q2, a.q3) == convert.pose_enu(state)
    expected = convert.navdata_fields(state, settings.navdata_vehicle, n1.tm)
    assert {k: getattr(n1, k) for k in expected} == expected
    assert vehicle.wait_for(lambda s: s is not state, 5)
    assert pose3d.getPose3DData() is not a and nav.getNavdata() is not n1
