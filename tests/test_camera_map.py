"""The vehicle's camera on the map (issue 23): its footprint and look direction follow the gimbal, "Look here"
from the map's menu points it at a place (ROI) and "Stop looking" (menu, or the button under the video) ends it."""
from __future__ import annotations

import math

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtGui import QContextMenuEvent
from PyQt5.QtWidgets import QApplication, QMenu
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.payload import GimbalControl
from uavviewer.map.camera_footprint import MAX_RANGE, footprint, look_point

from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)


def test_footprint_geometry():
    down = footprint(10.0, -90.0, 0.0)                           # straight down from 10 m: 90 x 73.7 deg
    assert [(round(n, 2), round(e, 2)) for n, e in down] == [(7.5, -10.0), (7.5, 10.0), (-7.5, 10.0), (-7.5, -10.0)]
    n, e, on_ground = look_point(10.0, -45.0, 90.0)              # 45 deg down, facing east: 10 m east
    assert (n, e, on_ground) == (pytest.approx(0.0, abs=1e-9), pytest.approx(10.0), True)
    far, near = footprint(10.0, -45.0, 0.0)[0], footprint(10.0, -45.0, 0.0)[3]
    assert far[0] == pytest.approx(10 / math.tan(math.radians(45 - 73.74 / 2)), rel=1e-3)
    assert near[0] == pytest.approx(10 / math.tan(math.radians(45 + 73.74 / 2)), rel=1e-3)
    assert look_point(10.0, 0.0, 0.0) == (MAX_RANGE, 0.0, False)    # level: the horizon, cut at MAX_RANGE
    assert footprint(10.0, 60.0, 0.0) is None and footprint(float("nan"), -45, 0) is None


def menu_action(qtbot, view, east: float, north: float, starts: str) -> None:
    pos = view.to_screen(east, north).toPoint()
    QApplication.postEvent(view, QContextMenuEvent(QContextMenuEvent.Mouse, pos, view.mapToGlobal(pos)))
    qtbot.waitUntil(lambda: view.findChild(QMenu, "mapMenu") is not None
                    and view.findChild(QMenu, "mapMenu").isVisible())
    menu = view.findChild(QMenu, "mapMenu")
    action = next(a for a in menu.actions() if a.text().startswith(starts))
    assert action.isEnabled(), action.text()
    qtbot.mouseClick(menu, Qt.LeftButton, pos=menu.actionGeometry(action).center())
    menu.deleteLater()
    qtbot.waitUntil(lambda: view.findChild(QMenu, "mapMenu") is None, timeout=3000)


def test_look_here_on_the_map_and_stop_looking(qtbot, sim, vehicle, window_factory):
    w = window_factory(vehicle)
    view, overlay = w.mapPanel.mapView, w.map.camera
    qtbot.waitUntil(lambda: view.vehicle is not None and view.frame is not None
                    and overlay.geometry()[0] is not None, timeout=15000)
    corners, look = overlay.geometry()
    east, north = view.vehicle[0], view.vehicle[1]
    assert look[2] and math.hypot(look[0] - east, look[1] - north) < 1.0      # -90: right under the vehicle

    vehicle.point_gimbal(-30).result(10)                        # tilted: the look point moves ahead of the nose
    qtbot.waitUntil(lambda: overlay.geometry()[1] is not None and math.hypot(
        overlay.geometry()[1][0] - east, overlay.geometry()[1][1] - north) > 0.3, timeout=10000)

    menu_action(qtbot, view, east, north + 20.0, "Look here")
    qtbot.waitUntil(lambda: vehicle.state().gimbal.control is GimbalControl.ROI, timeout=10000)
    assert sim.autopilot.mount_mode == mavlink.MAV_MOUNT_MODE_GPS_POINT
    lat, lon, _ = sim.autopilot.mount_roi
    roi = view.frame.to_view(lat, lon)
    assert math.hypot(roi[0] - east, roi[1] - north - 20.0) < 0.5
    qtbot.waitUntil(lambda: overlay.roi_view() is not None and w.gimbal_bar.stop_looking_button.isVisible(),
                    timeout=5000)

    menu_action(qtbot, view, east + 5.0, north, "Stop looking")
    qtbot.waitUntil(lambda: vehicle.state().gimbal.roi is None, timeout=10000)
    # the ROI is gone on the vehicle; the window then points the camera back where it was (MAVLink targeting)
    assert sim.autopilot.mount_roi is None
    qtbot.waitUntil(lambda: sim.autopilot.mount_mode == mavlink.MAV_MOUNT_MODE_MAVLINK_TARGETING, timeout=10000)
    qtbot.waitUntil(lambda: not w.gimbal_bar.stop_looking_button.isVisible() and overlay.roi_view() is None,
                    timeout=5000)

    menu_action(qtbot, view, east, north + 10.0, "Look here")     # and the button under the video ends it too
    qtbot.waitUntil(lambda: w.gimbal_bar.stop_looking_button.isVisible(), timeout=10000)
    w.gimbal_bar.stop_looking_button.click()
    qtbot.waitUntil(lambda: vehicle.state().gimbal.roi is None and sim.autopilot.mount_roi is None, timeout=10000)
