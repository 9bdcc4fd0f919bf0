"""The cable: a smooth curve through the pilot's keyframes, walked by distance, at a speed the airframe can fly.

* :class:`Spline` is a centripetal Catmull-Rom curve (Yuksel, Schaefer and Keyser's parametrisation: unlike the
  uniform one 3DR's Solo used, it never loops or cusps between keyframes that are close together), with a
  mirrored control point beyond each end so the cable starts and ends heading along its first and last legs.
  It is measured once (Gauss-Legendre quadrature on a fine grid) so that it is walked by arc length: a distance
  along it, not the curve's own parameter, is what a speed integrates.
* :class:`SpeedProfile` is the fastest speed at each distance that keeps the acceleration normal to the path
  within 1.75 m/s² (v²·κ) and, together with the tangential acceleration, within 2.0 m/s² overall: the tangential
  share is √(2.0² − 1.75²) ≈ 0.97 m/s², the Solo's own split. It plans to 80 % of each (:data:`PLAN_SHARE`) and
  brakes in time for each bend and for either end.
* :class:`PathRun` walks a path on that profile: the pilot (or a cruise speed) asks for a speed, forward or back;
  the run accelerates toward it no faster than the tangential share and never above the profile, so pausing,
  reversing and stopping at an end are all within the limits.

Coordinates are metres from home: (north, east, up). Everything here is pure: no clock, no I/O.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

__all__ = ["Spline", "SpeedProfile", "PathRun", "Looks", "ACCEL_LIMIT", "NORMAL_ACCEL_LIMIT", "TANGENT_ACCEL_LIMIT",
           "PLANNED_NORMAL", "PLANNED_TANGENT", "MIN_KEYFRAME_SPACING"]

ACCEL_LIMIT = 2.0                 # m/s² overall (shotmanager's ACCEL_LIMIT)
NORMAL_ACCEL_LIMIT = 1.75         # m/s² normal to the path (NORM_ACCEL_LIMIT)
TANGENT_ACCEL_LIMIT = math.sqrt(ACCEL_LIMIT ** 2 - NORMAL_ACCEL_LIMIT ** 2)    # ≈ 0.968 m/s² along it
#: What a shot plans to: 80 % of each limit, so that what the vehicle flies, its own corrections on top, stays
#: within them, and its lag behind a turning path stays small (ArduCopter's guided target takes no acceleration
#: with a global position, so it lags in proportion to the path's). Measured on the bench's cable: at 100 % the
#: simulator flew 2.04 m/s² (averaged over 0.5 s); at 90 % real ArduCopter 4.6.3 SITL flew 1.94 m/s² and strayed
#: 0.53 m RMS from the path.
PLAN_SHARE = 0.8
PLANNED_NORMAL = NORMAL_ACCEL_LIMIT * PLAN_SHARE
PLANNED_TANGENT = math.sqrt((ACCEL_LIMIT * PLAN_SHARE) ** 2 - PLANNED_NORMAL ** 2)
MIN_KEYFRAME_SPACING = 1.0        # m: two keyframes closer than this are one place
GRID = 96                         # quadrature intervals a segment
_GL_X = np.array([0.0, -0.5384693101056831, 0.5384693101056831, -0.9061798459386640, 0.9061798459386640])
_GL_W = np.array([0.5688888888888889, 0.4786286704993665, 0.4786286704993665, 0.2369268850561891, 0.2369268850561891])

Point = Sequence[float]


class Spline:
    """A centripetal Catmull-Rom curve through 2 or more points (north, east, up), walked by arc length."""

    def __init__(self, points: Sequence[Point]):
        pts = np.asarray(points, dtype=float)
        if pts.ndim != 2 or pts.shape[0] < 2 or pts.shape[1] != 3 or not np.all(np.isfinite(pts)):
            raise ValueError("a cable needs at least two finite points (north, east, up)")
        gaps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
        if np.any(gaps < MIN_KEYFRAME_SPACING):
            i = int(np.argmin(gaps))
            raise ValueError(f"keyframes {i + 1} and {i + 2} are {gaps[i]:.1f} m apart: at least "
                             f"{MIN_KEYFRAME_SPACING:g} m, or they are one place")
        self.points = pts
        ext = np.vstack([2 * pts[0] - pts[1], pts, 2 * pts[-1] - pts[-2]])
        self._coef = np.array([_hermite(*ext[i:i + 4]) for i in range(len(pts) - 1)])   # (segments, 4, 3)
        self.segments = len(pts) - 1
        # the arc-length table: global parameter g = segment + u, and the distance to it
        g = np.linspace(0.0, self.segments, self.segments * GRID + 1)
        lo, hi = g[:-1], g[1:]
        half, mid = (hi - lo) / 2.0, (hi + lo) / 2.0
        nodes = mid[:, None] + half[:, None] * _GL_X[None, :]
        speed = np.linalg.norm(self.derivative(nodes.ravel()), axis=1).reshape(nodes.shape)
        pieces = half * (speed * _GL_W[None, :]).sum(axis=1)
        self._g = g
        self._s = np.concatenate([[0.0], np.cumsum(pieces)])
        self._xyz = self.position_at(g)
        self.length = float(self._s[-1])
        #: the distance along the cable of each keyframe
        self.keyframe_s = tuple(float(self._s[i * GRID]) for i in range(len(pts)))

    # -- by the curve's own parameter g = segment + u ---------------------------------------------------
    def _split(self, g):
        g = np.clip(np.asarray(g, dtype=float), 0.0, float(self.segments))
        seg = np.minimum(np.floor(g).astype(int), self.segments - 1)
        return seg, g - seg

    def position_at(self, g) -> np.ndarray:
        seg, u = self._split(g)
        a, b, c, d = (self._coef[seg, k] for k in range(4))
        u = u[..., None]
        return ((a * u + b) * u + c) * u + d

    def derivative(self, g) -> np.ndarray:
        seg, u = self._split(g)
        a, b, c = (self._coef[seg, k] for k in range(3))
        u = u[..., None]
        return (3 * a * u + 2 * b) * u + c

    def second_derivative(self, g) -> np.ndarray:
        seg, u = self._split(g)
        a, b = self._coef[seg, 0], self._coef[seg, 1]
        return 6 * a * u[..., None] + 2 * b

    # -- by distance along the cable -------------------------------------------------------------------
    def param(self, s):
        """The curve's parameter g at distance ``s`` (clamped to the cable)."""
        return np.interp(np.clip(s, 0.0, self.length), self._s, self._g)

    def distance(self, g):
        """The distance along the cable at parameter ``g``."""
        return np.interp(np.clip(g, 0.0, self.segments), self._g, self._s)

    def point(self, s: float) -> tuple[float, float, float]:
        return tuple(float(v) for v in self.position_at(self.param(s)))

    def tangent(self, s: float) -> tuple[float, float, float]:
        d = self.derivative(self.param(s))
        n = float(np.linalg.norm(d))
        return tuple(float(v) / n for v in d) if n > 1e-9 else (0.0, 0.0, 0.0)

    def curvature(self, s):
        """κ (1/m) at distance ``s`` (scalar or array)."""
        g = self.param(s)
        d1, d2 = self.derivative(g), self.second_derivative(g)
        speed = np.linalg.norm(d1, axis=-1)
        return np.linalg.norm(np.cross(d1, d2), axis=-1) / np.maximum(speed, 1e-9) ** 3

    def sample(self, step: float) -> list[tuple[float, float, float]]:
        """Points every ``step`` metres from start to end (both included): for drawing and for the limits."""
        count = max(2, int(math.ceil(self.length / max(step, 0.01))) + 1)
        return [tuple(float(v) for v in p) for p in self.position_at(self.param(np.linspace(0, self.length, count)))]

    def nearest(self, point: Point) -> float:
        """The distance along the cable of the point of it nearest ``point``: how far a vehicle there has come."""
        p = np.asarray(point, dtype=float)
        i = int(np.argmin(np.sum((self._xyz - p) ** 2, axis=1)))
        lo, hi = self._g[max(i - 1, 0)], self._g[min(i + 1, len(self._g) - 1)]
        for _ in range(30):                      # golden section on the squared distance
            m1, m2 = hi - (hi - lo) * 0.618, lo + (hi - lo) * 0.618
            if np.sum((self.position_at(m1) - p) ** 2) < np.sum((self.position_at(m2) - p) ** 2):
                hi = m2
            else:
                lo = m1
        return float(self.distance((lo + hi) / 2.0))


