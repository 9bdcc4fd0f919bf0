"""Where the vehicle's camera looks on the ground: its footprint and its look direction (pure geometry).

The camera sits ``altitude`` metres above flat ground at the vehicle, pitched as the gimbal reports (0 level,
-90 straight down) and turned to the vehicle's heading plus the gimbal's yaw. A corner ray that misses the
ground (at or above the horizon) is cut at ``MAX_RANGE``, so a level camera draws a long wedge, not infinity.
The field of view is the simulated camera's (90° across a 4:3 picture), which the default ``--sim`` shows.
"""
from __future__ import annotations

import math

__all__ = ["footprint", "look_point", "HFOV_DEG", "VFOV_DEG", "MAX_RANGE"]

HFOV_DEG = 90.0
VFOV_DEG = math.degrees(2 * math.atan(math.tan(math.radians(HFOV_DEG) / 2) * 3 / 4))   # 73.7° (4:3)
MAX_RANGE = 300.0        # m: where a ray that never meets the ground is cut


def _ray(pitch: float, yaw: float, right: float, up: float) -> tuple[float, float, float]:
    """NED direction of the picture point (right, up) in tangent units, for a camera at pitch/yaw (radians)."""
    fx, fz = math.cos(pitch), -math.sin(pitch)                 # forward, in the vertical plane of the yaw
    # the picture's "up", perpendicular to forward in the same plane: (-sin p, 0, -cos p) as (ahead, right, down)
    ahead = fx - up * math.sin(pitch)
    down = fz - up * math.cos(pitch)
    side = right
    c, s = math.cos(yaw), math.sin(yaw)
    return ahead * c - side * s, ahead * s + side * c, down


def _hit(direction, altitude: float) -> tuple[float, float]:
    n, e, d = direction
    horizontal = math.hypot(n, e)
    if d > 1e-6:
        distance = altitude / d
        if math.hypot(n, e) * distance <= MAX_RANGE:
            return n * distance, e * distance
    if horizontal < 1e-9:
        return 0.0, 0.0
    return n / horizontal * MAX_RANGE, e / horizontal * MAX_RANGE


def footprint(altitude: float, pitch_deg: float, heading_deg: float) -> list[tuple[float, float]] | None:
    """(north, east) metres from the vehicle of the picture's four corners on the ground, or None when the
    whole picture is above the horizon."""
    if not all(math.isfinite(v) for v in (altitude, pitch_deg, heading_deg)):
        return None
    h = max(altitude, 0.5)
    pitch, yaw = math.radians(pitch_deg), math.radians(heading_deg)
    tx, ty = math.tan(math.radians(HFOV_DEG) / 2), math.tan(math.radians(VFOV_DEG) / 2)
    corners = [_ray(pitch, yaw, right, up) for right, up in ((-tx, ty), (tx, ty), (tx, -ty), (-tx, -ty))]
    if all(d <= 0 for _, _, d in corners):
        return None
    return [_hit(c, h) for c in corners]


def look_point(altitude: float, pitch_deg: float, heading_deg: float) -> tuple[float, float, bool] | None:
    """(north, east, on_ground) of the picture's centre: where it meets the ground, or MAX_RANGE along it."""
    if not all(math.isfinite(v) for v in (altitude, pitch_deg, heading_deg)):
        return None
    direction = _ray(math.radians(pitch_deg), math.radians(heading_deg), 0.0, 0.0)
    n, e = _hit(direction, max(altitude, 0.5))
    return n, e, direction[2] > 1e-6 and math.hypot(n, e) < MAX_RANGE - 1e-6
