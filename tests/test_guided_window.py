"""Fly › Change altitude and Circle, from the window and the map's right click, flown by the simulated vehicle."""
from __future__ import annotations

import math

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtGui import QContextMenuEvent
from PyQt5.QtWidgets import QApplication, QDialogButtonBox, QMenu

from viewer_fixtures import viewer_settings, window, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)


def answer(qtbot, w, value: float) -> None:
    """Type ``value`` in the open question and press its OK button, as the pilot does."""
    qtbot.waitUntil(lambda: w.guided.question is not None and w.guided.question.isVisible(), timeout=3000)
    dialog = w.guided.question
    dialog.setDoubleValue(value)
    ok = dialog.findChild(QDialogButtonBox).button(QDialogButtonBox.Ok)
    qtbot.mouseClick(ok, Qt.LeftButton)


def map_item(qtbot, view, east: float, north: float, text: str) -> None:
    """Right-click the map at a point (metres from home) and choose ``text`` in its menu."""
    pos = view.to_screen(east, north).toPoint()
    QApplication.postEvent(view, QContextMenuEvent(QContextMenuEvent.Mouse, pos, view.mapToGlobal(pos)))
    qtbot.waitUntil(lambda: view.findChild(QMenu, "mapMenu") is not None
                    and view.findChild(QMenu, "mapMenu").isVisible(), timeout=3000)
    menu = view.findChild(QMenu, "mapMenu")
    action = next(a for a in menu.actions() if a.text() == text)
    assert action.isEnabled()
    qtbot.mouseClick(menu, Qt.LeftButton, pos=menu.actionGeometry(action).center())
    menu.deleteLater()


def test_guided_actions_wait_for_guided_flight(qtbot, window):
    qtbot.waitUntil(lambda: window.adapter.state.connected, timeout=10000)
    qtbot.waitUntil(lambda: not window.guided.change_altitude_action.isEnabled()
                    and "not flying" in window.guided.change_altitude_action.toolTip(), timeout=3000)
    assert not window.guided.circle_action.isEnabled()


def test_change_altitude_from_the_window(qtbot, sim, flying, window):
    w = window
    qtbot.waitUntil(lambda: w.guided.change_altitude_action.isEnabled(), timeout=10000)
    w.guided.change_altitude_action.trigger()            # Fly › Change altitude…
    answer(qtbot, w, 7.0)
    qtbot.waitUntil(lambda: abs(-sim.truth().down - 7.0) < 0.3, timeout=30000)
    assert w.adapter.state.mode == "GUIDED"
    assert any("go to" in t and "alt 7.0" in t and "accepted" in t for t in w.messages.texts())


def test_circle_a_point_from_the_map_flies_ardupilots_circle(qtbot, sim, flying, window):
    w = window
    view = w.mapPanel.mapView
    qtbot.waitUntil(lambda: w.guided.circle_action.isEnabled() and bool(view.fly_here_text), timeout=10000)
    centre = (8.0, 0.0)                                  # north, east of home
    map_item(qtbot, view, centre[1], centre[0], "Circle here…")
    answer(qtbot, w, 5.0)
    qtbot.waitUntil(lambda: sim.truth().mode == "CIRCLE", timeout=60000)
    assert sim.autopilot.params["CIRCLE_RADIUS"] == 500             # set in cm, as ArduCopter reads it
    turned = []

    def around() -> bool:                                # a good part of a turn, on the circle, nose on the centre
        t = sim.truth()
        dn, de = t.north - centre[0], t.east - centre[1]
        assert abs(math.hypot(dn, de) - 5.0) < 1.5, (t.north, t.east)
        facing = math.atan2(-de, -dn)
        assert abs((math.degrees(t.yaw - facing) + 180) % 360 - 180) < 30
        turned.append(math.atan2(de, dn))
        return len(turned) > 2 and abs((math.degrees(turned[-1] - turned[0]) + 180) % 360 - 180) > 90
    qtbot.waitUntil(around, timeout=60000)
    qtbot.waitUntil(lambda: any("circling" in t for t in w.messages.texts()), timeout=5000)
    assert w.adapter.state.mode == "CIRCLE"
    north, east, radius = w.guided.circling                           # drawn on the map while it is flown
    assert math.hypot(north - centre[0], east - centre[1]) < 0.5 and radius == 5.0   # (a pixel off: the click)
    paints = view.paints
    qtbot.waitUntil(lambda: view.paints > paints, timeout=3000)
    w.flight.request_mode("LOITER")                                           # any other mode leaves the circle
    qtbot.waitUntil(lambda: w.guided.circling is None, timeout=10000)


def test_stop_ends_a_circle_on_its_way(qtbot, sim, flying, window):
    w = window
    qtbot.waitUntil(lambda: w.guided.circle_action.isEnabled(), timeout=10000)
    w.guided.circle((40.0, 0.0), 10.0)                  # far enough that Stop comes first
    qtbot.waitUntil(lambda: math.hypot(sim.truth().vn, sim.truth().ve) > 0.5, timeout=20000)
    qtbot.mouseClick(w.flightControls.stop_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: any("circle" in t and "cancelled" in t for t in w.messages.texts()), timeout=5000)
    qtbot.waitUntil(lambda: math.hypot(sim.truth().vn, sim.truth().ve) < 0.2, timeout=20000)
    assert sim.truth().mode == "GUIDED"


def test_a_circle_the_vehicle_took_is_drawn_from_the_ui_thread(qtbot):
    """The circle's answer arrives on a driver thread; the map learns of it on the UI thread (view_changed)."""
    import threading
    from concurrent.futures import Future

    from PyQt5.QtCore import QThread
    from PyQt5.QtWidgets import QWidget

    from driver.vehicle import Vehicle, VehicleConfig
    from driver.vehicle.state import CommandResult, CommandStatus
    from uavviewer.drone_adapter import DroneAdapter
    from uavviewer.flight.guided import GuidedController

    future = Future()
    vehicle = Vehicle(VehicleConfig())                   # never started: its circle is the one answered below

    def circle(north: float, east: float, radius: float) -> Future:
        return future
    vehicle.circle = circle
    parent = QWidget()
    qtbot.addWidget(parent)
    guided = GuidedController(DroneAdapter(vehicle, parent=parent), parent)
    threads = []
    guided.view_changed.connect(lambda: threads.append(QThread.currentThread()))
    guided.circle((10.0, 0.0), 5.0)
    driver = threading.Thread(target=future.set_result, args=(CommandResult("circle", CommandStatus.ACCEPTED),))
    driver.start()
    driver.join()
    assert guided.circling is None                       # not set from the driver's thread
    qtbot.waitUntil(lambda: guided.circling == (10.0, 0.0, 5.0), timeout=2000)
    assert threads == [QApplication.instance().thread()]
    vehicle.close()
