"""What the vehicle says about its gimbal and its camera, as immutable values in :class:`~driver.vehicle.state.VehicleState`.

Everything here is the vehicle's word: the gimbal's attitude is "unknown" (None) until GIMBAL_DEVICE_ATTITUDE_STATUS
or MOUNT_STATUS arrives, and a picture counts only once CAMERA_FEEDBACK, CAMERA_IMAGE_CAPTURED or the GoPro
confirms it (the gimbal recording shows DO_DIGICAM_CONTROL ACCEPTED by a vehicle with no camera at all).
Pure functions turn those messages into values; the driver's :mod:`driver.payload.control` holds them.
"""
from __future__ import annotations

import enum
import math
from dataclasses import dataclass

__all__ = ["GimbalControl", "Gimbal", "CameraKind", "VehicleCamera", "gimbal_from_quaternion",
           "GIMBAL_PITCH_RANGE", "RETRACT_FLAG", "YAW_IN_EARTH_FRAME", "YAW_LOCK_FLAG", "YAW_IN_VEHICLE_FRAME"]

# GIMBAL_DEVICE_FLAGS (MAVLink common)
RETRACT_FLAG = 1
NEUTRAL_FLAG = 2
YAW_LOCK_FLAG = 16
YAW_IN_VEHICLE_FRAME = 32
YAW_IN_EARTH_FRAME = 64

#: The pitch a pilot may ask for, degrees (0 level, -90 straight down): a servo mount's MNT1_PITCH_MIN/MAX in
#: ArduPilot's copter-gimbal.parm and the Solo gimbal's travel; a little up for mounts that have it.
GIMBAL_PITCH_RANGE = (-90.0, 30.0)


class GimbalControl(enum.Enum):
    """Which way the gimbal is being pointed now (MAV_MOUNT_MODE, as far as the vehicle or our commands tell)."""
    UNKNOWN = "unknown"
    RC = "RC (pilot's transmitter)"         # the mount's default on ArduCopter (MNT1_DEFLT_MODE 3)
    ANGLE = "angle"                         # an angle we sent
    RATE = "rate"                           # a rate we sent
    ROI = "looking at a point"              # DO_SET_ROI_LOCATION
    RETRACTED = "retracted"
    NEUTRAL = "neutral"


@dataclass(frozen=True)
class Gimbal:
    """The gimbal as the vehicle reports it; None fields are unknown (never a guess)."""
    pitch_deg: float | None = None          # 0 level, negative down
    yaw_deg: float | None = None            # from the vehicle's nose, clockwise; None also when pointing straight
    yaw_earth: bool = False                 # the vehicle reports yaw from north rather than from the nose
    retracted: bool | None = None
    control: GimbalControl = GimbalControl.UNKNOWN
    source: str = ""                        # the message that told: "GIMBAL_DEVICE_ATTITUDE_STATUS", "MOUNT_STATUS"
    component: int = 0                      # who told (1: the autopilot, 154: a MAVLink gimbal)
    protocol: str = ""                      # how we point it: "gimbal manager", "DO_MOUNT_CONTROL", "MOUNT_CONTROL"
    roi: tuple[float, float, float] | None = None   # lat, lon, alt (m above home) it was asked to look at
    updated: float = 0.0                    # wall time of the last report

    @property
    def known(self) -> bool:
        return self.pitch_deg is not None

    def describe(self) -> str:
        """"-45° (angle)" or "unknown"."""
        if self.pitch_deg is None:
            return "unknown"
        text = f"{self.pitch_deg:.0f}°"
        if self.yaw_deg is not None and abs(self.yaw_deg) >= 0.5:
            text += f" yaw {self.yaw_deg:+.0f}°"
        return text + ("" if self.control is GimbalControl.UNKNOWN else f" ({self.control.value})")


class CameraKind(enum.Enum):
    UNKNOWN = "unknown"                     # nothing said yet: a trigger goes out as DO_DIGICAM_CONTROL
    MAVLINK = "MAVLink camera"              # CAMERA_INFORMATION arrived: IMAGE_/VIDEO_START_CAPTURE
    GOPRO = "Solo GoPro"                    # GOPRO_HEARTBEAT from the Solo's gimbal (component 154)


@dataclass(frozen=True)
class VehicleCamera:
    """The camera on the vehicle (not the video the window shows or records itself)."""
    kind: CameraKind = CameraKind.UNKNOWN
    name: str = ""                          # vendor and model from CAMERA_INFORMATION, "GoPro"
    component: int = 0
    can_record: bool | None = None          # CAMERA_CAP_FLAGS_CAPTURE_VIDEO, a GoPro: True
    photos: int = 0                         # pictures the vehicle confirmed this session
    last_photo: float | None = None         # wall time of the last confirmed picture
    last_photo_at: tuple[float, float] | None = None   # lat, lon the vehicle stamped on it
    recording: bool | None = None           # the vehicle says it records video; None: it has not said
    status: str = ""                        # the GoPro's own status ("connected", "no GoPro"), else ""


def gimbal_from_quaternion(q, previous_yaw: float | None = None) -> tuple[float, float | None] | None:
    """(pitch, yaw) in degrees of the camera's forward axis for GIMBAL_DEVICE_ATTITUDE_STATUS's quaternion
    (w, x, y, z), or None when it is not a unit quaternion.

    Read from the axis the camera looks along rather than as Euler angles: at -90° Euler angles put yaw
    anywhere (the recording reports yaw 180° after DO_GIMBAL_MANAGER_PITCHYAW -90, 0). Straight down, yaw
    does not exist: ``previous_yaw`` is kept (None if there was none).
    """
    try:
        w, x, y, z = (float(v) for v in q)
    except (TypeError, ValueError):
        return None
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    if not math.isfinite(norm) or abs(norm - 1.0) > 0.05:
        return None
    w, x, y, z = w / norm, x / norm, y / norm, z / norm
    fx = 1.0 - 2.0 * (y * y + z * z)
    fy = 2.0 * (x * y + w * z)
    fz = 2.0 * (x * z - w * y)
    horizontal = math.hypot(fx, fy)
    pitch = math.degrees(math.atan2(-fz, horizontal))
    yaw = math.degrees(math.atan2(fy, fx)) if horizontal > 0.02 else previous_yaw
    pitch = round(pitch, 2) + 0.0                       # float32 noise, and no "-0.0"
    yaw = None if yaw is None else round(yaw, 2) + 0.0
    return pitch, yaw
