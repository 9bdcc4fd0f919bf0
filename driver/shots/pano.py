"""Pano: turn in equal steps and take a picture at each, holding the place (the Solo's Pano).

* **cylinder**: yaw steps across ``fov`` degrees (360: all round) at the gimbal's pitch, as many as the lens needs
  with a third of each picture overlapping the next;
* **sphere**: rows at 0°, -30° and -60° of pitch, each with the steps its circle needs, and one straight down.

At each step the nose turns to the step's heading and the gimbal to its pitch; once the vehicle's own heading
and gimbal report the look within :data:`AIMED` degrees and its turn has settled for :data:`SETTLE` s, a picture
is taken, and the step counts only when the camera confirms it (driver.payload: CAMERA_FEEDBACK,
CAMERA_IMAGE_CAPTURED or the GoPro's answer, never the ACK alone). A picture refused or never confirmed is asked
once more; a second failure ends the shot and says why. Done, it holds there.
"""
from __future__ import annotations

import math

from .base import Shot
from .model import ShotKind, ShotPhase, Sticks
from .setpoint import Target, aim_error, camera_look

__all__ = ["Pano", "cylinder_steps", "sphere_steps", "AIMED", "SETTLE", "OVERLAP"]

AIMED = 2.0                  # degrees from the step's look
SETTLE = 0.5                 # s steady before the picture
STILL = math.radians(3.0)    # rad/s: the turn has stopped
OVERLAP = 1.0 / 3.0          # of a picture shared with the next
TURN_TIMEOUT = 30.0          # s for the vehicle to turn to a step
SPHERE_ROWS = (0.0, -30.0, -60.0)


def cylinder_steps(heading: float, fov: float, lens: float, pitch: float) -> list[tuple[float, float]]:
    """(yaw, pitch) of each picture across ``fov`` degrees centred on ``heading``, with a ``lens`` degrees wide."""
    fov = min(max(fov, lens), 360.0)
    advance = lens * (1.0 - OVERLAP)
    if fov >= 360.0:
        n = max(3, math.ceil(360.0 / advance))
        return [((heading + i * 360.0 / n) % 360.0, pitch) for i in range(n)]
    span = fov - lens                           # between the first and the last picture's centres
    n = max(2, math.ceil(span / advance) + 1)
    return [((heading - span / 2 + i * span / (n - 1)) % 360.0, pitch) for i in range(n)]


def sphere_steps(heading: float, lens: float) -> list[tuple[float, float]]:
    out = []
    for row in SPHERE_ROWS:
        circle = 360.0 * math.cos(math.radians(row))
        n = max(1, math.ceil(circle / (lens * (1.0 - OVERLAP))))
        out += [((heading + i * 360.0 / n) % 360.0, row) for i in range(n)]
    return out + [(heading % 360.0, -90.0)]


class Pano(Shot):
    kind = ShotKind.PANO

    def __init__(self, start: tuple[float, float, float], heading: float, take_photo, shape: str = "cylinder",
                 fov: float = 360.0, lens: float = 74.0, pitch: float = 0.0):
        """``take_photo()`` returns a Future of a CommandResult that resolves on the camera's confirmation."""
        super().__init__()
        if shape not in ("cylinder", "sphere"):
            raise ValueError("a pano is a cylinder or a sphere")
        if not (20.0 <= lens <= 180.0 and 30.0 <= fov <= 360.0 and -90.0 <= pitch <= 0.0):
            raise ValueError("lens 20-180°, fov 30-360°, pitch -90-0°")
        self.start, self.heading, self.take_photo = start, heading % 360.0, take_photo
        self.steps = cylinder_steps(heading, fov, lens, pitch) if shape == "cylinder" else sphere_steps(heading, lens)
        self.index = 0
        self.photos = 0
        self._settled: float | None = None
        self._turn_started: float | None = None
        self._photo = None
        self._tries = 0
        self.failure = ""

    def step(self, now: float, dt: float, state, sticks: Sticks) -> Target:
        if self.phase is ShotPhase.DONE or self.index >= len(self.steps):
            if self.phase is not ShotPhase.DONE:
                self.phase, self.detail = ShotPhase.DONE, f"{self.photos} pictures taken: done"
            return Target(*self.start, yaw=self.heading, pitch=self.steps[0][1])
        yaw, pitch = self.steps[self.index]
        if self.phase is ShotPhase.PAUSED:
            self._settled = self._turn_started = None
            return Target(*self.start, yaw=yaw, pitch=pitch)
        if self._photo is not None:
            self._collect()
        elif self._aimed(state, yaw, pitch, now):
            self._photo, self._tries = self.take_photo(), self._tries + 1
        elif self._turn_started is not None and now - self._turn_started > TURN_TIMEOUT:
            self.failure = (f"the vehicle did not turn to {yaw:.0f}° and {pitch:.0f}° in {TURN_TIMEOUT:g} s "
                            f"(heading {state.heading_deg:.0f}°)")
        return Target(*self.start, yaw=yaw, pitch=pitch)

    def _aimed(self, state, yaw: float, pitch: float, now: float) -> bool:
        if self._turn_started is None:
            self._turn_started = now
        error = aim_error(camera_look(state), pitch, yaw)
        if error is None or error > AIMED or abs(state.attitude.yawspeed) > STILL:
            self._settled = None
            return False
        if self._settled is None:
            self._settled = now
        return now - self._settled >= SETTLE

    def _collect(self) -> None:
        if not self._photo.done():
            return
        result, self._photo = self._photo.result(), None
        if result.ok:
            self.photos += 1
            self.index += 1
            self._settled = self._turn_started = None
            self._tries = 0
        elif self._tries >= 2:
            self.failure = f"picture {self.index + 1} of {len(self.steps)} not taken: {result.reason or result.status.value}"

    def report(self, state) -> dict:
        if self.phase is ShotPhase.FLYING and self.index < len(self.steps):
            yaw, pitch = self.steps[self.index]
            self.detail = f"picture {self.index + 1} of {len(self.steps)}: {yaw:.0f}°, {pitch:.0f}°"
        aim = None
        if self.index < len(self.steps):
            aim = aim_error(camera_look(state), self.steps[self.index][1], self.steps[self.index][0])
        return {"photos": self.photos, "photos_total": len(self.steps), "aim_error": aim}