def _hermite(p0, p1, p2, p3) -> np.ndarray:
    """Cubic coefficients (a, b, c, d) of the centripetal segment p1→p2, for u in [0, 1]."""
    t01, t12, t23 = (max(float(np.linalg.norm(q - p)) ** 0.5, 1e-6) for p, q in ((p0, p1), (p1, p2), (p2, p3)))
    m1 = t12 * ((p1 - p0) / t01 - (p2 - p0) / (t01 + t12) + (p2 - p1) / t12)
    m2 = t12 * ((p2 - p1) / t12 - (p3 - p1) / (t12 + t23) + (p3 - p2) / t23)
    return np.array([2 * p1 - 2 * p2 + m1 + m2, -3 * p1 + 3 * p2 - 2 * m1 - m2, m1, p1])


class Looks:
    """The camera's look along the cable: each keyframe's (pitch, yaw) in degrees, interpolated with the same
    segments as the cable (a uniform Catmull-Rom over pitch and the yaw unwrapped the short way round), so the
    look at each keyframe is exactly the one recorded there."""

    def __init__(self, looks: Sequence[tuple[float, float]]):
        if len(looks) < 2:
            raise ValueError("two looks at least")
        pitch = [float(p) for p, _ in looks]
        yaw = [float(looks[0][1])]
        for _, y in looks[1:]:
            yaw.append(yaw[-1] + ((float(y) - yaw[-1] + 180.0) % 360.0 - 180.0))
        pts = np.column_stack([pitch, yaw])
        ext = np.vstack([2 * pts[0] - pts[1], pts, 2 * pts[-1] - pts[-2]])
        self._coef = np.array([[ext[i + 1], 0.5 * (ext[i + 2] - ext[i]), ext[i + 2], 0.5 * (ext[i + 3] - ext[i + 1])]
                               for i in range(len(pts) - 1)])
        self.segments = len(pts) - 1

    def at(self, g: float) -> tuple[float, float]:
        """(pitch, yaw 0..360) at the cable's parameter ``g``."""
        g = min(max(float(g), 0.0), float(self.segments))
        seg = min(int(g), self.segments - 1)
        u = g - seg
        p1, m1, p2, m2 = self._coef[seg]
        h = ((2 * u - 3) * u * u + 1, ((u - 2) * u + 1) * u, (3 - 2 * u) * u * u, (u - 1) * u * u)
        pitch, yaw = h[0] * p1 + h[1] * m1 + h[2] * p2 + h[3] * m2
        return min(max(float(pitch), -90.0), 0.0), float(yaw) % 360.0


