"""Closest approach of two straight, constant-speed tracks: pure functions, no clock, no state.

Positions are metres (north, east, up) of the contact from us, velocities m/s of the contact relative to us.
A conflict is a moment within the horizon when the contact is inside BOTH the horizontal radius and the vertical
band; the horizontal and vertical intervals are solved exactly (a quadratic and a linear inequality), so a
contact that passes close sideways but far above is no conflict, and one that climbs into our band while near is.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Approach", "AlertLimits", "closest_approach"]


@dataclass(frozen=True)
class AlertLimits:
    """When a contact alerts: projected within ``horizontal`` m and ``vertical`` m in the next ``horizon`` s."""
    horizontal: float = 500.0
    vertical: float = 150.0
    horizon: float = 60.0

    def problem(self) -> str:
        values = (self.horizontal, self.vertical, self.horizon)
        if not all(math.isfinite(v) and v > 0 for v in values):
            return "traffic alert limits must be positive finite numbers"
        return ""


@dataclass(frozen=True)
class Approach:
    time: float                  # s from now to the closest horizontal approach (0: now, it only gets farther)
    horizontal: float            # m at that time
    vertical: float              # m, the contact above (+) or below (-) us at that time
    conflict_in: float | None    # s until both limits are first broken together, None: not within the horizon

    @property
    def conflict(self) -> bool:
        return self.conflict_in is not None


def _inside_horizontal(px: float, py: float, vx: float, vy: float, radius: float) -> tuple[float, float] | None:
    """The times when |p + v t| <= radius (may be unbounded), None when never."""
    a = vx * vx + vy * vy
    b = 2.0 * (px * vx + py * vy)
    c = px * px + py * py - radius * radius
    if a < 1e-12:
        return (-math.inf, math.inf) if c <= 0 else None
    disc = b * b - 4 * a * c
    if disc < 0:
        return None
    root = math.sqrt(disc)
    return (-b - root) / (2 * a), (-b + root) / (2 * a)


def _inside_vertical(pz: float, vz: float, band: float) -> tuple[float, float] | None:
    if abs(vz) < 1e-9:
        return (-math.inf, math.inf) if abs(pz) <= band else None
    t1, t2 = (-band - pz) / vz, (band - pz) / vz
    return min(t1, t2), max(t1, t2)


def closest_approach(rel_pos: tuple[float, float, float], rel_vel: tuple[float, float, float],
                     limits: AlertLimits = AlertLimits()) -> Approach:
    """Where the contact will be nearest us horizontally within the horizon, and whether it conflicts."""
    px, py, pz = rel_pos
    vx, vy, vz = rel_vel
    speed2 = vx * vx + vy * vy
    t = 0.0 if speed2 < 1e-12 else min(max(-(px * vx + py * vy) / speed2, 0.0), limits.horizon)
    horizontal = math.hypot(px + vx * t, py + vy * t)
    conflict = None
    h = _inside_horizontal(px, py, vx, vy, limits.horizontal)
    v = _inside_vertical(pz, vz, limits.vertical)
    if h is not None and v is not None:
        start, end = max(h[0], v[0], 0.0), min(h[1], v[1], limits.horizon)
        if start <= end:
            conflict = start
    return Approach(t, horizontal, pz + vz * t, conflict)
