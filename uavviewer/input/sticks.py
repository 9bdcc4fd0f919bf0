"""From stick deflections to a velocity command, away from any widget so it can be tested.

Each pad gives a normalised ``(x, y)`` in [-1, 1] (x right, y up). A stick
*mode* decides which axis of which pad flies what; a deadband and optional expo
shape the deflection; maximum speeds scale it to m/s and rad/s.
"""
from __future__ import annotations

import enum
import math
from dataclasses import dataclass

__all__ = ["StickMode", "Axes", "StickShaping", "MaxSpeeds", "VelocityCommand", "shape",
           "axes_from_pads", "pad_labels", "velocity_from_axes", "combine"]


class StickMode(enum.Enum):
    """Which pad flies which axis (names as RC pilots know them)."""
    MODE2 = "mode2"          # left: climb + yaw;     right: forward + right
    MODE1 = "mode1"          # left: forward + yaw;   right: climb + right
    VIEWER2017 = "viewer2017"  # the 2017 viewer: left: forward + right; right: climb + yaw

    @property
    def title(self) -> str:
        return {StickMode.MODE2: "Mode 2 (left: climb/yaw, right: move)",
                StickMode.MODE1: "Mode 1 (left: forward/yaw, right: climb/sideways)",
                StickMode.VIEWER2017: "2017 viewer (left: move, right: climb/yaw)"}[self]


@dataclass(frozen=True)
class Axes:
    """Normalised pilot demand, each in [-1, 1]."""
    forward: float = 0.0
    right: float = 0.0
    up: float = 0.0
    yaw: float = 0.0          # + = nose right

    @property
    def is_zero(self) -> bool:
        return self.forward == 0.0 and self.right == 0.0 and self.up == 0.0 and self.yaw == 0.0


@dataclass(frozen=True)
class StickShaping:
    deadband: float = 0.05    # fraction of full deflection ignored around the centre
    expo: float = 0.0         # 0 = linear, 1 = fully cubic (finer control near the centre)


@dataclass(frozen=True)
class MaxSpeeds:
    horizontal: float = 2.0   # m/s at full deflection, forward and right
    vertical: float = 1.0     # m/s
    yaw_deg_s: float = 45.0   # deg/s


@dataclass(frozen=True)
class VelocityCommand:
    """What goes to ``Drone.set_velocity``: m/s and rad/s (+ = nose right)."""
    forward: float = 0.0
    right: float = 0.0
    up: float = 0.0
    yaw_rate: float = 0.0

    @property
    def is_zero(self) -> bool:
        return self.forward == 0.0 and self.right == 0.0 and self.up == 0.0 and self.yaw_rate == 0.0


def _clamp(v: float) -> float:
    if not math.isfinite(v):
        return 0.0
    return max(-1.0, min(1.0, v))


def shape(value: float, shaping: StickShaping = StickShaping()) -> float:
    """Deadband (rescaled so output still reaches ±1) then expo; NaN becomes 0."""
    v = _clamp(value)
    band = max(0.0, min(0.9, shaping.deadband))
    mag = abs(v)
    if mag <= band:
        return 0.0
    mag = (mag - band) / (1.0 - band)
    expo = max(0.0, min(1.0, shaping.expo))
    mag = (1.0 - expo) * mag + expo * mag ** 3
    return math.copysign(min(1.0, mag), v)


def axes_from_pads(mode: StickMode, left: tuple[float, float], right: tuple[float, float],
                   shaping: StickShaping = StickShaping()) -> Axes:
    """Pad positions (x, y) to pilot axes for a stick mode."""
    lx, ly = (shape(a, shaping) for a in left)
    rx, ry = (shape(a, shaping) for a in right)
    if mode is StickMode.MODE1:
        return Axes(forward=ly, right=rx, up=ry, yaw=lx)
    if mode is StickMode.VIEWER2017:
        return Axes(forward=ly, right=lx, up=ry, yaw=rx)
    return Axes(forward=ry, right=rx, up=ly, yaw=lx)


def pads_from_axes(mode: StickMode, axes: Axes) -> tuple[tuple[float, float], tuple[float, float]]:
    """Where pilot axes put the two pads' knobs in a stick mode: (left, right), each (x, y); the inverse of
    :func:`axes_from_pads` without shaping (keys and a gamepad shown on the screen's sticks)."""
    if mode is StickMode.MODE1:
        return (axes.yaw, axes.forward), (axes.right, axes.up)
    if mode is StickMode.VIEWER2017:
        return (axes.right, axes.forward), (axes.yaw, axes.up)
    return (axes.yaw, axes.up), (axes.right, axes.forward)


def pad_labels(mode: StickMode) -> tuple[str, str]:
    """What each pad flies, for the caption under it: (left, right)."""
    return {StickMode.MODE2: ("Climb · Yaw", "Forward · Sideways"),
            StickMode.MODE1: ("Forward · Yaw", "Climb · Sideways"),
            StickMode.VIEWER2017: ("Forward · Sideways", "Climb · Yaw")}[mode]


def combine(*demands: Axes) -> Axes:
    """Sum of several sources (two pads, the keyboard), each axis clamped to [-1, 1]."""
    return Axes(forward=_clamp(sum(d.forward for d in demands)),
                right=_clamp(sum(d.right for d in demands)),
                up=_clamp(sum(d.up for d in demands)),
                yaw=_clamp(sum(d.yaw for d in demands)))


def velocity_from_axes(axes: Axes, speeds: MaxSpeeds = MaxSpeeds()) -> VelocityCommand:
    """Scale normalised axes by the maximum speeds; yaw in rad/s."""
    return VelocityCommand(forward=_clamp(axes.forward) * speeds.horizontal,
                           right=_clamp(axes.right) * speeds.horizontal,
                           up=_clamp(axes.up) * speeds.vertical,
                           yaw_rate=math.radians(_clamp(axes.yaw) * speeds.yaw_deg_s))