class SpeedProfile:
    """The fastest speed (m/s) at each distance along ``spline``, going forward (toward its end) or back."""

    def __init__(self, spline: Spline, max_speed: float, step: float = 0.2,
                 normal_accel: float = PLANNED_NORMAL, tangent_accel: float = PLANNED_TANGENT):
        if not (max_speed > 0 and normal_accel > 0 and tangent_accel > 0):
            raise ValueError("speeds and accelerations are positive")
        self.spline, self.max_speed, self.tangent_accel = spline, float(max_speed), float(tangent_accel)
        n = max(2, int(math.ceil(spline.length / step)) + 1)
        self._s = np.linspace(0.0, spline.length, n)
        ds = self._s[1] - self._s[0] if n > 1 else 0.0
        fine = np.linspace(0.0, spline.length, 4 * (n - 1) + 1)
        kappa = spline.curvature(fine)
        padded = np.concatenate([np.full(4, kappa[0]), kappa, np.full(4, kappa[-1])])
        window = np.max(np.stack([padded[k:k + len(kappa)] for k in range(9)]), axis=0)[::4]   # max within ±ds
        bend = np.minimum(self.max_speed, np.sqrt(normal_accel / np.maximum(window, 1e-9)))
        self.bend = bend
        two_a_ds = 2.0 * tangent_accel * ds
        fwd, back = bend.copy(), bend.copy()
        fwd[-1] = 0.0                         # going forward: stopped at the end
        for i in range(n - 2, -1, -1):
            fwd[i] = min(fwd[i], math.sqrt(fwd[i + 1] ** 2 + two_a_ds))
        back[0] = 0.0                         # going back: stopped at the start
        for i in range(1, n):
            back[i] = min(back[i], math.sqrt(back[i - 1] ** 2 + two_a_ds))
        self._fwd, self._back = fwd, back

    def limit(self, s: float, forward: bool) -> float:
        return float(np.interp(s, self._s, self._fwd if forward else self._back))

    def duration(self, speed: float) -> float:
        """Seconds from end to end at a cruise of ``speed`` (within the profile): for the pilot's planning."""
        v = np.minimum(np.minimum(self._fwd, self._back), max(speed, 0.05))
        v = np.maximum(v, 0.05)
        return float(np.trapezoid(1.0 / v, self._s)) if len(self._s) > 1 else 0.0


@dataclass
class PathRun:
    """Where a vehicle walking ``profile``'s path is (``s``, m) and how fast (``speed``, m/s, negative going back).
    :meth:`step` moves it on by ``dt`` toward the ``wanted`` speed, within the profile and the tangential limit."""
    profile: SpeedProfile
    s: float = 0.0
    speed: float = 0.0
    accel: float = 0.0                    # m/s² along the path of the last step

    def step(self, dt: float, wanted: float) -> None:
        prof = self.profile
        length = prof.spline.length
        dv = prof.tangent_accel * dt
        ahead = self.s + self.speed * dt          # the limit where this step ends: a step's rounding stays inside
        if wanted > 0:
            wanted = min(wanted, max(prof.limit(ahead, True) - 0.5 * dv, 0.0) or min(dv, (length - self.s) / dt))
        elif wanted < 0:
            wanted = max(wanted, -(max(prof.limit(ahead, False) - 0.5 * dv, 0.0) or min(dv, self.s / dt)))
        new = min(max(wanted, self.speed - dv), self.speed + dv)
        new = 0.0 if abs(new) < 1e-9 else new
        self.accel = (new - self.speed) / dt if dt > 0 else 0.0
        self.s = min(max(self.s + 0.5 * (self.speed + new) * dt, 0.0), length)
        self.speed = new
        if (self.s >= length and self.speed > 0) or (self.s <= 0.0 and self.speed < 0):
            self.speed = 0.0                  # at an end (within a step's rounding of the braking curve)

    def velocity(self) -> tuple[float, float, float]:
        t = self.profile.spline.tangent(self.s)
        return tuple(self.speed * v for v in t)

    @property
    def at_end(self) -> bool:
        return self.s >= self.profile.spline.length - 0.05

    @property
    def at_start(self) -> bool:
        return self.s <= 0.05
