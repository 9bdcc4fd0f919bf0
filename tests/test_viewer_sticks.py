"""Stick modes, deadband, expo, scaling and keyboard axes (no widgets)."""
from __future__ import annotations

import math

import pytest
from PyQt5.QtCore import Qt

from uavviewer.input.keyboard import KeyboardSticks, key_help
from uavviewer.input.sticks import (Axes, MaxSpeeds, StickMode, StickShaping, axes_from_pads, combine, shape,
                                    velocity_from_axes)


def test_deadband_zeroes_small_deflections_and_still_reaches_full():
    s = StickShaping(deadband=0.1)
    assert shape(0.09, s) == 0.0
    assert shape(-0.1, s) == 0.0
    assert shape(1.0, s) == 1.0
    assert shape(-1.0, s) == -1.0
    assert 0.0 < shape(0.15, s) < 0.1


def test_expo_softens_the_centre_and_keeps_the_ends():
    linear, expo = StickShaping(0.0, 0.0), StickShaping(0.0, 0.8)
    assert shape(0.5, expo) < shape(0.5, linear) == 0.5
    assert shape(1.0, expo) == 1.0
    values = [shape(i / 20, expo) for i in range(21)]
    assert values == sorted(values)


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf")])
def test_non_finite_is_zero(bad):
    assert shape(bad) == 0.0
    assert velocity_from_axes(Axes(forward=bad, yaw=bad)).forward == 0.0


def test_mode2_mapping():
    a = axes_from_pads(StickMode.MODE2, left=(0.5, -1.0), right=(1.0, 0.8), shaping=StickShaping(0, 0))
    assert a == Axes(forward=0.8, right=1.0, up=-1.0, yaw=0.5)


def test_mode1_and_2017_mapping():
    none = StickShaping(0, 0)
    assert axes_from_pads(StickMode.MODE1, (0.5, 0.8), (1.0, -1.0), none) == Axes(0.8, 1.0, -1.0, 0.5)
    assert axes_from_pads(StickMode.VIEWER2017, (0.5, 0.8), (1.0, -1.0), none) == Axes(0.8, 0.5, -1.0, 1.0)


def test_scaling_to_speeds():
    v = velocity_from_axes(Axes(1.0, -0.5, 1.0, 1.0), MaxSpeeds(2.0, 1.0, 45.0))
    assert v.forward == 2.0 and v.right == -1.0 and v.up == 1.0
    assert v.yaw_rate == pytest.approx(math.radians(45))


def test_combine_clamps():
    assert combine(Axes(forward=0.8), Axes(forward=1.0)).forward == 1.0


def test_keyboard_axes_and_release():
    k = KeyboardSticks()
    assert k.press(Qt.Key_W) and k.press(Qt.Key_Right)
    assert k.axes() == Axes(forward=1.0, yaw=1.0)
    k.press(Qt.Key_S)                  # the latest of two opposite keys wins
    assert k.axes().forward == -1.0
    k.release(Qt.Key_S)
    assert k.axes().forward == 1.0
    k.release(Qt.Key_W)
    k.release(Qt.Key_Right)
    assert k.axes().is_zero
    assert not k.press(Qt.Key_T)       # an action key, not an axis


def test_key_help_lists_every_key():
    keys = [k for k, _ in key_help()]
    for name in ("W", "S", "A", "D", "↑", "↓", "←", "→", "Space", "T", "L"):
        assert name in keys
