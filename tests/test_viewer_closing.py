"""Leaving the window while the vehicle flies: the quit question's Cancel and "Quit anyway", and minimising.

("Land" on the quit question is in test_viewer_options.py.) Real simulator, real driver, real window; the
question is answered by clicking its buttons, and every wait is on a condition with a deadline.
"""
from __future__ import annotations

import math

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QMessageBox

from test_viewer_flight import body_velocity, speed, wait_flying
from viewer_fixtures import viewer_settings, window, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def sent_commands(w) -> list[str]:
    names: list[str] = []
    w.adapter.commandSent.connect(names.append)
    return names


def ask_to_close(qtbot, w) -> QMessageBox:
    """Close the window in flight: the question comes and the window stays."""
    w.close()
    qtbot.waitUntil(lambda: w.closing.quit_box is not None and w.closing.quit_box.isVisible(), timeout=3000)
    assert w.isVisible()
    return w.closing.quit_box


def button(box: QMessageBox, text: str):
    return next(b for b in box.buttons() if b.text() == text)


def hovers_in_place(qtbot, sim, seconds: float = 4.0) -> None:
    """Once still, the simulated vehicle stays armed in GUIDED, at its height and place, for ``seconds`` of
    its own time."""
    qtbot.waitUntil(lambda: speed(sim) < 0.2, timeout=20000)
    t0 = sim.truth()
    qtbot.waitUntil(lambda: sim.truth().time > t0.time + seconds, timeout=20000)
    t1 = sim.truth()
    assert t1.armed and t1.mode == "GUIDED"
    assert abs(t1.altitude - t0.altitude) < 0.3 and t1.altitude > 2.0
    assert math.hypot(t1.north - t0.north, t1.east - t0.east) < 0.5


def test_cancel_keeps_the_window_and_the_vehicle_flying(qtbot, sim, flying, window):
    w = window
    wait_flying(qtbot, w)
    sent = sent_commands(w)
    box = ask_to_close(qtbot, w)
    qtbot.mouseClick(box.button(QMessageBox.Cancel), Qt.LeftButton)
    qtbot.waitUntil(lambda: w.closing.quit_box is None, timeout=3000)
    assert w.isVisible() and sent == []
    hovers_in_place(qtbot, sim)
    # still the pilot's window: its state is live, its sticks fly, its buttons command the vehicle
    assert w.adapter.state.can_fly_velocity and w.rightStick.isEnabled()
    with qtbot.waitSignal(w.adapter.commandFinished, timeout=5000) as done:
        qtbot.mouseClick(w.flightControls.stop_button, Qt.LeftButton)
    assert sent == ["stop"] and done.args[0].command == "stop" and done.args[0].ok
    sent.clear()
    # and closing again asks again
    box = ask_to_close(qtbot, w)
    qtbot.mouseClick(box.button(QMessageBox.Cancel), Qt.LeftButton)
    qtbot.waitUntil(lambda: w.closing.quit_box is None, timeout=3000)
    assert w.isVisible() and sent == []


def test_quit_anyway_closes_and_leaves_the_vehicle_hovering(qtbot, sim, flying, window):
    w = window
    wait_flying(qtbot, w)
    sent = sent_commands(w)
    box = ask_to_close(qtbot, w)
    qtbot.mouseClick(button(box, "Quit anyway"), Qt.LeftButton)
    qtbot.waitUntil(lambda: not w.isVisible(), timeout=3000)
    assert w.closing.quit_box is None and sent == []              # no Land, no RTL: it is left where it is
    assert flying.state().setpoint.is_zero
    hovers_in_place(qtbot, sim)


def test_minimising_stops_the_vehicle(qtbot, sim, flying, window):
    """Minimised, the sticks are out of sight and out of hand: keys and pads centre, the vehicle stops."""
    w = window
    wait_flying(qtbot, w)
    qtbot.waitUntil(w.isActiveWindow, timeout=3000)
    qtbot.keyPress(w, Qt.Key_W)
    w.leftStick.hold(1.0, 0.0)                           # mode 2: left stick right = yaw right
    qtbot.waitUntil(lambda: body_velocity(sim)[0] > 1.0 and sim.truth().yaw_rate > 0.3, timeout=15000)
    w.showMinimized()
    qtbot.waitUntil(lambda: w.adapter.setpoint.is_zero, timeout=3000)
    assert w.leftStick.position == (0.0, 0.0) and not w.sticks.keyboard.active
    qtbot.waitUntil(lambda: flying.state().setpoint.is_zero, timeout=2000)
    qtbot.waitUntil(lambda: speed(sim) < 0.2 and abs(sim.truth().yaw_rate) < 0.05, timeout=20000)
    hovers_in_place(qtbot, sim)
