"""A smart shot as the pilot sees it: immutable values the vehicle's snapshot carries (``VehicleState.shot``).

What a shot reports is read from the vehicle's own telemetry (its position, heading and gimbal), never from the
targets the driver sent: progress along the cable is where the vehicle *is* on it, the orbit's radius and angle
are measured from the centre to where the vehicle is, the follow distance from the target's last fix to the
vehicle. A cable's keyframes are saved and loaded as a small JSON file (:func:`save_cable`, :func:`load_cable`).
"""
from __future__ import annotations

import enum
import json
from dataclasses import dataclass, field

from ..core import frames
from ..core.files import write_private

__all__ = ["ShotKind", "ShotPhase", "Keyframe", "Sticks", "ShotState", "Look", "save_cable", "load_cable",
           "CABLE_FORMAT", "MAX_KEYFRAMES", "MIN_KEYFRAMES"]

MIN_KEYFRAMES = 2
MAX_KEYFRAMES = 10
CABLE_FORMAT = "uavviewer-cable"


class ShotKind(enum.Enum):
    NONE = ""
    ORBIT = "orbit"
    CABLE = "cable"
    SELFIE = "selfie"
    FOLLOW = "follow"
    PANO = "pano"


class ShotPhase(enum.Enum):
    IDLE = "idle"
    STARTING = "starting"          # asked for the mode, waiting for the vehicle to show it
    ATTACHING = "attaching"        # flying to the start of the path (the cable's keyframe, the orbit's radius)
    FLYING = "flying"
    PAUSED = "paused"
    HOLDING = "holding"            # waiting on something outside (the follow target's fixes stopped)
    DONE = "done"                  # finished by itself: hovering where it ended, still in GUIDED
    ENDED = "ended"                # ended by the pilot, a mode change, the link or a refusal: detail says which

    @property
    def active(self) -> bool:
        return self in (ShotPhase.STARTING, ShotPhase.ATTACHING, ShotPhase.FLYING, ShotPhase.PAUSED,
                        ShotPhase.HOLDING)


@dataclass(frozen=True)
class Keyframe:
    """A place on the cable and the camera's look there, recorded while flying by hand."""
    lat: float
    lon: float
    alt: float                     # m above home
    pitch: float                   # gimbal pitch, degrees (0 level, -90 down)
    yaw: float                     # camera heading, degrees clockwise from north

    def finite(self) -> bool:
        return frames.finite(self.lat, self.lon, self.alt, self.pitch, self.yaw) and -90 <= self.lat <= 90 \
            and -180 <= self.lon <= 180


@dataclass(frozen=True)
class Look:
    """The camera's look at a place along a path, for drawing it on the map."""
    lat: float
    lon: float
    yaw: float
    pitch: float


@dataclass(frozen=True)
class Sticks:
    """The pilot's sticks during a shot, each -1..1: forward (pushed away), right, up (throttle above centre),
    yaw (right). What each does depends on the shot, as on the Solo."""
    forward: float = 0.0
    right: float = 0.0
    up: float = 0.0
    yaw: float = 0.0

    @property
    def centred(self) -> bool:
        return self.forward == 0.0 and self.right == 0.0 and self.up == 0.0 and self.yaw == 0.0

    @staticmethod
    def checked(forward: float, right: float, up: float, yaw: float) -> "Sticks | None":
        """Within -1..1, or None when a value is not a finite number (nothing flies on a NaN)."""
        if not frames.finite(forward, right, up, yaw):
            return None
        c = lambda v: max(-1.0, min(1.0, float(v)))    # noqa: E731
        return Sticks(c(forward), c(right), c(up), c(yaw))


@dataclass(frozen=True)
class ShotState:
    """The shot running now (or the last one), as the vehicle's telemetry shows it."""
    kind: ShotKind = ShotKind.NONE
    phase: ShotPhase = ShotPhase.IDLE
    detail: str = ""                                  # what the pilot reads: "orbiting at 20 m", why it ended
    engine: str = ""                                  # the mode that flies it: "GUIDED", "FOLLOW"
    keyframes: tuple[Keyframe, ...] = ()              # recorded for the cable (kept between shots)
    path: tuple[tuple[float, float, float], ...] = ()     # lat, lon, alt above home: the cable or selfie line
    looks: tuple[Look, ...] = ()                      # the camera's look along the path
    progress: float | None = None                     # 0..1 along the path, where the vehicle is
    speed: float | None = None                        # m/s along the path (negative: back), from telemetry
    centre: tuple[float, float, float] | None = None  # the orbit's centre, the follow target, the selfie's pilot
    radius: float | None = None                       # m, measured from the centre to the vehicle
    radius_wanted: float | None = None
    angle: float | None = None                        # degrees, bearing from the centre to the vehicle
    aim_error: float | None = None                    # degrees between where the camera looks and where it should
    target_distance: float | None = None              # m from the follow target's last fix to the vehicle
    target_age: float | None = None                   # s since that fix
    photos: int = 0                                   # pano: pictures the camera confirmed
    photos_total: int = 0
    cruise: float = 0.0                               # m/s the shot cruises at when the sticks are centred

    @property
    def active(self) -> bool:
        return self.phase.active

    def describe(self) -> str:
        if self.kind is ShotKind.NONE:
            return "no shot"
        return f"{self.kind.value} {self.phase.value}" + (f": {self.detail}" if self.detail else "")


def save_cable(path: str, keyframes: tuple[Keyframe, ...]) -> None:
    """Write ``keyframes`` as JSON (written whole or not at all)."""
    data = {"format": CABLE_FORMAT, "version": 1,
            "keyframes": [{"lat": k.lat, "lon": k.lon, "alt": k.alt, "pitch": k.pitch, "yaw": k.yaw}
                          for k in keyframes]}
    write_private(path, (json.dumps(data, indent=1) + "\n").encode(), 0o644)


def load_cable(path: str) -> tuple[Keyframe, ...]:
    """The keyframes of a cable file, or ValueError saying what is wrong with it."""
    try:
        with open(path, encoding="utf-8") as f:
            data = json.load(f)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"cannot read {path}: {exc}") from None
    if not isinstance(data, dict) or data.get("format") != CABLE_FORMAT:
        raise ValueError(f"{path} is not a cable file")
    try:
        keys = tuple(Keyframe(*(float(k[name]) for name in ("lat", "lon", "alt", "pitch", "yaw")))
                     for k in data["keyframes"])
    except (KeyError, TypeError, ValueError):
        raise ValueError(f"{path}: a keyframe lacks lat, lon, alt, pitch or yaw") from None
    if not MIN_KEYFRAMES <= len(keys) <= MAX_KEYFRAMES:
        raise ValueError(f"{path}: a cable has {MIN_KEYFRAMES} to {MAX_KEYFRAMES} keyframes, not {len(keys)}")
    if not all(k.finite() for k in keys):
        raise ValueError(f"{path}: a keyframe is not a place on Earth")
    return keys

