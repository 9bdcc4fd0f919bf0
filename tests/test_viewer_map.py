"""The Map dock in the real window, on the real driver and simulated vehicle (or a real recording)."""
from __future__ import annotations

import math

import pytest
from PyQt5.QtCore import QEvent, QPoint, QPointF, Qt
from PyQt5.QtGui import QColor, QContextMenuEvent, QMouseEvent
from PyQt5.QtWidgets import QApplication, QDialogButtonBox, QMenu, QMessageBox

from driver.core import frames
from driver.ice.client import IceDrone, viewer_properties
from driver.vehicle import Vehicle, VehicleConfig

from ice_fixtures import drone_factory, server_factory  # noqa: F401  (fixtures)
from recordings import FLIGHT
from tile_server import TileServer
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)

#: Far north and 11 m east of the antimeridian, nose east: flying west crosses from -180 to +180 degrees.
EDGE_HOME = (66.0, -179.9998, 20.0, 90.0)


def right_click_fly_here(qtbot, view, east: float, north: float):
    """Right-click the map at a point (view metres) and choose the menu's "Fly here" item."""
    pos = view.to_screen(east, north).toPoint()
    QApplication.postEvent(view, QContextMenuEvent(QContextMenuEvent.Mouse, pos, view.mapToGlobal(pos)))
    qtbot.waitUntil(lambda: view.findChild(QMenu, "mapMenu") is not None
                    and view.findChild(QMenu, "mapMenu").isVisible())
    menu = view.findChild(QMenu, "mapMenu")
    action = menu.actions()[0]
    text = action.text()
    qtbot.mouseClick(menu, Qt.LeftButton, pos=menu.actionGeometry(action).center())
    menu.deleteLater()
    return text


def test_fly_here_across_the_antimeridian_and_escape_cancels(qtbot, sim_factory, vehicle_factory, window_factory):
    sim = sim_factory(home=EDGE_HOME)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    w = window_factory(vehicle, takeoff_altitude=3.0)
    view, ctl = w.mapPanel.mapView, w.map
    qtbot.waitUntil(lambda: view.vehicle is not None and view.home_visible, timeout=15000)
    assert vehicle.takeoff(3.0).result(timeout=60).ok
    qtbot.waitUntil(lambda: view.fly_here_enabled, timeout=5000)

    # 30 m west of home is across the antimeridian: the pilot right-clicks there and confirms
    assert right_click_fly_here(qtbot, view, -30.0, 10.0) == "Fly here at 3 m"
    qtbot.waitUntil(lambda: ctl.question is not None and ctl.question.isVisible())
    box = ctl.question
    assert "30 m west" in box.text() and "10 m north" in box.text() and "at 3 m above home" in box.text()
    qtbot.mouseClick(box.button(QMessageBox.Yes), Qt.LeftButton)
    qtbot.waitUntil(lambda: view.target is not None, timeout=5000)           # the driver accepted the go-to
    assert view.target == pytest.approx((-30.0, 10.0), abs=0.6)

    def there() -> bool:
        s = vehicle.state()
        return s.local is not None and math.hypot(s.local.north - 10.0, s.local.east + 30.0) < 1.0
    qtbot.waitUntil(there, timeout=40000)                                      # the vehicle got there
    truth = sim.truth()
    assert math.hypot(truth.north - 10.0, truth.east + 30.0) < 1.5
    s = w.adapter.state
    assert s.position.lon > 179.99                                            # across: +180 side now
    qtbot.waitUntil(lambda: view.target is None, timeout=5000)                # reached: the target goes

    # the icon sits where the vehicle is, in ground metres from home, turned to its heading
    s = w.adapter.state
    north, east = frames.offset_ned(s.home.lat, s.home.lon, s.position.lat, s.position.lon)
    assert view.vehicle[:2] == pytest.approx((east, north), abs=0.05)
    assert view.vehicle[2] == s.heading_deg
    newest = view._bands[-1][-1]
    assert (newest.x(), newest.y()) == pytest.approx((east, north), abs=1.0) and view.trail_points > 10

    # a second, farther point; Escape in the middle of the way stops it there
    start = vehicle.state().local
    right_click_fly_here(qtbot, view, 20.0, 10.0)
    qtbot.waitUntil(lambda: ctl.question is not None and ctl.question.isVisible())
    qtbot.mouseClick(ctl.question.button(QMessageBox.Yes), Qt.LeftButton)
    qtbot.waitUntil(lambda: view.target is not None, timeout=5000)
    qtbot.waitUntil(lambda: vehicle.state().local.east - start.east > 5.0, timeout=20000)
    w.activateWindow()
    qtbot.keyClick(w, Qt.Key_Escape)
    assert view.target is None
    qtbot.waitUntil(lambda: any(r.command == "stop" for r in vehicle.state().results), timeout=5000)
    qtbot.waitUntil(lambda: vehicle.state().velocity.ground_speed < 0.3, timeout=20000)
    assert vehicle.state().local.east < 15.0                                  # held short of the target

    # panning lets go of the drone; one click on Follow brings it back to the middle
    drag(view, (200, 150), (260, 190))
    qtbot.waitUntil(lambda: not view.follow and not w.mapPanel.followButton.isChecked())
    assert view.centre != pytest.approx(view.vehicle[:2])
    qtbot.mouseClick(w.mapPanel.followButton, Qt.LeftButton)
    assert view.follow and view.centre == pytest.approx(view.vehicle[:2])


