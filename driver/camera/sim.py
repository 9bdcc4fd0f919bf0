"""The simulated vehicle's camera: a synthetic view drawn from the vehicle's own state.

It renders what a forward camera would see from the attitude and local position the
driver reports (sky, horizon, a ground grid every few metres, the home pad), so the
picture tilts when the vehicle rolls and the grid slides past when it flies. It reads
only :class:`~driver.vehicle.state.VehicleState`, so it works the same in the viewer's
embedded driver and in the server.
"""
from __future__ import annotations

import math
import time
from typing import Callable

import cv2
import numpy as np

from ..vehicle.state import VehicleState
from .source import SourceFailed, VideoSource

__all__ = ["SimulatedCamera", "SimSource", "SKY", "GROUND"]

SKY = (110, 160, 225)           # R, G, B
GROUND = (70, 110, 60)
GRID = (150, 175, 130)
GRID_NORTH = (200, 80, 70)      # lines running north-south are tinted so the heading can be read
HOME_PAD = (230, 230, 230)


def _body_to_ned(roll: float, pitch: float, yaw: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw), math.sin(yaw)
    return np.array([
        [cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy],
        [cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy],
        [-sp, sr * cp, cr * cp],
    ])


class SimulatedCamera:
    """Pinhole camera on the vehicle's gimbal where the vehicle reports one (it follows the gimbal's pitch,
    so the horizon moves when the pilot tilts), else fixed to the body, looking forward and ``tilt_deg`` down."""

    def __init__(self, width: int = 640, height: int = 480, fov_deg: float = 90.0, tilt_deg: float = 0.0,
                 grid_spacing: float = 5.0, grid_radius: float = 150.0):
        self.width, self.height = int(width), int(height)
        self.focal = (self.width / 2) / math.tan(math.radians(fov_deg) / 2)
        self.cx, self.cy = self.width / 2, self.height / 2
        t = math.radians(tilt_deg)
        # columns: camera x (right), y (down), z (forward) expressed in body FRD
        self._cam_in_body = np.array([[0.0, -math.sin(t), math.cos(t)],
                                      [1.0, 0.0, 0.0],
                                      [0.0, math.cos(t), math.sin(t)]])
        self._level = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])   # gimbal frame: no tilt
        n = int(grid_radius // grid_spacing)
        self._offsets = np.arange(-n, n + 1) * grid_spacing
        self._spacing, self._radius = grid_spacing, grid_radius
        self._sky = np.empty((self.height, self.width, 3), np.uint8)
        self._sky[:] = SKY

    def render(self, state: VehicleState) -> np.ndarray:
        """A new RGB image of what the camera sees in ``state``."""
        a = state.attitude
        if state.local is not None:
            north, east, down = state.local.north, state.local.east, state.local.down
        else:
            north, east, down = 0.0, 0.0, -state.altitude
        values = (a.roll, a.pitch, a.yaw, north, east, down)
        if not all(math.isfinite(v) for v in values):
            raise ValueError("vehicle state is not finite")
        g = state.gimbal
        if g.pitch_deg is not None and math.isfinite(g.pitch_deg):
            # on a pitch gimbal (the recorded servo mount): pitch held in the earth's frame, yaw from the nose
            # (or from north), no roll axis: the picture still rolls with the vehicle
            yaw = math.radians(g.yaw_deg or 0.0) + (0.0 if g.yaw_earth else a.yaw)
            world_from_cam = _body_to_ned(a.roll, math.radians(g.pitch_deg), yaw) @ self._level
        else:
            world_from_cam = _body_to_ned(a.roll, a.pitch, a.yaw) @ self._cam_in_body
        eye = np.array([north, east, min(down, -0.3)])     # never below the ground
        img = self._sky.copy()
        self._draw_ground(img, world_from_cam)
        self._draw_grid(img, world_from_cam, eye)
        self._draw_home(img, world_from_cam, eye)
        return img

    # -- drawing ----------------------------------------------------------------------------
    def _draw_ground(self, img: np.ndarray, world_from_cam: np.ndarray) -> None:
        # a pixel sees the ground when its ray points down: a linear function of (u, v)
        w0, w1, w2 = world_from_cam[2]
        def down(u, v):
            return w0 * (u - self.cx) / self.focal + w1 * (v - self.cy) / self.focal + w2
        corners = [(0, 0), (self.width, 0), (self.width, self.height), (0, self.height)]
        poly = []
        for i, p in enumerate(corners):
            q = corners[(i + 1) % 4]
            dp, dq = down(*p), down(*q)
            if dp > 0:
                poly.append(p)
            if (dp > 0) != (dq > 0):
                t = dp / (dp - dq)
                poly.append((p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])))
        if len(poly) >= 3:
            pts = np.round(np.array(poly) * 16).astype(np.int32)
            cv2.fillPoly(img, [pts], GROUND, cv2.LINE_AA, shift=4)

    def _project(self, cam: np.ndarray) -> np.ndarray:
        return np.stack([self.cx + self.focal * cam[:, 0] / cam[:, 2],
                         self.cy + self.focal * cam[:, 1] / cam[:, 2]], axis=1)

    def _draw_segments(self, img, world_from_cam, eye, p0, p1, colour) -> None:
        near = 1.0   # keeps projected coordinates small enough for OpenCV's fixed point
        c0 = (p0 - eye) @ world_from_cam
        c1 = (p1 - eye) @ world_from_cam
        keep = (c0[:, 2] > near) | (c1[:, 2] > near)
        c0, c1 = c0[keep], c1[keep]
        if not len(c0):
            return
        # move the end behind the camera onto the near plane
        for a, b in ((c0, c1), (c1, c0)):
            behind = a[:, 2] < near
            t = (near - a[behind, 2]) / (b[behind, 2] - a[behind, 2])
            a[behind] = a[behind] + t[:, None] * (b[behind] - a[behind])
        q0, q1 = self._project(c0), self._project(c1)
        segs = np.stack([q0, q1], axis=1)
        cv2.polylines(img, np.round(segs * 16).astype(np.int32), False, colour, 1, cv2.LINE_AA, shift=4)

    def _draw_grid(self, img, world_from_cam, eye) -> None:
        s, r = self._spacing, self._radius
        base_n, base_e = math.floor(eye[0] / s) * s, math.floor(eye[1] / s) * s
        n_lines = base_n + self._offsets
        e_lines = base_e + self._offsets
        k = len(self._offsets)
        zeros = np.zeros(k)
        # lines of constant east run north-south
        p0 = np.stack([np.full(k, base_n - r), e_lines, zeros], axis=1)
        p1 = np.stack([np.full(k, base_n + r), e_lines, zeros], axis=1)
        self._draw_segments(img, world_from_cam, eye, p0, p1, GRID_NORTH)
        p0 = np.stack([n_lines, np.full(k, base_e - r), zeros], axis=1)
        p1 = np.stack([n_lines, np.full(k, base_e + r), zeros], axis=1)
        self._draw_segments(img, world_from_cam, eye, p0, p1, GRID)

    def _draw_home(self, img, world_from_cam, eye) -> None:
        angles = np.linspace(0, 2 * math.pi, 24, endpoint=False)
        ring = np.stack([1.5 * np.cos(angles), 1.5 * np.sin(angles), np.zeros_like(angles)], axis=1)
        cam = (ring - eye) @ world_from_cam
        if np.all(cam[:, 2] > 1.0):
            pts = np.round(self._project(cam) * 16).astype(np.int32)
            cv2.fillPoly(img, [pts], HOME_PAD, cv2.LINE_AA, shift=4)


class SimSource(VideoSource):
    """Frames rendered from ``state_fn()`` at ``fps``."""

    def __init__(self, state_fn: Callable[[], VehicleState], *, width: int = 640, height: int = 480,
                 fps: float = 30.0, name: str = "simulated camera"):
        super().__init__("sim", name)
        self.camera = SimulatedCamera(width, height)
        self._state_fn = state_fn
        self._period = 1.0 / fps
        self._next = 0.0

    @property
    def description(self) -> str:
        return "simulated camera"

    def _open(self) -> None:
        self._next = time.monotonic()

    def _read(self) -> np.ndarray | None:
        wait = self._next - time.monotonic()
        if wait > 0 and self._stop.wait(wait):
            return None
        self._next = max(self._next + self._period, time.monotonic() - self._period)
        try:
            state = self._state_fn()
            return self.camera.render(state)
        except ValueError as e:
            raise SourceFailed(f"simulated camera: {e}") from e
