"""The viewer in remote mode: the same window, flying the simulated vehicle through the Ice server."""
from __future__ import annotations

import os

import pytest
from PyQt5.QtCore import Qt

from uavviewer import app as main
from driver.vehicle.state import CommandStatus, LinkStatus

from camera_media import write_clip
from ice_fixtures import drone_factory, free_port, server_factory  # noqa: F401  (fixtures)
from test_camera_view import nearest, painted_rgb
from test_viewer_flight import body_velocity, click_takeoff, press, release, speed, wait_flying
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_command_line_offers_ice_modes():
    parser = main.build_parser()
    args = parser.parse_args(["--ice", os.path.join(ROOT, "config", "viewer.cfg")])
    assert args.ice.name == "viewer.cfg" and args.ice_host is None
    assert parser.parse_args(["--ice-host", "10.1.1.10"]).ice_host == "10.1.1.10"
    with pytest.raises(SystemExit):
        parser.parse_args(["--ice-host", "10.1.1.10", "--sim"])


def test_ice_viewer_takes_off_flies_with_a_stick_and_lands(qtbot, sim, vehicle, server_factory, drone_factory,
                                                           window_factory):
    drone = drone_factory(server_factory(vehicle))
    w = window_factory(drone, takeoff_altitude=3.0)
    assert "Ice 127.0.0.1" in w.windowTitle()
    click_takeoff(qtbot, w)
    qtbot.waitUntil(lambda: w.flightControls.main_button.text() == "Land", timeout=15000)
    wait_flying(qtbot, w, timeout=60000)
    assert sim.truth().altitude > 2.5

    press(w.rightStick, 0.0, 1.0)                        # mode 2: right stick up = forward
    qtbot.waitUntil(lambda: body_velocity(sim)[0] > 1.0, timeout=15000)
    forward, right = body_velocity(sim)
    assert abs(right) < 0.3 * forward                    # along its heading, through CMDVel
    assert vehicle.state().setpoint.forward == pytest.approx(w.adapter.setpoint.forward, abs=0.05)
    release(w.rightStick)
    qtbot.waitUntil(lambda: vehicle.state().setpoint.is_zero, timeout=3000)
    qtbot.waitUntil(lambda: speed(sim) < 0.2, timeout=20000)

    qtbot.mouseClick(w.flightControls.main_button, Qt.LeftButton)        # Land
    qtbot.waitUntil(lambda: not sim.truth().armed and not w.adapter.state.armed
                    and w.flightControls.main_button.text() == "Take off", timeout=60000)
    done = [t for t in w.messages.texts() if "takeoff: accepted" in t]
    assert len(done) == 1, w.messages.texts()                # the answer and the snapshot, shown once


def test_lost_server_shows_as_lost_link_and_recovers(qtbot, vehicle, server_factory, drone_factory,
                                                     window_factory):
    port = free_port()
    server = server_factory(vehicle, port=port)
    w = window_factory(drone_factory(server, loss_timeout=1.0))
    qtbot.waitUntil(lambda: w.adapter.state.connected and w.linkBanner.isHidden(), timeout=10000)
    server.close()
    qtbot.waitUntil(lambda: w.linkBanner.isVisible() and w.linkBanner.text().startswith("Link lost"),
                    timeout=10000)
    assert not w.rightStick.isEnabled()
    server_factory(vehicle, port=port)
    qtbot.waitUntil(lambda: w.linkBanner.isHidden(), timeout=15000)
    assert w.adapter.state.link.status is LinkStatus.OK


def test_switch_camera_asks_the_server_for_its_next_camera(qtbot, vehicle, server_factory, drone_factory,
                                                          window_factory, tmp_path):
    """Video from the server's Camera: Switch camera goes through Drone.toggle_camera (JdeRobot's toggleCam)."""
    red = write_clip(str(tmp_path / "red.mp4"), [(255, 0, 0)], repeat=60)
    blue = write_clip(str(tmp_path / "blue.mp4"), [(0, 0, 255)], repeat=60)
    server = server_factory(vehicle, **{"MAVLinkServer.Camera.Uri": red, "MAVLinkServer.Camera.Uri.2": blue,
                                        "MAVLinkServer.Camera.Loop": "1"})
    drone = drone_factory(server)
    w = window_factory(drone, default_cameras=[f"ice:{server.proxy('Camera')}"])      # as main.py --ice
    w.camera_view.set_hud_visible(False)
    panel = w.camera_panel
    assert panel.switch_button.isEnabled()
    qtbot.waitUntil(lambda: w.camera_view.frame() is not None and nearest(painted_rgb(w.camera_view)) == (255, 0, 0),
                    timeout=10000)
    with qtbot.waitSignal(w.camera.switchAnswered, timeout=5000) as answer:
        qtbot.mouseClick(panel.switch_button, Qt.LeftButton)
    assert answer.args[0].ok, str(answer.args[0])
    assert panel.note.text().startswith("Camera: the vehicle switched")
    qtbot.waitUntil(lambda: w.camera_view.frame() is not None and nearest(painted_rgb(w.camera_view)) == (0, 0, 255),
                    timeout=10000)


def test_switch_camera_refusal_is_shown(qtbot, vehicle, window_factory, tmp_path):
    """A vehicle without a camera switch (the embedded driver) says so in the camera panel."""
    result = vehicle.toggle_camera().result(timeout=0)
    assert result.status is CommandStatus.REJECTED and "no camera switch" in result.reason
    w = window_factory(vehicle, cameras=["ice:Camera:tcp -h 127.0.0.1 -p 9"])
    assert w.camera_panel.switch_button.isEnabled()
    with qtbot.waitSignal(w.camera.switchAnswered, timeout=5000):
        qtbot.mouseClick(w.camera_panel.switch_button, Qt.LeftButton)
    assert w.camera_panel.note.text() == "Cannot switch camera: this vehicle has no camera switch"
