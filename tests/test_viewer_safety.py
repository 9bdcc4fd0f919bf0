"""Safety of the flying window: keys never stay held, Space never confirms a takeoff, keys act like
their buttons, the pilot's speeds are the driver's clamps, and a lost link makes the sticks inert.

Real simulator, real driver, real window; waits are on conditions with deadlines.
"""
from __future__ import annotations

import math
from dataclasses import replace

import pytest
from PyQt5.QtCore import QPoint, Qt
from PyQt5.QtWidgets import QApplication, QDialogButtonBox, QMessageBox, QWidget

from driver.vehicle.api import CEILING, Limits
from uavviewer.preferences.dialog import SettingsDialog
from uavviewer.settings import ViewerSettings, save_settings

from test_viewer_window import silent_vehicle  # noqa: F401  (fixture)
from viewer_fixtures import viewer_settings, window, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def wait_flying(qtbot, w, timeout=40000) -> None:
    qtbot.waitUntil(lambda: w.adapter.state.can_fly_velocity and w.leftStick.isEnabled(), timeout=timeout)


def sent_commands(w) -> list[str]:
    names: list[str] = []
    w.adapter.commandSent.connect(names.append)
    return names


def test_popups_centre_the_sticks_and_a_release_counts_anywhere(qtbot, sim, flying, window):
    w = window
    wait_flying(qtbot, w)
    # A menu opens while W is held: its release would go to the menu, so the sticks centre at once.
    qtbot.keyPress(w, Qt.Key_W)
    assert w.adapter.setpoint.forward > 0
    w.menuView.popup(w.mapToGlobal(QPoint(50, 30)))
    qtbot.waitUntil(lambda: QApplication.activePopupWidget() is not None, timeout=3000)
    assert w.adapter.setpoint.is_zero
    qtbot.keyRelease(QApplication.activePopupWidget(), Qt.Key_W)
    w.menuView.close()
    qtbot.waitUntil(lambda: QApplication.activePopupWidget() is None, timeout=3000)
    assert w.adapter.setpoint.is_zero
    qtbot.waitUntil(lambda: flying.state().setpoint.is_zero, timeout=2000)
    # The mode selector's list is a popup too.
    qtbot.keyPress(w, Qt.Key_D)
    assert w.adapter.setpoint.right > 0
    w.modeSelector.showPopup()
    qtbot.waitUntil(lambda: QApplication.activePopupWidget() is not None, timeout=3000)
    assert w.adapter.setpoint.is_zero
    qtbot.keyRelease(QApplication.activePopupWidget(), Qt.Key_D)
    w.modeSelector.hidePopup()
    qtbot.waitUntil(lambda: QApplication.activePopupWidget() is None, timeout=3000)
    assert w.adapter.setpoint.is_zero
    # A release delivered to some other widget still releases the key.
    w.activateWindow()
    qtbot.waitUntil(w.isActiveWindow, timeout=3000)
    qtbot.keyPress(w, Qt.Key_A)
    assert w.adapter.setpoint.right < 0
    other = QWidget()
    other.setAttribute(Qt.WA_ShowWithoutActivating)
    qtbot.addWidget(other)
    other.show()
    assert w.isActiveWindow() and w.adapter.setpoint.right < 0
    qtbot.keyRelease(other, Qt.Key_A)
    assert w.adapter.setpoint.is_zero


def test_space_and_enter_do_not_confirm_the_takeoff(qtbot, sim, window):
    w = window
    sent = sent_commands(w)
    qtbot.waitUntil(lambda: w.flightControls.main_button.isEnabled(), timeout=15000)
    for key in (Qt.Key_Space, Qt.Key_Return):
        qtbot.keyClick(w, Qt.Key_T)
        qtbot.waitUntil(lambda: w.flight.takeoff_box is not None and w.flight.takeoff_box.isVisible(), timeout=3000)
        box = w.flight.takeoff_box
        qtbot.waitUntil(lambda: box.isActiveWindow() and box.isAncestorOf(QApplication.focusWidget()),
                        timeout=3000)
        assert box.button(QMessageBox.Yes).focusPolicy() == Qt.NoFocus
        assert box.defaultButton() is box.button(QMessageBox.Cancel)
        qtbot.keyClick(QApplication.focusWidget(), key)
        assert box.clickedButton() is not box.button(QMessageBox.Yes)
        qtbot.waitUntil(lambda: w.flight.takeoff_box is None, timeout=3000)
    assert "takeoff" not in sent
    assert not w.adapter.state.takeoff.active


