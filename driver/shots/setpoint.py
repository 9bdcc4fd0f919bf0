"""What a shot asks of the vehicle each beat, and how it goes on the wire.

A :class:`Target` is a place (metres from home), the velocity through it, the heading and the turn rate there,
and, when the shot points the camera itself, the gimbal's pitch. :func:`target_message` writes it as
SET_POSITION_TARGET_GLOBAL_INT in MAV_FRAME_GLOBAL_RELATIVE_ALT_INT with position, velocity, yaw and yaw rate:
ArduCopter 4.x takes position with velocity as its PosVelAccel guided target, moves the target on with the
velocity between messages and feeds the velocity forward (ModeGuided::set_destination_posvel,
AC_PosControl::input_pos_vel_accel_xy), and yaw with a yaw rate as AutoYaw's ANGLE_RATE (the heading moves on
with the rate), so a path is flown without lag and the nose keeps up with a turning look. The acceleration
fields are ignored (a position with an acceleration makes the vehicle stop: GCS_MAVLINK_Copter's
handle_message_set_position_target_global_int).

Nothing that is not a finite number is ever written: :func:`target_message` returns None instead.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core import frames

__all__ = ["Target", "target_message", "POS_VEL_YAW_MASK", "here", "look_pitch", "bearing", "horizontal"]

#: use position, velocity, yaw and yaw rate; ignore the acceleration (POSITION_TARGET_TYPEMASK)
POS_VEL_YAW_MASK = (mavlink.POSITION_TARGET_TYPEMASK_AX_IGNORE | mavlink.POSITION_TARGET_TYPEMASK_AY_IGNORE
                    | mavlink.POSITION_TARGET_TYPEMASK_AZ_IGNORE)


@dataclass(frozen=True)
class Target:
    north: float                       # m from home
    east: float
    up: float                          # m above home
    vn: float = 0.0                    # m/s
    ve: float = 0.0
    vu: float = 0.0                    # m/s up
    yaw: float = 0.0                   # degrees clockwise from north: where the nose (and camera) points
    yaw_rate: float = 0.0              # deg/s, positive clockwise
    pitch: float | None = None         # the gimbal's pitch the shot streams; None: the vehicle's ROI points it

    def finite(self) -> bool:
        return frames.finite(self.north, self.east, self.up, self.vn, self.ve, self.vu, self.yaw, self.yaw_rate) \
            and (self.pitch is None or frames.finite(self.pitch))

    @property
    def speed(self) -> float:
        return math.sqrt(self.vn ** 2 + self.ve ** 2 + self.vu ** 2)


def target_message(target: Target, home, system: int, component: int):
    """SET_POSITION_TARGET_GLOBAL_INT for ``target`` (home: a GlobalPosition), or None if anything is not finite."""
    if home is None or not target.finite():
        return None
    lat, lon = frames.offset_latlon(home.lat, home.lon, target.north, target.east)
    if not frames.finite(lat, lon):
        return None
    return mavlink.MAVLink_set_position_target_global_int_message(
        0, system, component, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, POS_VEL_YAW_MASK,
        int(round(lat * 1e7)), int(round(lon * 1e7)), float(target.up), float(target.vn), float(target.ve),
        float(-target.vu), 0.0, 0.0, 0.0, math.radians(target.yaw % 360.0), math.radians(target.yaw_rate))


def here(state) -> tuple[float, float, float] | None:
    """(north, east, up) metres from home of the vehicle in ``state`` (a VehicleState), None before it says."""
    if state.local is None:
        return None
    return state.local.north, state.local.east, state.altitude


def bearing(dn: float, de: float) -> float:
    """Degrees clockwise from north of the direction (dn, de)."""
    return math.degrees(math.atan2(de, dn)) % 360.0


def horizontal(a, b) -> float:
    return math.hypot(b[0] - a[0], b[1] - a[1])


def look_pitch(frm, to) -> float:
    """The camera pitch (degrees, negative down) from ``frm`` to ``to``, both (north, east, up)."""
    return math.degrees(math.atan2(to[2] - frm[2], max(horizontal(frm, to), 0.01)))


def camera_look(state) -> tuple[float, float] | None:
    """(pitch, heading) in degrees where the vehicle's camera looks, from its own reports (the gimbal's pitch and
    yaw, the vehicle's heading); None while the gimbal has not reported its pitch."""
    g = state.gimbal
    if g.pitch_deg is None:
        return None
    heading = state.heading_deg
    if g.yaw_deg is not None:
        heading = g.yaw_deg if g.yaw_earth else heading + g.yaw_deg
    return g.pitch_deg, heading % 360.0


def aim_error(look: tuple[float, float] | None, pitch: float, yaw: float) -> float | None:
    """The angle (degrees) between the camera's look and the wanted (pitch, yaw): the great circle between two
    directions, so a yaw error counts less the more the camera looks down."""
    if look is None:
        return None
    p1, y1 = (math.radians(v) for v in look)
    p2, y2 = math.radians(pitch), math.radians(yaw)
    c = math.sin(p1) * math.sin(p2) + math.cos(p1) * math.cos(p2) * math.cos(y1 - y2)
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))
