"""What the simulated ArduCopter's parts share: modes, streams, parameters, small helpers."""
from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mavlink

__all__ = ["MODES", "MODE_NAMES", "POSITION_MODES", "NOT_ARMABLE", "STREAMS", "STREAM_PARAMS", "DEFAULT_PARAMS",
           "FORCE_ARM_MAGIC", "POS_IGNORE", "VEL_IGNORE", "YAW_IGNORE", "YAW_RATE_IGNORE", "wrap_pi",
           "wrap_lon", "finite", "command_name", "clamp"]

FORCE_ARM_MAGIC = 21196

MODES = {
    "STABILIZE": 0, "ACRO": 1, "ALT_HOLD": 2, "AUTO": 3, "GUIDED": 4, "LOITER": 5, "RTL": 6,
    "CIRCLE": 7, "LAND": 9, "DRIFT": 11, "SPORT": 13, "FLIP": 14, "AUTOTUNE": 15, "POSHOLD": 16,
    "BRAKE": 17, "THROW": 18, "AVOID_ADSB": 19, "GUIDED_NOGPS": 20, "SMART_RTL": 21,
    "FLOWHOLD": 22, "FOLLOW": 23, "ZIGZAG": 24,
}
MODE_NAMES = {number: name for name, number in MODES.items()}
# Modes that need a position estimate: armed, "Mode change failed: X requires position"; disarmed any mode
# may be set (Copter::set_mode: ignore_checks = !motors->armed(); the arming checks catch it).
POSITION_MODES = {3, 4, 5, 6, 7, 11, 16, 17, 19, 21, 23, 24}
# Modes from which ArduCopter refuses to arm.
NOT_ARMABLE = {3, 6, 7, 9, 19, 21, 23}
# REQUEST_DATA_STREAM ids → the messages ArduCopter puts in them (GCS_Mavlink.cpp). EXTENDED_SYS_STATE is in
# none: the 4.7 recording never got it from REQUEST_DATA_STREAM (ask by SET_MESSAGE_INTERVAL), 3.3 had none.
# MOUNT_STATUS is 3.3's (the Solo's mount, gimbal.py); 4.x sends none, its builder says None there.
STREAMS = {
    mavlink.MAV_DATA_STREAM_RAW_SENSORS: ("RAW_IMU", "SCALED_IMU2", "SCALED_PRESSURE"),
    mavlink.MAV_DATA_STREAM_EXTENDED_STATUS: ("SYS_STATUS", "POWER_STATUS", "MEMINFO", "MISSION_CURRENT",
                                              "GPS_RAW_INT", "NAV_CONTROLLER_OUTPUT", "FENCE_STATUS"),
    mavlink.MAV_DATA_STREAM_RC_CHANNELS: ("SERVO_OUTPUT_RAW", "RC_CHANNELS"),
    mavlink.MAV_DATA_STREAM_POSITION: ("GLOBAL_POSITION_INT", "LOCAL_POSITION_NED"),
    mavlink.MAV_DATA_STREAM_EXTRA1: ("ATTITUDE",),
    mavlink.MAV_DATA_STREAM_EXTRA2: ("VFR_HUD",),
    mavlink.MAV_DATA_STREAM_EXTRA3: ("SYSTEM_TIME", "BATTERY_STATUS", "EKF_STATUS_REPORT", "VIBRATION", "WIND",
                                     "MOUNT_STATUS"),
}

# SET_POSITION_TARGET type_mask bits (set = ignore).
POS_IGNORE = 0b111
VEL_IGNORE = 0b111000
YAW_IGNORE = 1024
YAW_RATE_IGNORE = 2048