def test_space_and_l_do_nothing_while_their_buttons_are_disabled(qtbot, sim, window):
    w = window
    qtbot.waitUntil(lambda: w.flightControls.main_button.isEnabled()
                    and w.flightControls.main_button.text() == "Take off", timeout=15000)
    assert not w.flightControls.stop_button.isEnabled()
    sent = sent_commands(w)
    qtbot.keyClick(w, Qt.Key_Space)
    qtbot.keyClick(w, Qt.Key_L)
    assert sent == []


def test_saved_speeds_become_the_driver_limits_at_start(qtbot, silent_vehicle, viewer_settings, window_factory):
    save_settings(viewer_settings, ViewerSettings(max_horizontal=3.5, max_vertical=0.5, max_yaw_deg_s=30.0))
    w = window_factory(silent_vehicle)
    limits = silent_vehicle.limits
    assert (limits.horizontal, limits.vertical) == (3.5, 0.5)
    assert limits.yaw_rate == pytest.approx(math.radians(30.0))
    assert w.sticks.speeds.horizontal == 3.5 and w.sticks.speeds.yaw_deg_s == pytest.approx(30.0)
    dialog = SettingsDialog(w.settings, w)
    assert dialog.maxHorizontal.maximum() == CEILING.horizontal
    assert dialog.maxVertical.maximum() == CEILING.vertical
    assert dialog.maxYaw.maximum() == pytest.approx(math.degrees(CEILING.yaw_rate), abs=0.5)


def test_preferences_speeds_reach_the_driver(qtbot, sim, flying, window):
    w = window
    wait_flying(qtbot, w)
    w.actionPreferences.trigger()
    qtbot.waitUntil(lambda: w.findChild(SettingsDialog) is not None and w.findChild(SettingsDialog).isVisible(),
                    timeout=3000)
    dialog = w.findChild(SettingsDialog)
    dialog.maxHorizontal.setValue(4.0)
    dialog.buttons.button(QDialogButtonBox.Ok).click()
    assert flying.limits.horizontal == 4.0
    w.activateWindow()
    qtbot.waitUntil(w.isActiveWindow, timeout=3000)
    qtbot.keyPress(w, Qt.Key_W)
    assert w.adapter.setpoint.forward == pytest.approx(4.0)
    assert "fwd +4.0" in w.setpointLabel.text()
    qtbot.waitUntil(lambda: flying.state().setpoint.forward == pytest.approx(4.0), timeout=3000)
    qtbot.keyRelease(w, Qt.Key_W)
    assert w.adapter.setpoint.is_zero


def test_speeds_follow_what_the_driver_allows(qtbot, silent_vehicle, window_factory):
    """Asking for more than the ceiling: the sticks scale by the limits in force, not the wish."""
    w = window_factory(silent_vehicle)
    w.preferences.set_settings(replace(w.settings, max_horizontal=25.0))
    assert silent_vehicle.limits.horizontal == CEILING.horizontal
    assert w.sticks.speeds.horizontal == CEILING.horizontal


def test_lost_link_in_flight_makes_the_sticks_inert_and_keys_need_a_fresh_press(
        qtbot, sim, vehicle_factory, window_factory):
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", loss_timeout=1.0)
    assert v.wait_for(lambda s: s.connected, 10)
    assert v.takeoff(3.0).result(timeout=60).ok
    w = window_factory(v, takeoff_altitude=3.0)
    wait_flying(qtbot, w)
    qtbot.keyPress(w, Qt.Key_A)
    assert w.adapter.setpoint.right < 0
    sim.faults.link_down = True
    qtbot.waitUntil(lambda: not w.rightStick.isEnabled(), timeout=10000)
    assert w.rightStick._hint == "No link" and w.leftStick._hint == "No link"
    assert w.adapter.setpoint.is_zero
    fc = w.flightControls
    assert fc.main_button.text() == "Land" and fc.main_button.isEnabled()
    assert fc.stop_button.isEnabled() and fc.rtl_button.isEnabled()
    qtbot.keyRelease(w, Qt.Key_A)
    qtbot.keyPress(w, Qt.Key_W)                          # held while the sticks are inert...
    assert w.adapter.setpoint.is_zero
    sim.faults.link_down = False
    wait_flying(qtbot, w, timeout=15000)
    assert w.adapter.setpoint.is_zero                    # ...does not fly when they come back
    qtbot.keyRelease(w, Qt.Key_W)
    qtbot.keyPress(w, Qt.Key_W)                          # a fresh press does
    assert w.adapter.setpoint.forward > 0
    qtbot.keyRelease(w, Qt.Key_W)


