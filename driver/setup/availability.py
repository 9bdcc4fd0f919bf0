"""What a firmware can do on the bench, and in plain words why not: each setup page says so instead of failing.

From the firmware version the vehicle reports (AUTOPILOT_VERSION, ``VehicleState.firmware``): ArduCopter 3.3
(the Solo, 3drobotics/ardupilot-solo GCS_Mavlink.pde) handles PREFLIGHT_CALIBRATION gyro and baro but not level
(p5=2) nor the simple accel calibration (p5=4); its six-position accel calibration (p5=1) is the older one: the
start is answered FAILED though it runs, each position is asked only in a STATUSTEXT and confirmed with a bare
COMMAND_ACK, never with ACCELCAL_VEHICLE_POS (its AP_AccelCal.cpp), and a success reboots the vehicle: this app
drives only the ACCELCAL_VEHICLE_POS one, so it says so on 3.3. 3.3 has no FIXED_MAG_CAL_YAW (ArduPilot 4's) and
no ADS-B (AP_ADSB, 3.4). Where exactly between 3.3 and 4.x each came is not checked: 3.4 and 4.0 are the bounds used. An unknown version claims nothing: everything is offered and the vehicle's answer decides.
"""
from __future__ import annotations

__all__ = ["unavailable", "SETUP_ACTIONS", "version"]

SETUP_ACTIONS = ("gyro", "baro", "level", "accel", "accel_simple", "compass", "fixed_yaw", "motor_test", "radio",
                 "adsb")
# action → (first version that has it, why not before)
_SINCE = {
    "level": ((3, 4), "ArduCopter {v} does not handle a level calibration by command (PREFLIGHT_CALIBRATION "
                      "p5=2): the accelerometer calibration levels the vehicle"),
    "accel_simple": ((3, 4), "ArduCopter {v} does not handle the simple accelerometer calibration (p5=4)"),
    "accel": ((3, 4), "ArduCopter {v} runs the six-position accelerometer calibration the older way (positions "
                      "asked by text, confirmed with COMMAND_ACK, no ACCELCAL_VEHICLE_POS), which this app does "
                      "not drive: use the Solo's own app for it"),
    "fixed_yaw": ((4, 0), "ArduCopter {v} has no compass calibration from a known yaw (MAV_CMD_FIXED_MAG_CAL_YAW "
                          "is ArduPilot 4's)"),
    "adsb": ((3, 4), "ArduCopter {v} does not forward ADS-B traffic (AP_ADSB came with 3.4)"),
}


def version(firmware: str) -> tuple[int, int] | None:
    """(major, minor) of "3.3.1", None when unknown."""
    try:
        major, minor = firmware.split(".")[:2]
        return int(major), int(minor)
    except ValueError:
        return None


def unavailable(action: str, firmware: str) -> str:
    """Why ``action`` is not available on ``firmware`` ("3.3.1"), or "" when it is (or the version is unknown)."""
    if action not in SETUP_ACTIONS:
        raise ValueError(f"unknown setup action {action!r}")
    have = version(firmware)
    since = _SINCE.get(action)
    if have is None or since is None or have >= since[0]:
        return ""
    return since[1].format(v=firmware)
