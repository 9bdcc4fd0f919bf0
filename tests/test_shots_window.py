"""The Shots panel in the window: keyframes recorded with its button and the cable drawn on the map with its looks,
an orbit from the map's right click with its circle, and the pilot's sticks steering the shot instead of ending it.
"""
from __future__ import annotations

import math

import pytest
from PyQt5.QtCore import Qt

from driver.shots.model import ShotKind, ShotPhase

from shots_fixtures import flight_factory  # noqa: F401
from test_guided_window import map_item
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(180)


def test_keyframes_recorded_with_the_button_are_drawn_as_the_cable_and_played(qtbot, flight_factory, window_factory):
    f = flight_factory()
    w = window_factory(f.vehicle, takeoff_altitude=10.0)
    panel = w.shots.panel
    qtbot.waitUntil(lambda: panel.record_button.isEnabled(), timeout=10000)
    for north, east, up in ((0.0, 0.0, 10.0), (20.0, 15.0, 14.0), (35.0, -5.0, 12.0)):
        assert f.vehicle.go_to(north, east, up).result(timeout=10).ok
        qtbot.waitUntil(lambda: (t := f.sim.truth()) and math.hypot(t.north - north, t.east - east) < 0.4
                        and abs(t.altitude - up) < 0.4 and t.ground_speed < 0.1, timeout=60000)
        count = len(w.adapter.state.shot.keyframes)
        qtbot.mouseClick(panel.record_button, Qt.LeftButton)
        qtbot.waitUntil(lambda: len(w.adapter.state.shot.keyframes) == count + 1, timeout=5000)
    assert panel.keyframes_label.text() == "3 keyframes"
    points, looks, keys = w.shots.overlay.cable()              # drawn before it plays: the path it will fly
    assert len(keys) == 3 and len(points) > 20 and len(looks) >= 3
    first = w.adapter.state.shot.keyframes[0]
    assert math.dist(points[0], (first.lat, first.lon)) < 1e-6
    panel.cable_speed.setValue(4.0)
    qtbot.waitUntil(lambda: panel.play_button.isEnabled(), timeout=5000)
    qtbot.mouseClick(panel.play_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.adapter.state.shot.kind is ShotKind.CABLE and w.adapter.state.shot.active,
                    timeout=10000)
    assert len(w.adapter.state.shot.path) > 20                    # the driver's own path, drawn once it plays
    qtbot.waitUntil(lambda: w.shots.badge.isVisible() and "CABLE" in w.shots.badge.text(), timeout=5000)
    qtbot.waitUntil(lambda: w.adapter.state.shot.phase is ShotPhase.PAUSED, timeout=90000)
    t = f.sim.truth()
    assert math.hypot(t.north - 0.0, t.east - 0.0) < 1.0           # flown back to keyframe 1 from keyframe 3
    qtbot.mouseClick(panel.running_buttons["stop"], Qt.LeftButton)
    qtbot.waitUntil(lambda: w.adapter.state.shot.phase is ShotPhase.ENDED and not w.shots.badge.isVisible(),
                    timeout=10000)


def test_orbit_here_from_the_map_and_the_sticks_steer_it_instead_of_ending_it(qtbot, flight_factory,
                                                                             window_factory):
    f = flight_factory()
    w = window_factory(f.vehicle, takeoff_altitude=10.0)
    view = w.mapPanel.mapView
    qtbot.waitUntil(lambda: view.frame is not None and w.rightStick.isEnabled(), timeout=10000)
    w.shots.panel.orbit_speed.setValue(2.0)
    map_item(qtbot, view, 0.0, 12.0, "Orbit here (smart shot)")    # 12 m north: the vehicle's distance
    qtbot.waitUntil(lambda: w.adapter.state.shot.kind is ShotKind.ORBIT
                    and w.adapter.state.shot.phase is ShotPhase.FLYING, timeout=15000)
    shot = w.adapter.state.shot
    assert shot.centre is not None and abs(shot.radius_wanted - 12.0) < 0.5
    velocity_frames = sum(1 for _, kind, _ in list(f.sim.received_messages) if kind == "SET_POSITION_TARGET_LOCAL_NED")
    w.rightStick.hold(0.0, -1.0)                                   # full stick back: out, as on the Solo
    # it backs out from the centre (however fast this machine refreshes the stick), and the shot goes on
    qtbot.waitUntil(lambda: math.hypot(f.sim.truth().north - 12.0, f.sim.truth().east) > 15.0
                    or not w.adapter.state.shot.active, timeout=30000)
    w.rightStick.hold(0.0, 0.0)
    assert w.adapter.state.shot.active                             # steered, not ended
    assert sum(1 for _, kind, _ in list(f.sim.received_messages)
               if kind == "SET_POSITION_TARGET_LOCAL_NED") == velocity_frames    # no velocity went out
    qtbot.mouseClick(w.shots.panel.running_buttons["stop"], Qt.LeftButton)
    qtbot.waitUntil(lambda: not w.adapter.state.shot.active, timeout=10000)