def test_a_takeoff_question_is_withdrawn_when_the_link_is_lost(qtbot, sim, vehicle_factory, window_factory):
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", loss_timeout=1.0)
    w = window_factory(v, takeoff_altitude=3.0)
    sent = sent_commands(w)
    qtbot.waitUntil(lambda: w.flightControls.main_button.isEnabled(), timeout=15000)
    qtbot.mouseClick(w.flightControls.main_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.flight.takeoff_box is not None and w.flight.takeoff_box.isVisible(), timeout=3000)
    clicked: list[str] = []
    w.flight.takeoff_box.buttonClicked.connect(lambda b: clicked.append(b.text()))
    sim.faults.link_down = True
    qtbot.waitUntil(lambda: w.flight.takeoff_box is None, timeout=10000)        # withdrawn, never answered
    assert clicked == []
    sim.faults.link_down = False
    qtbot.waitUntil(lambda: w.adapter.state.link.status.value == "ok"
                    and w.flightControls.main_button.isEnabled(), timeout=15000)
    assert "takeoff" not in sent and not sim.truth().armed


def test_scrolling_over_the_mode_selector_never_changes_the_mode(qtbot, sim, flying, window):
    from PyQt5.QtCore import QPointF
    from PyQt5.QtGui import QWheelEvent
    w = window
    wait_flying(qtbot, w)
    sent = sent_commands(w)
    sel = w.modeSelector
    for delta in (120, 120, -120):
        pos = QPointF(sel.width() / 2, sel.height() / 2)
        QApplication.sendEvent(sel, QWheelEvent(pos, QPointF(sel.mapToGlobal(pos.toPoint())), QPoint(0, 0),
                                                QPoint(0, delta), Qt.NoButton, Qt.NoModifier, Qt.NoScrollPhase,
                                                False))
    assert sent == [] and sel.mode == "GUIDED"
    assert w.adapter.state.mode == "GUIDED"


def test_the_attitude_indicator_flags_a_lost_link(qtbot, sim, vehicle_factory, window_factory):
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", loss_timeout=1.0)
    w = window_factory(v, takeoff_altitude=3.0)
    qtbot.waitUntil(lambda: w.attitude.values["valid"], timeout=10000)
    sim.faults.link_down = True
    qtbot.waitUntil(lambda: w.attitude.values["flag"] == "NO LINK", timeout=10000)
    assert w.attitude.values["altitude"] is None
    sim.faults.link_down = False
    qtbot.waitUntil(lambda: w.attitude.values["valid"] and w.attitude.values["altitude"] is not None,
                    timeout=15000)


def test_preferences_leave_stop_and_land_within_reach(qtbot, sim, flying, window):
    w = window
    wait_flying(qtbot, w)
    w.actionPreferences.trigger()
    qtbot.waitUntil(lambda: w.findChild(SettingsDialog) is not None and w.findChild(SettingsDialog).isVisible(),
                    timeout=3000)
    assert QApplication.activeModalWidget() is None
    sent = sent_commands(w)
    qtbot.mouseClick(w.flightControls.stop_button, Qt.LeftButton)
    assert sent == ["stop"]
    w.findChild(SettingsDialog).reject()


def test_minimising_centres_the_sticks(qtbot, sim, flying, window):
    w = window
    wait_flying(qtbot, w)
    w.rightStick.hold(0.0, 1.0)
    assert w.adapter.setpoint.forward > 0
    w.showMinimized()
    qtbot.waitUntil(lambda: w.adapter.setpoint.is_zero, timeout=3000)
    assert w.rightStick.position == (0.0, 0.0)
