"""Fly the simulated vehicle through the real window: buttons, sticks, keys, messages, link banner.

Everything is real: SimVehicle on a TCP socket, the embedded driver, the main window driven by
pytest-qt. Waits are on conditions with deadlines, never on bare sleeps.
"""
from __future__ import annotations

import math

import pytest
from PyQt5.QtCore import QEvent, QPointF, Qt
from PyQt5.QtGui import QMouseEvent
from PyQt5.QtWidgets import QApplication, QMessageBox

from driver.vehicle.state import LandedState, LinkStatus
from uavviewer.flight.phase import FlightPhase

from lockstep_fixtures import lockstep_window  # noqa: F401  (fixtures)
from viewer_fixtures import pick_mode, viewer_settings, window, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def press(pad, x: float, y: float) -> None:
    ev = QMouseEvent(QEvent.MouseButtonPress, QPointF(pad.point_for(x, y)), Qt.LeftButton, Qt.LeftButton,
                     Qt.NoModifier)
    QApplication.sendEvent(pad, ev)


def release(pad) -> None:
    ev = QMouseEvent(QEvent.MouseButtonRelease, QPointF(pad.knob_centre()), Qt.LeftButton, Qt.NoButton,
                     Qt.NoModifier)
    QApplication.sendEvent(pad, ev)


def body_velocity(sim):
    """(forward, right) of the simulated vehicle's true velocity along its true heading."""
    t = sim.truth()
    c, s = math.cos(t.yaw), math.sin(t.yaw)
    return (c * t.vn + s * t.ve, -s * t.vn + c * t.ve)


def speed(sim) -> float:
    t = sim.truth()
    return math.hypot(t.vn, t.ve)


def click_takeoff(qtbot, w) -> None:
    qtbot.waitUntil(lambda: w.flightControls.main_button.isEnabled()
                    and w.flightControls.main_button.text() == "Take off", timeout=15000)
    qtbot.mouseClick(w.flightControls.main_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.flight.takeoff_box is not None and w.flight.takeoff_box.isVisible(), timeout=3000)
    assert "3.0 m" in w.flight.takeoff_box.text()
    qtbot.mouseClick(w.flight.takeoff_box.button(QMessageBox.Yes), Qt.LeftButton)


def wait_flying(qtbot, w, timeout=40000) -> None:
    qtbot.waitUntil(lambda: w.adapter.state.can_fly_velocity and w.leftStick.isEnabled(), timeout=timeout)


def test_takeoff_button_climbs_and_turns_to_land(qtbot, sim, window):
    w = window
    assert not w.rightStick.isEnabled()                  # inert on the ground, with a hint
    click_takeoff(qtbot, w)
    qtbot.waitUntil(lambda: w.flightControls.main_button.text() == "Land", timeout=15000)
    qtbot.waitUntil(lambda: sim.truth().altitude > 1.0, timeout=30000)
    assert w.flightControls.main_button.text() == "Land"
    wait_flying(qtbot, w)
    assert sim.truth().altitude > 2.5
    assert w.flightControls.phase is FlightPhase.FLYING
    assert not w.flightControls.progress.isVisible()


def test_cancelled_takeoff_sends_nothing(qtbot, sim, window):
    w = window
    qtbot.waitUntil(lambda: w.flightControls.main_button.isEnabled(), timeout=15000)
    qtbot.mouseClick(w.flightControls.main_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.flight.takeoff_box is not None and w.flight.takeoff_box.isVisible(), timeout=3000)
    qtbot.mouseClick(w.flight.takeoff_box.button(QMessageBox.Cancel), Qt.LeftButton)
    qtbot.waitUntil(lambda: w.flight.takeoff_box is None, timeout=3000)
    assert not w.adapter.state.takeoff.active and not sim.truth().armed


