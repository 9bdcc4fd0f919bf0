"""The attitude indicator draws known attitudes where a pilot expects them (pixel checks)."""
from __future__ import annotations

import math

import pytest
from PyQt5.QtGui import QColor

from uavviewer.widgets.attitude_indicator import AttitudeIndicator

W, H = 400, 300


@pytest.fixture
def ai(qtbot):
    w = AttitudeIndicator()
    qtbot.addWidget(w)
    w.resize(W, H)
    w.show()
    qtbot.waitExposed(w)
    return w


def kind(image, x: float, y: float) -> str:
    c = QColor(image.pixel(int(round(x)), int(round(y))))
    if c.blue() > c.red() + 40:
        return "sky"
    if c.red() > c.blue() + 40 and c.green() < c.red():
        return "ground"
    return f"other{c.getRgb()[:3]}"


def expected_horizon_y(ai, x: float, roll_deg: float, pitch_deg: float) -> float:
    """Independent of the widget's own helper: rotate the pitch-shifted line about the centre."""
    area = ai.horizon_rect()
    cx, cy = area.center().x(), area.center().y()
    ppd = area.height() / 2.0 / AttitudeIndicator.VISIBLE_PITCH_DEG
    r = math.radians(roll_deg)
    d = pitch_deg * ppd
    # horizon: points (u, d) rotated counter-clockwise on screen by r
    u = (x - cx - d * math.sin(r)) / math.cos(r)
    return cy - u * math.sin(r) + d * math.cos(r)


CASES = [(0, 0), (0, 10), (0, -10), (30, 0), (-30, 0), (20, -8), (-15, 12)]


@pytest.mark.parametrize("roll_deg,pitch_deg", CASES)
def test_horizon_position_and_angle(ai, roll_deg, pitch_deg):
    ai.set_attitude(math.radians(roll_deg), math.radians(pitch_deg), 0.0)
    img = ai.grab().toImage()
    cx = ai.horizon_rect().center().x()
    for dx in (-90, 90):
        x = cx + dx
        y = expected_horizon_y(ai, x, roll_deg, pitch_deg)
        assert abs(ai.horizon_y_at(x) - y) < 0.5
        # Perpendicular to the horizon: sky above it, ground below it.
        assert kind(img, x, y - 9) == "sky", (roll_deg, pitch_deg, dx)
        assert kind(img, x, y + 9) == "ground", (roll_deg, pitch_deg, dx)


def test_nose_up_moves_horizon_down(ai):
    cx, cy = ai.centre().x(), ai.centre().y()
    ai.set_attitude(0.0, math.radians(10), 0.0)
    img = ai.grab().toImage()
    # Ten degrees nose up: the point just below the centre is still sky.
    assert kind(img, cx + 90, cy + 20) == "sky"
    ai.set_attitude(0.0, math.radians(-10), 0.0)
    img = ai.grab().toImage()
    assert kind(img, cx + 90, cy - 20) == "ground"


def test_right_roll_turns_horizon_left(ai):
    cx, cy = ai.centre().x(), ai.centre().y()
    ai.set_attitude(math.radians(30), 0.0, 0.0)
    img = ai.grab().toImage()
    # Right wing down: the horizon's right end rises (ground on the upper right), left end falls.
    assert kind(img, cx + 90, cy - 25) == "ground"
    assert kind(img, cx - 90, cy + 25) == "sky"


def test_unknown_attitude_shows_the_failure_flag_not_a_level_horizon(ai):
    cx, cy = ai.centre().x(), ai.centre().y()
    for unknown in ((float("nan"), 0.0), (0.0, float("inf"))):
        ai.set_attitude(0.1, 0.0, 10.0)
        assert ai.values["valid"]
        ai.set_attitude(unknown[0], unknown[1], 10.0)
        img = ai.grab().toImage()
        assert not ai.values["valid"]
        for x, y in ((cx + 90, cy - 30), (cx + 90, cy + 30), (cx - 90, cy + 30)):
            assert kind(img, x, y).startswith("other"), (x, y)      # neither sky nor ground
    ai.set_attitude(0.0, 0.0, 0.0)
    img = ai.grab().toImage()
    assert kind(img, cx + 90, cy - 9) == "sky" and kind(img, cx + 90, cy + 9) == "ground"
    ai.clear()
    assert kind(ai.grab().toImage(), cx + 90, cy - 30).startswith("other")
