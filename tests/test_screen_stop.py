"""Issue 21, problem 5: Stop outside GUIDED means "hold here, and the sticks are mine again": after RTL then Stop
(or Escape in LOITER) the next stick or key input flies, without picking GUIDED from the list.

Real simulator, real driver, real window.
"""
from __future__ import annotations

import pytest
from PyQt5.QtCore import Qt

from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def test_rtl_then_stop_gives_the_sticks_back(qtbot, sim, flying, window_factory):
    w = window_factory(flying)
    qtbot.waitUntil(lambda: w.leftStick.isEnabled(), timeout=20000)
    qtbot.mouseClick(w.flightControls.rtl_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: flying.state().mode == "RTL" and not w.leftStick.isEnabled(), timeout=10000)
    qtbot.mouseClick(w.flightControls.stop_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.leftStick.isEnabled() and flying.state().can_fly_velocity, timeout=10000)
    assert sim.truth().mode == "GUIDED"
    qtbot.keyPress(w, Qt.Key_W)                                # the next key flies
    qtbot.waitUntil(lambda: flying.state().setpoint.forward > 0, timeout=3000)
    qtbot.waitUntil(lambda: sim.truth().ground_speed > 0.3, timeout=10000)
    qtbot.keyRelease(w, Qt.Key_W)


def test_escape_in_loiter_holds_and_the_sticks_fly(qtbot, sim, flying, window_factory):
    w = window_factory(flying)
    assert flying.set_mode("LOITER").result(timeout=10).ok
    qtbot.waitUntil(lambda: not w.leftStick.isEnabled(), timeout=10000)
    assert "GUIDED" in w.leftStick._hint
    qtbot.keyClick(w, Qt.Key_Escape)
    qtbot.waitUntil(lambda: w.rightStick.isEnabled() and sim.truth().mode == "GUIDED", timeout=10000)
