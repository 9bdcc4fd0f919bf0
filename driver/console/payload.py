"""The console's payload verbs (mixed into :class:`driver.console.console.Console`): gimbal, roi, camera."""
from __future__ import annotations

from .words import number


__all__ = ["PayloadCommands", "gimbal_line"]

GIMBAL_USAGE = "gimbal pitch DEG [YAW] | gimbal rate DEG_S [YAW_S] | gimbal level | gimbal down | gimbal"
ROI_USAGE = "roi LAT LON [ALT] | roi none"
CAMERA_USAGE = "camera shoot | camera record on|off | camera"


def gimbal_line(s) -> str:
    """"gimbal -45° (angle), by gimbal manager; camera: MAVLink camera SimCam, 2 pictures, not recording"."""
    g, c = s.gimbal, s.camera
    text = f"gimbal {g.describe()}" + (f", by {g.protocol}" if g.protocol else "")
    if g.roi is not None:
        text += f", looking at {g.roi[0]:.6f}, {g.roi[1]:.6f}"
    recording = {True: "recording", False: "not recording", None: "recording unknown"}[c.recording]
    return text + f"; camera: {c.kind.value}{' ' + c.name if c.name else ''}, {c.photos} pictures, {recording}"


class PayloadCommands:
    """``self.vehicle`` is a :class:`~driver.vehicle.api.Drone`; ``self._report(future)`` prints its result."""

    def do_gimbal(self, arg: str) -> None:
        """gimbal pitch DEG [YAW] | gimbal rate DEG_S [YAW_S] | gimbal level | gimbal down: point the camera
        (0 level, -90 straight down; a positive rate tilts up, 0 stops); "gimbal" alone shows it"""
        words = arg.split()
        if not words:
            self.say(gimbal_line(self.vehicle.state()))
        elif words[0] == "pitch" and len(words) in (2, 3):
            yaw = number(words[2], "YAW") if len(words) == 3 else None
            self._report(self.vehicle.point_gimbal(number(words[1], "DEG"), yaw))
        elif words[0] == "rate" and len(words) in (2, 3):
            yaw = number(words[2], "YAW_S") if len(words) == 3 else 0.0
            self._report(self.vehicle.gimbal_rate(number(words[1], "DEG_S"), yaw))
        elif words == ["level"]:
            self._report(self.vehicle.point_gimbal(0.0))
        elif words == ["down"]:
            self._report(self.vehicle.point_gimbal(-90.0))
        else:
            raise ValueError(f"usage: {GIMBAL_USAGE}")

    def do_roi(self, arg: str) -> None:
        """roi LAT LON [ALT] | roi none: look at a point (ALT m above home, default 0), or stop looking"""
        words = arg.split()
        if words == ["none"]:
            self._report(self.vehicle.stop_looking())
        elif len(words) in (2, 3):
            alt = number(words[2], "ALT") if len(words) == 3 else 0.0
            self._report(self.vehicle.look_at(number(words[0], "LAT"), number(words[1], "LON"), alt))
        else:
            raise ValueError(f"usage: {ROI_USAGE}")

    def do_camera(self, arg: str) -> None:
        """camera shoot | camera record on|off: a picture or video on the vehicle's camera (counted only when
        the camera confirms it); "camera" alone shows it"""
        words = arg.split()
        if not words:
            self.say(gimbal_line(self.vehicle.state()))
        elif words == ["shoot"]:
            self._report(self.vehicle.take_photo())
        elif len(words) == 2 and words[0] == "record" and words[1] in ("on", "off"):
            self._report(self.vehicle.record_video(words[1] == "on"))
        else:
            raise ValueError(f"usage: {CAMERA_USAGE}")