def test_right_stick_flies_forward_and_release_stops(qtbot, sim, flying, window):
    w = window
    wait_flying(qtbot, w)
    press(w.rightStick, 0.0, 1.0)                        # mode 2: right stick up = forward
    assert w.adapter.setpoint.forward == pytest.approx(2.0, abs=0.05)
    qtbot.waitUntil(lambda: body_velocity(sim)[0] > 1.0, timeout=15000)
    forward, right = body_velocity(sim)
    assert abs(right) < 0.3 * forward                    # along its heading, not sideways
    # Held: the window keeps refreshing the setpoint, so the driver's deadman never fires.
    sent = w.adapter.sent_setpoints
    qtbot.waitUntil(lambda: w.adapter.sent_setpoints >= sent + 10, timeout=5000)
    assert flying.state().setpoint.forward == pytest.approx(2.0)
    release(w.rightStick)
    assert w.rightStick.position == (0.0, 0.0)
    assert w.adapter.setpoint.is_zero
    qtbot.waitUntil(lambda: flying.state().setpoint.is_zero, timeout=2000)
    qtbot.waitUntil(lambda: speed(sim) < 0.2, timeout=20000)


def test_keyboard_w_moves_and_release_stops(qtbot, sim, flying, window):
    w = window
    wait_flying(qtbot, w)
    qtbot.keyPress(w, Qt.Key_W)
    assert w.adapter.setpoint.forward == pytest.approx(2.0, abs=0.05)
    qtbot.waitUntil(lambda: body_velocity(sim)[0] > 1.0, timeout=15000)
    qtbot.keyRelease(w, Qt.Key_W)
    assert w.adapter.setpoint.is_zero
    qtbot.waitUntil(lambda: speed(sim) < 0.2, timeout=20000)


def test_keyboard_climbs_and_yaws_the_vehicle(qtbot, sim, flying, window):
    """↑ climbs and → turns the nose right: the simulated vehicle really does, and each stops with its key."""
    w = window
    wait_flying(qtbot, w)
    start = sim.truth()
    qtbot.keyPress(w, Qt.Key_Up)
    qtbot.keyPress(w, Qt.Key_Right)
    sp = w.adapter.setpoint
    assert sp.up == pytest.approx(1.0) and sp.yaw_rate == pytest.approx(math.radians(45))
    qtbot.waitUntil(lambda: sim.truth().vd < -0.5 and sim.truth().yaw_rate > 0.5
                    and sim.truth().altitude > start.altitude + 0.5, timeout=20000)
    assert speed(sim) < 0.3                              # climbing and turning on the spot, not sliding
    qtbot.keyRelease(w, Qt.Key_Up)
    assert w.adapter.setpoint.up == 0.0 and w.adapter.setpoint.yaw_rate > 0
    # the climb stops, the turn goes on
    qtbot.waitUntil(lambda: abs(sim.truth().vd) < 0.1 and sim.truth().yaw_rate > 0.5, timeout=20000)
    qtbot.keyRelease(w, Qt.Key_Right)
    assert w.adapter.setpoint.is_zero
    qtbot.waitUntil(lambda: abs(sim.truth().yaw_rate) < 0.05 and abs(sim.truth().vd) < 0.1, timeout=20000)
    assert sim.truth().altitude > start.altitude + 0.5


def test_stop_holds_position(qtbot, sim, flying, window):
    w = window
    wait_flying(qtbot, w)
    qtbot.keyPress(w, Qt.Key_D)                          # slide right...
    qtbot.waitUntil(lambda: body_velocity(sim)[1] > 1.0, timeout=15000)
    qtbot.mouseClick(w.flightControls.stop_button, Qt.LeftButton)   # ...and Stop, key still held
    assert w.adapter.setpoint.is_zero
    qtbot.waitUntil(lambda: speed(sim) < 0.1, timeout=20000)
    t0 = sim.truth()
    count = []
    w.adapter.stateChanged.connect(lambda s: count.append(1))
    qtbot.waitUntil(lambda: len(count) >= 20, timeout=10000)       # a couple of seconds of snapshots
    t1 = sim.truth()
    assert math.hypot(t1.north - t0.north, t1.east - t0.east) < 0.5
    assert t1.armed and t1.altitude > 2.0