def drag(view, start: tuple[int, int], end: tuple[int, int]) -> None:
    """A left-button drag on the map, as mouse events through the event loop."""
    post = QApplication.postEvent
    post(view, QMouseEvent(QEvent.MouseButtonPress, QPointF(*start), Qt.LeftButton, Qt.LeftButton, Qt.NoModifier))
    for i in range(1, 11):
        x = start[0] + (end[0] - start[0]) * i / 10
        y = start[1] + (end[1] - start[1]) * i / 10
        post(view, QMouseEvent(QEvent.MouseMove, QPointF(x, y), Qt.NoButton, Qt.LeftButton, Qt.NoModifier))
    post(view, QMouseEvent(QEvent.MouseButtonRelease, QPointF(*end), Qt.LeftButton, Qt.NoButton, Qt.NoModifier))


def test_preferences_set_the_tile_server_and_the_area_downloads(qtbot, vehicle, window_factory, tmp_path,
                                                                  viewer_settings):
    server = TileServer().start()
    try:
        w = window_factory(vehicle, tile_cache_dir=str(tmp_path / "tiles"))
        panel = w.mapPanel
        combo = panel.layerCombo
        assert combo.currentText() == "Grid" and not combo.model().item(1).isEnabled()   # the offline grid first
        assert w.map.tiles is None and not panel.downloadButton.isEnabled()            # nothing on the network
        w.preferences.edit()
        dialog = w.preferences.dialog
        dialog.tileUrl.setText(server.url)
        dialog.tileAttribution.setText("© test")
        dialog.tileCacheMb.setValue(50)
        dialog.buttons.button(QDialogButtonBox.Ok).click()
        assert w.settings.tile_url == server.url and w.settings.tile_cache_mb == 50
        assert combo.model().item(1).isEnabled()
        combo.setCurrentIndex(1)
        assert w.map.tiles is not None and panel.mapView.attribution == "© test"
        assert w.map.tiles.cache_dir.rstrip("/") == str(tmp_path / "tiles")
        assert viewer_settings.value("viewer/map_tiles") in (True, "true")             # kept for the next run
        qtbot.waitUntil(lambda: vehicle.state().home is not None and panel.mapView.drawn_tiles > 0, timeout=15000)

        w.mapDock.setFloating(True)                         # a big map: its four levels need too many tiles
        w.mapDock.resize(1800, 1200)
        qtbot.waitUntil(lambda: panel.mapView.width() > 1500)
        panel.mapView.zoom_to(4.0)                          # levels 15 to 18 over 7 km
        qtbot.mouseClick(panel.downloadButton, Qt.LeftButton)
        assert "Area too large" in panel.statusLabel.text() and "1500" in panel.statusLabel.text()
        w.mapDock.setFloating(False)
        qtbot.waitUntil(lambda: panel.mapView.width() < 800)
        panel.mapView.zoom_to(1.0)
        hits = server.tile_hits
        qtbot.mouseClick(panel.downloadButton, Qt.LeftButton)
        assert panel.statusLabel.text().startswith("Downloading 0/")
        qtbot.waitUntil(lambda: panel.statusLabel.text().startswith("Area kept for offline use"), timeout=20000)
        assert "failed" not in panel.statusLabel.text()
        assert server.tile_hits > hits
    finally:
        server.stop()


def fly_here_and_arrive(qtbot, w, sim, east: float, north: float) -> None:
    view, ctl = w.mapPanel.mapView, w.map
    qtbot.waitUntil(lambda: view.fly_here_enabled, timeout=15000)
    right_click_fly_here(qtbot, view, east, north)
    qtbot.waitUntil(lambda: ctl.question is not None and ctl.question.isVisible())
    qtbot.mouseClick(ctl.question.button(QMessageBox.Yes), Qt.LeftButton)
    qtbot.waitUntil(lambda: view.target is not None, timeout=10000)          # the server said accepted
    qtbot.waitUntil(lambda: math.hypot(sim.truth().north - north, sim.truth().east - east) < 1.0, timeout=30000)


