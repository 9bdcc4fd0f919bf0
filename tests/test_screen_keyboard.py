"""A pilot flying by keyboard: the Take off and Arm questions could not be answered without the mouse (Enter means
Cancel), though Help › Keys says "T Take off"; and no control ever showed where the keyboard's focus was. Now T
answers the takeoff question (A the arm one), Enter and Esc still cancel, a held key never answers, and the focused
button wears a ring. Real window, real driver, real simulated vehicle.
"""
from __future__ import annotations

import pytest
from PyQt5 import sip
from PyQt5.QtCore import QEvent, Qt
from PyQt5.QtGui import QKeyEvent
from PyQt5.QtWidgets import QApplication, QMessageBox

from viewer_fixtures import app_style, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = [pytest.mark.timeout(90), pytest.mark.usefixtures("app_style")]


def asked(qtbot, box_of) -> QMessageBox:
    qtbot.waitUntil(lambda: box_of() is not None and box_of().isVisible(), timeout=5000)
    box = box_of()
    QApplication.setActiveWindow(box)
    return box


def held(box: QMessageBox, key: int, text: str) -> None:
    """A key held down: the platform's repeats of it."""
    for kind in (QEvent.KeyPress, QEvent.KeyRelease):
        QApplication.sendEvent(box, QKeyEvent(kind, key, Qt.NoModifier, text, True))


def test_t_asks_and_t_takes_off_while_enter_and_a_held_key_cancel_or_wait(qtbot, sim, vehicle, window_factory):
    w = window_factory(vehicle, takeoff_altitude=3.0)
    qtbot.waitUntil(lambda: w.adapter.state.readiness.ready_to_arm and w.flightControls.main_button.isEnabled(),
                    timeout=20000)
    qtbot.keyClick(w.centralWidget(), Qt.Key_T)                  # T: the takeoff question
    box = asked(qtbot, lambda: w.flight.takeoff_box)
    said = box.text()
    qtbot.keyClick(box, Qt.Key_Return)                           # Enter is Cancel
    qtbot.waitUntil(lambda: not box.isVisible(), timeout=3000)
    assert not w.adapter.state.armed and not w.adapter.state.takeoff.active

    qtbot.keyClick(w.centralWidget(), Qt.Key_T)
    box = asked(qtbot, lambda: w.flight.takeoff_box)
    held(box, Qt.Key_T, "t")                                     # T held since it asked: no answer
    QApplication.processEvents()
    assert box.isVisible() and not w.adapter.state.takeoff.active
    qtbot.keyClick(box, Qt.Key_T)                                # T again: take off, no mouse
    qtbot.waitUntil(lambda: w.adapter.state.armed, timeout=30000)
    assert sip.isdeleted(box) or not box.isVisible()
    assert "T: take off" in said                                 # and the question says so


def test_a_arms_from_the_arm_question(qtbot, sim, vehicle, window_factory):
    w = window_factory(vehicle)
    qtbot.waitUntil(lambda: w.adapter.state.readiness.ready_to_arm, timeout=20000)
    w.flight.request_mode("GUIDED")
    qtbot.waitUntil(lambda: w.adapter.state.mode == "GUIDED", timeout=10000)
    qtbot.mouseClick(w.flightControls.arm_button, Qt.LeftButton)
    box = asked(qtbot, lambda: w.flight.arm_box)
    said, default = box.text(), box.defaultButton() is box.button(QMessageBox.Cancel)
    qtbot.keyClick(box, Qt.Key_A)
    qtbot.waitUntil(lambda: w.adapter.state.armed, timeout=20000)
    assert "A: arm" in said and default


def test_the_focused_button_wears_a_ring(qtbot, sim, vehicle, window_factory):
    w = window_factory(vehicle)
    qtbot.waitUntil(lambda: w.flightControls.main_button.isEnabled(), timeout=20000)
    qtbot.mouseClick(w.flightControls.main_button, Qt.LeftButton)
    box = asked(qtbot, lambda: w.flight.takeoff_box)
    cancel = box.button(QMessageBox.Cancel)
    qtbot.waitUntil(cancel.hasFocus, timeout=3000)
    focused = cancel.grab().toImage()
    cancel.clearFocus()
    qtbot.waitUntil(lambda: not cancel.hasFocus(), timeout=3000)
    assert cancel.grab().toImage() != focused, "the focused Cancel looks as it does without the focus"
    box.reject()