def test_land_lands_disarms_and_button_returns(qtbot, lockstep_window):
    """In lockstep the window is shown each state of the landing: "Landing…" is seen on a loaded machine too
    (over a socket at 4x the descent from 3 m was under a real second)."""
    steps = lockstep_window(window={"takeoff_altitude": 3.0})
    w = steps.window
    steps.take_off(3.0)
    steps.until(lambda: w.adapter.state.can_fly_velocity and w.leftStick.isEnabled(), 40, "flying")
    seen = set()
    w.adapter.stateChanged.connect(lambda s: seen.add(w.flightControls.main_button.text()))
    qtbot.mouseClick(w.flightControls.main_button, Qt.LeftButton)
    steps.until(lambda: not w.rightStick.isEnabled(), 5, "the sticks off")
    steps.until(lambda: not steps.autopilot.armed and not w.adapter.state.armed
                and w.flightControls.main_button.text() == "Take off", 60, "landed and disarmed")
    assert "Landing…" in seen
    s = w.adapter.state
    assert not s.armed and s.landed_state in (LandedState.ON_GROUND, LandedState.UNDEFINED)
    assert w.flightControls.arm_button.text() == "Arm"


def test_refused_arming_shows_the_reason(qtbot, sim, window):
    w = window
    sim.faults.refuse_arm = "Compass not calibrated"
    qtbot.waitUntil(lambda: w.flightControls.arm_button.isEnabled(), timeout=15000)
    qtbot.mouseClick(w.flightControls.arm_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.flight.arm_box is not None and w.flight.arm_box.isVisible(), timeout=3000)  # it asks first
    qtbot.mouseClick(w.flight.arm_box.button(QMessageBox.Yes), Qt.LeftButton)

    def refused():
        return any("refused" in t and "Compass not calibrated" in t for t in w.messages.texts())
    qtbot.waitUntil(refused, timeout=15000)
    assert not sim.truth().armed


def test_link_loss_banner_appears_and_clears(qtbot, sim, vehicle_factory, window_factory):
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", loss_timeout=1.0)
    w = window_factory(v)
    qtbot.waitUntil(lambda: v.state().connected and w.linkBanner.isHidden(), timeout=10000)
    sim.faults.link_down = True
    qtbot.waitUntil(lambda: w.linkBanner.isVisible() and w.linkBanner.text().startswith("Link lost"),
                    timeout=10000)
    assert "since the last heartbeat" in w.linkBanner.text()
    assert any("Link lost" in t for t in w.messages.texts())
    sim.faults.link_down = False
    qtbot.waitUntil(lambda: w.linkBanner.isHidden(), timeout=10000)
    assert w.adapter.state.link.status is LinkStatus.OK


def test_focus_loss_centres_sticks(qtbot, sim, flying, window):
    w = window
    wait_flying(qtbot, w)
    qtbot.waitUntil(w.isActiveWindow, timeout=3000)
    qtbot.keyPress(w, Qt.Key_A)
    press(w.rightStick, 0.0, 0.8)
    assert not w.adapter.setpoint.is_zero
    from PyQt5.QtWidgets import QWidget
    other = QWidget()
    qtbot.addWidget(other)
    other.show()
    other.activateWindow()
    qtbot.waitUntil(lambda: not w.isActiveWindow(), timeout=3000)
    assert w.adapter.setpoint.is_zero
    assert w.rightStick.position == (0.0, 0.0)
    qtbot.waitUntil(lambda: flying.state().setpoint.is_zero, timeout=2000)


