"""The thumb stick springs back, stays inside its ring, and lets go when the pointer leaves."""
from __future__ import annotations

import math

import pytest
from PyQt5.QtCore import QEvent, QPoint, QPointF, Qt
from PyQt5.QtGui import QMouseEvent
from PyQt5.QtWidgets import QApplication

from uavviewer.widgets.joystick_pad import JoystickPad


def mouse(widget, kind, pos: QPointF, button=Qt.LeftButton):
    buttons = Qt.NoButton if kind == QEvent.MouseButtonRelease else Qt.LeftButton
    ev = QMouseEvent(kind, QPointF(pos), button if kind != QEvent.MouseMove else Qt.NoButton, buttons,
                     Qt.NoModifier)
    QApplication.sendEvent(widget, ev)


@pytest.fixture
def pad(qtbot):
    w = JoystickPad()
    qtbot.addWidget(w)
    w.resize(240, 262)
    w.show()
    qtbot.waitExposed(w)
    return w


def test_press_drag_release_springs_back(qtbot, pad):
    moves = []
    pad.moved.connect(lambda x, y: moves.append((x, y)))
    mouse(pad, QEvent.MouseButtonPress, pad.point_for(0.0, 0.8))
    x, y = pad.position
    assert abs(x) < 0.02 and abs(y - 0.8) < 0.02
    mouse(pad, QEvent.MouseMove, pad.point_for(-0.5, 0.0))
    assert abs(pad.position[0] + 0.5) < 0.02 and abs(pad.position[1]) < 0.02
    mouse(pad, QEvent.MouseButtonRelease, pad.point_for(-0.5, 0.0))
    assert pad.position == (0.0, 0.0)
    assert moves[-1] == (0.0, 0.0)
    assert pad.knob_centre() == pad.point_for(0.0, 0.0)
    assert len(moves) == 3


def test_knob_stays_inside_the_ring(pad):
    mouse(pad, QEvent.MouseButtonPress, pad.point_for(0.0, 0.0))
    mouse(pad, QEvent.MouseMove, pad.point_for(1.2, 1.2))
    x, y = pad.position
    assert math.hypot(x, y) == pytest.approx(1.0, abs=0.01)
    assert x == pytest.approx(y, abs=0.01)


def test_sliding_off_the_pad_centres(pad):
    mouse(pad, QEvent.MouseButtonPress, pad.point_for(0.6, 0.0))
    assert pad.position[0] > 0.5
    mouse(pad, QEvent.MouseMove, QPointF(pad.width() + 30, pad.height() / 2))
    assert pad.position == (0.0, 0.0)
    assert not pad.dragging
    # Coming back without a new press does not grab the stick again.
    mouse(pad, QEvent.MouseMove, pad.point_for(0.6, 0.0))
    assert pad.position == (0.0, 0.0)


def test_leave_event_centres(pad):
    mouse(pad, QEvent.MouseButtonPress, pad.point_for(0.0, -0.7))
    QApplication.sendEvent(pad, QEvent(QEvent.Leave))
    assert pad.position == (0.0, 0.0)


def test_disabled_pad_is_inert_and_disabling_centres(pad):
    mouse(pad, QEvent.MouseButtonPress, pad.point_for(0.5, 0.5))
    assert pad.position != (0.0, 0.0)
    pad.setEnabled(False)
    assert pad.position == (0.0, 0.0)
    mouse(pad, QEvent.MouseButtonPress, pad.point_for(0.5, 0.5))
    assert pad.position == (0.0, 0.0)


def test_disabled_pad_is_greyed(pad):
    pad.set_hint("Take off to fly")
    enabled = pad.grab().toImage().pixelColor(QPoint(int(pad.knob_centre().x()), int(pad.knob_centre().y())))
    pad.setEnabled(False)
    disabled = pad.grab().toImage().pixelColor(QPoint(int(pad.knob_centre().x()), int(pad.knob_centre().y()) + 25))
    assert enabled.blue() > enabled.red() + 60          # live: blue knob
    assert abs(disabled.blue() - disabled.red()) < 20   # inert: grey


def test_hold_is_clamped_and_ignored_when_disabled(pad):
    pad.hold(2.0, 0.0)
    assert pad.position == (1.0, 0.0)
    pad.setEnabled(False)
    pad.hold(0.5, 0.5)
    assert pad.position == (0.0, 0.0)