# name → (value, MAV_PARAM_TYPE): the parameters the sim's behaviour reads, laid over ArduCopter 4.6.3's recorded
# table (params.py); a listed name keeps the recorded type. Values are the recording's unless said here.
DEFAULT_PARAMS = {
    "SYSID_THISMAV": (1, mavlink.MAV_PARAM_TYPE_INT16),
    "SYSID_MYGCS": (255, mavlink.MAV_PARAM_TYPE_INT16),
    "ARMING_CHECK": (1, mavlink.MAV_PARAM_TYPE_INT32),
    "DISARM_DELAY": (10, mavlink.MAV_PARAM_TYPE_INT8),
    "GUID_TIMEOUT": (3.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "RTL_ALT": (1500, mavlink.MAV_PARAM_TYPE_INT32),
    "RTL_ALT_FINAL": (0, mavlink.MAV_PARAM_TYPE_INT16),
    "RTL_LOIT_TIME": (5000, mavlink.MAV_PARAM_TYPE_INT32),
    "RTL_SPEED": (0, mavlink.MAV_PARAM_TYPE_INT16),
    "WPNAV_SPEED": (1000.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "WPNAV_SPEED_UP": (250.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "WPNAV_SPEED_DN": (150.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "WPNAV_ACCEL": (250.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "CIRCLE_RADIUS": (1000.0, mavlink.MAV_PARAM_TYPE_REAL32),   # cm (AC_Circle), the centre this far ahead
    "CIRCLE_RATE": (20.0, mavlink.MAV_PARAM_TYPE_REAL32),       # deg/s, positive clockwise
    "LAND_SPEED": (50, mavlink.MAV_PARAM_TYPE_INT16),
    "LAND_SPEED_HIGH": (0, mavlink.MAV_PARAM_TYPE_INT16),
    "PILOT_SPEED_UP": (250, mavlink.MAV_PARAM_TYPE_INT16),
    "PILOT_SPEED_DN": (0, mavlink.MAV_PARAM_TYPE_INT16),
    "LOIT_SPEED": (1250.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "ANGLE_MAX": (3000, mavlink.MAV_PARAM_TYPE_INT16),
    "WP_YAW_BEHAVIOR": (2, mavlink.MAV_PARAM_TYPE_INT8),
    "FRAME_CLASS": (1, mavlink.MAV_PARAM_TYPE_INT8),
    "FRAME_TYPE": (1, mavlink.MAV_PARAM_TYPE_INT8),   # X, as the sim's banner says (the recording's SITL: +)
    "BATT_MONITOR": (4, mavlink.MAV_PARAM_TYPE_INT8),
    "BATT_CAPACITY": (5200, mavlink.MAV_PARAM_TYPE_INT32),
    "BATT_LOW_VOLT": (10.5, mavlink.MAV_PARAM_TYPE_REAL32),
    "FS_GCS_ENABLE": (0, mavlink.MAV_PARAM_TYPE_INT8),
    # AC_Fence (libraries/AC_Fence/AC_Fence.cpp): off by default; circle 300 m around home (the firmware's default;
    # the recording's SITL reads 150 from its defaults file), ceiling 100 m
    "FENCE_ENABLE": (0, mavlink.MAV_PARAM_TYPE_INT8),
    "FENCE_TYPE": (7, mavlink.MAV_PARAM_TYPE_INT8),      # ceiling | circle | polygon on 4.x (Profile.fence_types)
    "FENCE_ACTION": (1, mavlink.MAV_PARAM_TYPE_INT8),    # RTL or land
    "FENCE_ALT_MAX": (100.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "FENCE_RADIUS": (300.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "FENCE_MARGIN": (2.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "RALLY_TOTAL": (0, mavlink.MAV_PARAM_TYPE_INT8),     # AP_Rally: how many rally points (3.3: set by the GCS)
    "CHUTE_ENABLED": (0, mavlink.MAV_PARAM_TYPE_INT8),  # off, as recorded; CHUTE_ALT_MIN is then hidden
    "CHUTE_ALT_MIN": (10, mavlink.MAV_PARAM_TYPE_INT16),
    # AP_Follow (libraries/AP_Follow): FOLL_ENABLE is listed; the rest hidden until it is set, as the firmware's
    # enable flag does (AP_PARAM_FLAG_ENABLE), and read or set by name
    "FOLL_ENABLE": (0, mavlink.MAV_PARAM_TYPE_INT8),
    "FOLL_SYSID": (0, mavlink.MAV_PARAM_TYPE_INT16),
    "FOLL_DIST_MAX": (100.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "FOLL_OFS_TYPE": (0, mavlink.MAV_PARAM_TYPE_INT8),
    "FOLL_OFS_X": (0.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "FOLL_OFS_Y": (0.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "FOLL_OFS_Z": (0.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "FOLL_YAW_BEHAVE": (1, mavlink.MAV_PARAM_TYPE_INT8),
    "FOLL_POS_P": (0.1, mavlink.MAV_PARAM_TYPE_REAL32),
    "FOLL_ALT_TYPE": (1, mavlink.MAV_PARAM_TYPE_INT8),
    "FOLL_OPTIONS": (0, mavlink.MAV_PARAM_TYPE_INT16),
    "SERIAL0_PROTOCOL": (2, mavlink.MAV_PARAM_TYPE_INT8),
    "SR0_EXT_STAT": (0, mavlink.MAV_PARAM_TYPE_INT16),    # SITL's defaults file streams at once; the sim
    # streams only what a ground station asks for (REQUEST_DATA_STREAM writes these, as ArduPilot does)
    "SR0_POSITION": (0, mavlink.MAV_PARAM_TYPE_INT16),
    "SR0_EXTRA1": (0, mavlink.MAV_PARAM_TYPE_INT16),
    "SR0_EXTRA2": (0, mavlink.MAV_PARAM_TYPE_INT16),
    "SR0_EXTRA3": (0, mavlink.MAV_PARAM_TYPE_INT16),
}
STREAM_PARAMS = {
    mavlink.MAV_DATA_STREAM_EXTENDED_STATUS: "SR0_EXT_STAT", mavlink.MAV_DATA_STREAM_POSITION: "SR0_POSITION",
    mavlink.MAV_DATA_STREAM_EXTRA1: "SR0_EXTRA1", mavlink.MAV_DATA_STREAM_EXTRA2: "SR0_EXTRA2",
    mavlink.MAV_DATA_STREAM_EXTRA3: "SR0_EXTRA3",
}


def clamp(value: float, low: float, high: float) -> float:
    return low if value < low else high if value > high else value


def wrap_pi(angle: float) -> float:
    """Angle in (-pi, pi]."""
    a = math.fmod(angle + math.pi, 2.0 * math.pi)
    if a <= 0.0:
        a += 2.0 * math.pi
    return a - math.pi


def wrap_lon(degrees: float) -> float:
    """Longitude in [-180, 180) (Location::wrap_longitude): the vehicle may fly across the antimeridian."""
    return (degrees + 180.0) % 360.0 - 180.0


def finite(*values: float) -> bool:
    return all(math.isfinite(v) for v in values)


def command_name(command: int) -> str:
    entry = mavlink.enums["MAV_CMD"].get(command)
    return entry.name if entry is not None else str(command)
