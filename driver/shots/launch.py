"""Each shot made from what the pilot asked and the vehicle's snapshot: the checks a shot has before it starts.

A maker takes the snapshot (with home and position known: :meth:`ShotControl._begin` checked) and the
:class:`~driver.shots.limits.Bounds`, and returns the shot or raises ValueError with the pilot's reason.
"""
from __future__ import annotations

import math

from ..core import frames
from .cable import Cable
from .follow import Follow
from .model import Keyframe
from .orbit import Orbit, spot_under_camera
from .pano import Pano
from .selfie import Selfie
from .setpoint import camera_look, here

__all__ = ["make_orbit", "make_cable", "make_selfie", "make_follow", "make_pano", "ned_of", "latlon_of",
           "keyframe_here", "follow_params"]


def ned_of(state, lat: float, lon: float, alt: float) -> tuple[float, float, float]:
    """(north, east, up) m from home of (lat, lon) at ``alt`` m above home."""
    n, e = frames.offset_ned(state.home.lat, state.home.lon, lat, lon)
    return n, e, alt


def latlon_of(state, point) -> tuple[float, float, float]:
    lat, lon = frames.offset_latlon(state.home.lat, state.home.lon, point[0], point[1])
    return lat, lon, point[2]


def _look_now(state) -> tuple[float, float]:
    look = camera_look(state)
    return look if look is not None else (0.0, state.heading_deg)


def make_orbit(state, bounds, lat, lon, alt, radius, speed, roi: bool) -> Orbit:
    if lat is not None and lon is not None:
        if not frames.finite(lat, lon, alt) or not (-90 <= lat <= 90 and -180 <= lon <= 180):
            raise ValueError("the centre is not a place on Earth")
        centre = ned_of(state, lat, lon, alt)
    elif roi:
        if state.gimbal.roi is None:
            raise ValueError("the vehicle has no region of interest: pick the centre on the map")
        centre = ned_of(state, *state.gimbal.roi)
    else:
        centre = spot_under_camera(state)
        if centre is None:
            raise ValueError("the camera does not look down at the ground (or its pitch is not known): "
                             "tilt it down, or pick the centre on the map")
    if radius is not None and not frames.finite(radius) or not frames.finite(speed):
        raise ValueError("radius and speed are finite numbers")
    return Orbit(centre, here(state), state.heading_deg, radius, speed, bounds.allowed)


def make_cable(state, bounds, keyframes: tuple[Keyframe, ...], speed: float, attach: int | None) -> Cable:
    if len(keyframes) < 2:
        raise ValueError(f"a cable needs 2 to 10 keyframes: {len(keyframes)} recorded")
    if not frames.finite(speed):
        raise ValueError("the speed is not a finite number")
    points = [ned_of(state, k.lat, k.lon, k.alt) for k in keyframes]
    looks = [(k.pitch, k.yaw) for k in keyframes]
    return Cable(points, looks, here(state), _look_now(state), attach, min(abs(speed), 8.0))


def make_selfie(state, bounds, distance, rise, speed, pilot) -> Selfie:
    if not frames.finite(distance, rise, speed):
        raise ValueError("distance, rise and speed are finite numbers")
    if pilot is None:
        where = (0.0, 0.0, 0.0)                           # home: where the pilot took off
    else:
        where = ned_of(state, pilot[0], pilot[1], 0.0)
    return Selfie(where, here(state), distance, rise, speed)


def make_follow(state, bounds, source, engine: str, now: float) -> Follow:
    def to_ned(fix):
        n, e = frames.offset_ned(state.home.lat, state.home.lon, fix.lat, fix.lon)
        return n, e, (fix.alt - state.home.alt) if fix.alt is not None else 0.0
    return Follow(source.latest, here(state), now, engine, bounds.allowed, to_ned)


def follow_engine(state, asked: str) -> tuple[str, str]:
    """(the engine, a note): FOLLOW where the vehicle has FOLL_ENABLE 1 ("auto") or it is asked for."""
    enabled = state.parameters.get("FOLL_ENABLE") if hasattr(state.parameters, "get") else None
    value = getattr(enabled, "value", enabled)
    if asked == "guided":
        return "GUIDED", ""
    if asked not in ("auto", "follow"):
        raise ValueError("the follow engine is auto, follow or guided")
    if value is not None and float(value) == 1.0:
        return "FOLLOW", ""
    if asked == "follow":
        raise ValueError("ArduCopter's FOLLOW mode needs FOLL_ENABLE = 1 on the vehicle (set it, then read the "
                         "parameters again), or follow in GUIDED")
    return "GUIDED", "FOLL_ENABLE is not 1: following in GUIDED"


def follow_params(shot: Follow, system_id: int) -> list[tuple[str, float]]:
    """What AP_Follow is set to for the FOLLOW engine: this driver's fixes, the shot's offset (NED, vehicle from
    target), the nose on the target, altitudes above home."""
    n, e, u = shot.offset
    return [("FOLL_SYSID", system_id), ("FOLL_OFS_TYPE", 0), ("FOLL_OFS_X", round(n, 2)), ("FOLL_OFS_Y", round(e, 2)),
            ("FOLL_OFS_Z", round(-u, 2)), ("FOLL_YAW_BEHAVE", 1), ("FOLL_ALT_TYPE", 1)]


def make_pano(state, bounds, shape, fov, lens, pitch, take_photo) -> Pano:
    if not frames.finite(fov, lens, pitch):
        raise ValueError("fov, lens and pitch are finite numbers")
    return Pano(here(state), state.heading_deg, take_photo, shape, fov, lens, pitch)


def keyframe_here(state) -> tuple[Keyframe, str]:
    """The keyframe where the vehicle is, and a note when the camera's pitch is not known (level assumed)."""
    look = camera_look(state)
    note = "" if look is not None else "the gimbal has not reported its pitch: level assumed"
    pitch, yaw = look if look is not None else (0.0, state.heading_deg)
    lat, lon, alt = latlon_of(state, here(state))
    return Keyframe(lat, lon, alt, pitch, yaw), note


def too_close(a: Keyframe, b: Keyframe) -> bool:
    n, e = frames.offset_ned(a.lat, a.lon, b.lat, b.lon)
    return math.sqrt(n * n + e * e + (b.alt - a.alt) ** 2) < 1.0
