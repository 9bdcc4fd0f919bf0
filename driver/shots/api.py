"""The smart shots as any front end calls them: the same typed calls on the embedded driver and over Ice.

``drone.shots`` is a :class:`Shots`: :class:`~driver.shots.control.ShotControl` on the embedded driver, the Ice
client's proxy of the server's (driver.ice.client), or :data:`NO_SHOTS` where neither exists. Every call returns
at once: a Future of a :class:`~driver.core.results.CommandResult` (ACCEPTED once the shot started flying or the
request was taken; REJECTED/REFUSED with the vehicle's or the driver's reason). What the shot does is in
``drone.state().shot`` (:class:`~driver.shots.model.ShotState`), read from the vehicle's telemetry.
"""
from __future__ import annotations

from concurrent.futures import Future

from ..core.results import CommandResult, CommandStatus, answered
from .model import Keyframe, ShotState, load_cable, save_cable

__all__ = ["Shots", "NO_SHOTS"]


class Shots:
    """The pilot's calls for smart shots. This base answers every one REJECTED (no shots on this connection)."""

    unavailable = "this vehicle connection runs no smart shots"
    state = ShotState()                   # what a client that reads it remotely holds (driver.ice.shots)

    def _no(self, name: str) -> Future:
        return answered(CommandResult(name, CommandStatus.REJECTED, self.unavailable))

    # -- the shots ----------------------------------------------------------------------------------------
    def orbit(self, lat: float | None = None, lon: float | None = None, alt: float = 0.0,
              radius: float | None = None, speed: float = 0.0, roi: bool = False) -> Future:
        """Circle (lat, lon) (alt m above home), or the region of interest the vehicle has (``roi``), or else the
        spot under the camera; at ``radius`` m (None: where the vehicle is), cruising at ``speed`` m/s
        (positive clockwise seen from above; 0: the sticks alone)."""
        return self._no("orbit")

    def cable(self, speed: float = 0.0, attach: int | None = None) -> Future:
        """Play the recorded keyframes: attach at keyframe ``attach`` (0-based; None: the nearest end), then cruise
        toward the far end at ``speed`` m/s (0: the sticks alone)."""
        return self._no("cable")

    def selfie(self, distance: float = 30.0, rise: float = 15.0, speed: float = 3.0,
               pilot: tuple[float, float] | None = None) -> Future:
        """Out ``distance`` m and up ``rise`` m away from the pilot at (lat, lon) (None: home), and back."""
        return self._no("selfie")

    def follow(self, source: str = "given", engine: str = "auto") -> Future:
        """Follow the target whose fixes come from ``source`` (a URL of :func:`driver.shots.targets.open_target`;
        "given": :meth:`follow_position`), by ArduCopter's FOLLOW mode or in GUIDED ("auto": FOLLOW where the
        vehicle has FOLL_ENABLE 1)."""
        return self._no("follow")

    def follow_position(self, lat: float, lon: float, alt: float | None = None, vn: float | None = None,
                        ve: float | None = None, vd: float = 0.0) -> bool:
        """A fix of the follow target (alt m above sea level; velocity m/s NED), for the "given" source."""
        return False

    def pano(self, shape: str = "cylinder", fov: float = 360.0, lens: float = 74.0, pitch: float = 0.0) -> Future:
        """Pictures in equal yaw steps (a cylinder over ``fov`` degrees at ``pitch``) or a sphere."""
        return self._no("pano")

    # -- during a shot ------------------------------------------------------------------------------------
    def sticks(self, forward: float, right: float, up: float, yaw: float) -> bool:
        """The pilot's sticks (-1..1 each) for the shot running; False when refused (not finite, no shot)."""
        return False

    def pause(self) -> Future:
        return self._no("shot pause")

    def resume(self) -> Future:
        return self._no("shot resume")

    def reverse(self) -> Future:
        return self._no("shot reverse")

    def set_cruise(self, speed: float) -> Future:
        return self._no("shot speed")

    def stop(self) -> Future:
        """End the shot and hold where the vehicle is (zero velocity in GUIDED)."""
        return self._no("shot stop")

    # -- keyframes ----------------------------------------------------------------------------------------
    def record_keyframe(self) -> Future:
        """Add where the vehicle is and where its camera looks as the cable's next keyframe."""
        return self._no("record keyframe")

    def set_keyframes(self, keyframes: tuple[Keyframe, ...]) -> Future:
        """Replace the cable's keyframes (a loaded cable; () clears them)."""
        return self._no("keyframes")

    def keyframes(self) -> tuple[Keyframe, ...]:
        return ()

    def save_cable(self, path: str) -> CommandResult:
        """Write the keyframes to ``path`` on this machine."""
        keys = self.keyframes()
        if not keys:
            return CommandResult("save cable", CommandStatus.REJECTED, "no keyframes recorded")
        try:
            save_cable(path, keys)
        except OSError as exc:
            return CommandResult("save cable", CommandStatus.REJECTED, str(exc))
        return CommandResult("save cable", CommandStatus.ACCEPTED, f"{len(keys)} keyframes to {path}")

    def load_cable(self, path: str) -> Future:
        """Read keyframes from ``path`` on this machine and make them the cable's."""
        try:
            keys = load_cable(path)
        except ValueError as exc:
            return answered(CommandResult("load cable", CommandStatus.REJECTED, str(exc)))
        return self.set_keyframes(keys)


NO_SHOTS = Shots()
