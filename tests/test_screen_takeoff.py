"""Issue 21, problems 3 and 4: Take off says when it must wait and can be cancelled before liftoff, leaving the
vehicle as it was (never LAND); Arm asks first and says what happens in the vehicle's mode.

Real simulator, real driver, real window.
"""
from __future__ import annotations

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QMessageBox
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.vehicle.state import SequencePhase

from lockstep_fixtures import lockstep_window  # noqa: F401  (fixtures)
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def open_takeoff_question(qtbot, w) -> QMessageBox:
    qtbot.mouseClick(w.flightControls.main_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.flight.takeoff_box is not None and w.flight.takeoff_box.isVisible(), timeout=3000)
    return w.flight.takeoff_box


def test_takeoff_before_ready_says_it_waits_and_cancel_leaves_the_vehicle_as_it_was(
        qtbot, sim_factory, vehicle_factory, window_factory):
    sim = sim_factory(ready_after=10_000)                     # never ready in this test
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    w = window_factory(vehicle, takeoff_altitude=3.0)
    b = w.flightControls.main_button
    qtbot.waitUntil(lambda: b.isEnabled() and bool(vehicle.state().readiness.missing), timeout=10000)
    assert b.text() == "Take off when ready" and "Waiting for" in b.toolTip()
    box = open_takeoff_question(qtbot, w)
    assert "not ready yet: waiting for" in box.text() and "Cancel takeoff" in box.text()
    assert box.button(QMessageBox.Yes).text().replace("&", "") == "Take off when ready"
    qtbot.mouseClick(box.button(QMessageBox.Yes), Qt.LeftButton)
    qtbot.waitUntil(lambda: b.text() == "Cancel takeoff", timeout=5000)
    qtbot.waitUntil(lambda: "when ready — waiting for" in w.phaseLabel.text(), timeout=3000)
    mode = sim.truth().mode
    qtbot.mouseClick(b, Qt.LeftButton)
    qtbot.waitUntil(lambda: not vehicle.state().takeoff.active and b.text() == "Take off when ready", timeout=5000)
    assert vehicle.state().takeoff.phase is SequencePhase.ABORTED
    assert sim.truth().mode == mode != "LAND" and not sim.truth().armed


def test_cancel_after_guided_before_arming_switches_back(qtbot, sim, vehicle_factory, window_factory):
    sim.faults.ignore_commands = {mavlink.MAV_CMD_COMPONENT_ARM_DISARM}   # the sequence waits at "arming"
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    w = window_factory(vehicle, takeoff_altitude=3.0)
    b = w.flightControls.main_button
    qtbot.waitUntil(lambda: b.isEnabled() and b.text() == "Take off", timeout=15000)
    before = sim.truth().mode
    qtbot.mouseClick(open_takeoff_question(qtbot, w).button(QMessageBox.Yes), Qt.LeftButton)
    qtbot.waitUntil(lambda: sim.truth().mode == "GUIDED" and b.text() == "Cancel takeoff", timeout=10000)
    qtbot.mouseClick(b, Qt.LeftButton)
    qtbot.waitUntil(lambda: sim.truth().mode == before, timeout=10000)          # back where it was
    assert not sim.truth().armed and not vehicle.state().takeoff.active
    qtbot.waitUntil(lambda: any("cancelled before liftoff" in t for t in w.messages.texts()), timeout=10000)


def test_arm_asks_first_and_says_what_happens_without_rc(qtbot, sim, vehicle_factory, window_factory):
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    w = window_factory(vehicle)
    arm = w.flightControls.arm_button
    qtbot.waitUntil(lambda: arm.isEnabled() and vehicle.state().mode == "STABILIZE", timeout=15000)
    qtbot.mouseClick(arm, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.flight.arm_box is not None and w.flight.arm_box.isVisible(), timeout=3000)
    text = w.flight.arm_box.text()
    assert "STABILIZE" in text and "RC transmitter" in text and "disarms again" in text
    assert w.flight.arm_box.defaultButton() is w.flight.arm_box.button(QMessageBox.Cancel)
    qtbot.mouseClick(w.flight.arm_box.button(QMessageBox.Cancel), Qt.LeftButton)
    qtbot.waitUntil(lambda: w.flight.arm_box is None, timeout=3000)
    assert not sim.truth().armed and not vehicle.state().armed


def test_launch_to_airborne_is_one_click_and_its_confirmation(qtbot, lockstep_window):
    """As a new user on --sim: the window opens before the vehicle is ready; one click on the main button, one on
    the question's "Take off when ready", and it flies (the sticks live) once the vehicle is ready. In lockstep:
    the vehicle's 6 s of start-up wait for the window, however slow it is to build."""
    steps = lockstep_window(ready_after=6.0, window={"takeoff_altitude": 3.0})
    w, vehicle = steps.window, steps.vehicle
    b = w.flightControls.main_button
    clicks = 0
    steps.until(lambda: b.isEnabled() and b.text() == "Take off when ready", 5, "Take off when ready")
    assert not steps.autopilot.ready
    qtbot.mouseClick(b, Qt.LeftButton)
    clicks += 1
    steps.until(lambda: w.flight.takeoff_box is not None and w.flight.takeoff_box.isVisible(), 1, "the question")
    qtbot.mouseClick(w.flight.takeoff_box.button(QMessageBox.Yes), Qt.LeftButton)      # its confirmation
    steps.until(lambda: w.leftStick.isEnabled() and vehicle.state().can_fly_velocity, 60, "flying")
    assert clicks == 1 and steps.autopilot.truth().altitude > 2.5
