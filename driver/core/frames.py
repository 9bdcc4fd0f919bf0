"""Conversions between the autopilot's frames and the ones applications use.

Positions are turned into metres with a local flat-earth approximation on the
WGS84 equatorial radius, accurate to centimetres over the few kilometres a
copter flies from home (the 2017 driver reported raw millions of metres).
"""
from __future__ import annotations

import math
import numbers

EARTH_RADIUS = 6378137.0  # WGS84 semi-major axis, m
_M_PER_DEG = EARTH_RADIUS * math.pi / 180.0


def offset_ned(home_lat: float, home_lon: float, lat: float, lon: float) -> tuple[float, float]:
    """(north, east) metres of (lat, lon) from home."""
    north = (lat - home_lat) * _M_PER_DEG
    east = wrap_lon(lon - home_lon) * _M_PER_DEG * math.cos(math.radians(home_lat))   # across the antimeridian
    return north, east


def offset_latlon(home_lat: float, home_lon: float, north: float, east: float) -> tuple[float, float]:
    """(lat, lon) of a point north/east metres from home; inverse of :func:`offset_ned`."""
    lat = home_lat + north / _M_PER_DEG
    lon = home_lon + east / (_M_PER_DEG * math.cos(math.radians(home_lat)))
    return lat, wrap_lon(lon)


def wrap_180(degrees: float) -> float:
    """An angle in degrees (a heading, a yaw, a difference of two) in [-180, 180)."""
    return (degrees + 180.0) % 360.0 - 180.0


def wrap_lon(degrees: float) -> float:
    """A longitude (or a difference of two) in [-180, 180), as ArduPilot's wrap_longitude."""
    return wrap_180(degrees)


def wrap_pi(angle: float) -> float:
    """Angle in (-pi, pi]."""
    a = math.fmod(angle + math.pi, 2.0 * math.pi)
    if a <= 0.0:
        a += 2.0 * math.pi
    return a - math.pi


def enu_quaternion(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    """(w, x, y, z) of a vehicle with NED Euler angles, expressed as FLU body in ENU.

    JdeRobot's simulated drones report yaw 0 facing east, counter-clockwise
    positive: yaw_enu = pi/2 - yaw_ned; rolling right stays a positive roll about
    the forward axis in FLU, pitching nose up is a negative rotation about the
    left axis, so pitch_enu = -pitch_ned.
    """
    from pymavlink.quaternion import QuaternionBase
    w, x, y, z = QuaternionBase([roll, -pitch, wrap_pi(math.pi / 2.0 - yaw)]).q
    return float(w), float(x), float(y), float(z)


def battery_percent_from_cell(cell_voltage: float) -> float:
    """MAVProxy's LiPo estimate (arducopter.md), percent from one cell's voltage."""
    v = cell_voltage
    if v > 4.1:
        return 100.0
    if v >= 3.81:
        return 17.0 + 83.0 * (v - 3.81) / 0.29
    if v >= 3.2:
        return 17.0 * (v - 3.2) / 0.61
    return 0.0


def finite(*values: float) -> bool:
    """Real numbers (numpy's too), not booleans, neither NaN nor infinite."""
    return all(isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v) for v in values)


def clamp(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))