def test_instruments_and_plots_follow_the_vehicle(qtbot, sim, flying, window):
    w = window
    wait_flying(qtbot, w)
    qtbot.waitUntil(lambda: w.plots.sample_count > 10, timeout=5000)
    w.plots.redraw()
    assert w.plots.curve_points("altitude") > 10
    shown = w.attitude.values
    assert shown["valid"] and shown["altitude"] == pytest.approx(flying.state().altitude, abs=0.5)
    assert w.telemetry.text("mode") == "GUIDED"
    assert w.telemetry.text("armed") == "ARMED"


def test_on_the_ground_the_pilot_sees_what_the_autopilot_waits_for(qtbot, sim_factory, vehicle_factory,
                                                                    window_factory):
    late = sim_factory(ready_after=1e6)                     # not ready until the test says so
    w = window_factory(vehicle_factory(f"tcp:127.0.0.1:{late.tcp_port}"), takeoff_altitude=3.0)
    qtbot.waitUntil(lambda: w.flightControls.phase is FlightPhase.ON_GROUND
                    and "waiting for" in w.phaseLabel.text(), timeout=15000)
    assert w.phaseLabel.text().startswith("On the ground · waiting for GPS fix")
    late.config.ready_after = 0.0                           # the fix and the EKF come now
    qtbot.waitUntil(lambda: w.phaseLabel.text() == "On the ground · ready to arm", timeout=15000)
    assert late.truth().ready


def test_a_mode_picked_in_the_selector_reaches_the_vehicle(qtbot, sim, window):
    w = window
    sel = w.modeSelector
    qtbot.waitUntil(lambda: sel.isEnabled() and sel.mode == "STABILIZE", timeout=15000)
    sent: list[str] = []
    w.adapter.commandSent.connect(sent.append)
    pick_mode(qtbot, sel, "ALT_HOLD")
    assert sent == ["set_mode"]
    qtbot.waitUntil(lambda: sim.truth().mode == "ALT_HOLD", timeout=10000)
    qtbot.waitUntil(lambda: sel.currentText() == "ALT_HOLD" and w.telemetry.text("mode") == "ALT_HOLD",
                    timeout=5000)


def test_a_takeoff_confirmed_after_the_link_was_lost_is_not_sent(qtbot, sim, vehicle_factory, window_factory):
    """The window withdraws the takeoff question as soon as it shows a state the question no longer fits; should
    the pilot's "Take off" come while the window is behind the vehicle (held here one snapshot behind, the link
    lost in between), the window checks the newest state again: nothing is sent, and the pilot is told."""
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", loss_timeout=1.0)
    w = window_factory(v, takeoff_altitude=3.0)
    sent: list[str] = []
    w.adapter.commandSent.connect(sent.append)
    qtbot.waitUntil(lambda: w.flightControls.main_button.isEnabled()
                    and w.flightControls.main_button.text() == "Take off", timeout=15000)
    qtbot.mouseClick(w.flightControls.main_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.flight.takeoff_box is not None and w.flight.takeoff_box.isVisible(), timeout=3000)
    box = w.flight.takeoff_box
    w.adapter.stateChanged.disconnect(w.show_state)         # the window has not yet shown the newest state...
    try:
        sim.faults.link_down = True                         # ...in which the link is lost
        qtbot.waitUntil(lambda: w.adapter.state.link.status is LinkStatus.LOST, timeout=10000)
        assert w.flight.takeoff_box is box and box.isVisible()
        qtbot.mouseClick(box.button(QMessageBox.Yes), Qt.LeftButton)
    finally:
        w.adapter.stateChanged.connect(w.show_state)
    assert "takeoff" not in sent
    assert any(t.startswith("Takeoff not sent") for t in w.messages.texts())
    qtbot.waitUntil(lambda: w.flight.takeoff_box is None, timeout=3000)
    sim.faults.link_down = False
    qtbot.waitUntil(lambda: w.adapter.state.link.status is LinkStatus.OK
                    and w.flightControls.main_button.isEnabled(), timeout=15000)
    assert "takeoff" not in sent
    assert not sim.truth().armed and not v.state().takeoff.active