def test_fly_here_through_ice_with_the_fence_shown(qtbot, sim, flying, server_factory, drone_factory,
                                                   window_factory):
    """The same map and the same Fly here on a vehicle reached through the MAVLinkServer: our extension's goTo,
    then a plain JdeRobot client (Pose3D, CMDVel, Navdata, Extra, WP only: metres from home, no fence)."""
    assert flying.set_parameter("FENCE_ENABLE", 1).result(timeout=10).ok
    server = server_factory(flying)
    w = window_factory(drone_factory(server), takeoff_altitude=3.0)
    qtbot.waitUntil(lambda: w.mapPanel.mapView.fence_radius == 300.0, timeout=15000)
    fly_here_and_arrive(qtbot, w, sim, 8.0, -6.0)
    w.quit_without_asking()

    props = viewer_properties()
    for name in ("Pose3D", "CMDVel", "Navdata", "Extra", "WP"):
        props.setProperty(f"UAVViewer.{name}.Proxy", server.proxy(name))
    plain = IceDrone(props).start()
    try:
        w = window_factory(plain, takeoff_altitude=3.0)
        fly_here_and_arrive(qtbot, w, sim, -4.0, 5.0)
        assert w.mapPanel.mapView.frame is None                               # no latitude: the metre grid
    finally:
        plain.close()


def red_on_circle(view, radius: float) -> int:
    """How many of 36 points on a circle of ``radius`` m around home are painted in the fence's red."""
    image = view.grab().toImage()
    hits = 0
    for i in range(36):
        a = math.radians(i * 10)
        p = view.to_screen(radius * math.sin(a), radius * math.cos(a)).toPoint()
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                c = QColor(image.pixel(p + QPoint(dx, dy)))
                if c.red() > 180 and c.green() < 120 and c.blue() < 120:
                    hits += 1
                    break
            else:
                continue
            break
    return hits


def test_the_fence_is_drawn_from_the_vehicles_parameters(qtbot, vehicle, window_factory):
    w = window_factory(vehicle, takeoff_altitude=3.0)
    view = w.mapPanel.mapView
    qtbot.waitUntil(lambda: vehicle.state().fence.known, timeout=15000)
    view.set_follow(False)
    view.centre = (0.0, 0.0)
    view.zoom_to(2.5)                             # the 300 m circle is 120 px across the map
    assert view.fence_radius is None and red_on_circle(view, 300.0) == 0          # FENCE_ENABLE=0: none

    assert vehicle.set_parameter("FENCE_ENABLE", 1).result(timeout=10).ok
    qtbot.waitUntil(lambda: view.fence_radius == 300.0, timeout=5000)
    assert red_on_circle(view, 300.0) >= 18 and red_on_circle(view, 250.0) == 0
    assert vehicle.set_parameter("FENCE_RADIUS", 200.0).result(timeout=10).ok     # moved by another GCS: follows
    qtbot.waitUntil(lambda: view.fence_radius == 200.0, timeout=5000)
    assert red_on_circle(view, 200.0) >= 18 and red_on_circle(view, 300.0) == 0


def test_a_replay_shows_the_whole_track_and_the_vehicle_moves_along_it(qtbot, window_factory):
    replay = Vehicle(VehicleConfig(connection=FLIGHT + ".tlog", tlog_path=None, replay_speed=16.0)).start()
    try:
        w = window_factory(replay)
        view, ctl = w.mapPanel.mapView, w.map
        track = replay.replay.track().result(timeout=10)
        assert len(track) > 300
        qtbot.waitUntil(lambda: len(ctl.trail) == len(track) and view.frame is not None, timeout=30000)
        assert view.trail_points >= len(track)                      # all of it, from the start, at once
        assert view.fly_here_text == ""                             # nothing to fly in a recording
        points = [ctl.trail.bands(1, 0.0, view.frame.to_view)[0][i] for i in range(0, len(track), 10)]
        seen = []

        def on_track() -> bool:
            if view.vehicle is not None:
                e, n = view.vehicle[:2]
                seen.append(min(math.hypot(e - pe, n - pn) for pe, pn in points))
            return len(seen) > 20
        qtbot.waitUntil(on_track, timeout=30000)
        assert max(seen) < 3.0                                      # the icon rides the recorded track
        moved = {(round(view.vehicle[0], 1), round(view.vehicle[1], 1))}
        qtbot.waitUntil(lambda: (round(view.vehicle[0], 1), round(view.vehicle[1], 1)) not in moved or
                        replay.replay.finished, timeout=30000)
    finally:
        replay.close()


def test_the_plan_redraws_the_map_only_when_what_it_draws_changed(qtbot, vehicle, window_factory):
    w = window_factory(vehicle)
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=10000)
    updates = []
    w.plan.view.update = lambda: updates.append(1)      # the plan's own redraws (the map's are not called here)
    w.plan._shown = None                                 # as if the panel had changed: everything is worked out
    w.plan._show_vehicle(w.adapter.state)
    assert updates == []                                 # no mission flown: no current item, no progress drawn
    w.plan.layer.progress = "Item 1 of 2"                # drawn before, not any more
    w.plan._shown = None
    w.plan._show_vehicle(w.adapter.state)
    assert updates == [1] and w.plan.layer.progress == ""
