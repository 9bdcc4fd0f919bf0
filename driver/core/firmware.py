"""What this vehicle's firmware does differently, in one place: the parts ask this profile instead of testing a
version each, as QGroundControl's parts ask its FirmwarePlugin (ArduCopterFirmwarePlugin).

The profile is learnt from what the vehicle shows, never assumed:

* AUTOPILOT_VERSION: the version (3.3 on the 3DR Solo, 4.x elsewhere) and the protocols it advertises (MAVLink
  FTP, MISSION_ITEM_INT);
* the link: a vehicle framing MAVLink 2 (3.3 speaks only MAVLink 1);
* the first UNSUPPORTED answers: a command the firmware does not know (DO_SET_MODE on the stock Solo,
  REQUEST_MESSAGE, SET_MESSAGE_INTERVAL, the gimbal and ROI commands), and a protocol that failed (FTP).

What ArduCopter 3.3 (the Solo, 3drobotics/ardupilot-solo) lacks, from its sources: body-frame velocities and
yaw rates in SET_POSITION_TARGET_LOCAL_NED (before 3.5: "for future use"); mount, ROI-location and message
commands in COMMAND_LONG (before 3.4; its mount takes the MOUNT_CONTROL message); the mission protocol's
mission_type (fences and rally points travel otherwise); the setup actions of :data:`SETUP_SINCE`; a motor test
of several motors (one, at most 30 s). An unknown version claims nothing: everything is offered and the vehicle's
answer decides.

Not thread-safe: the driver's state lock guards it (the reader teaches it, every part asks it).
"""
from __future__ import annotations

from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink

__all__ = ["FirmwareProfile", "SETUP_ACTIONS", "unavailable", "version_of"]

SETUP_ACTIONS = ("gyro", "baro", "level", "accel", "accel_simple", "compass", "fixed_yaw", "motor_test", "radio",
                 "adsb")
#: setup action → (the first version that has it, why not before). Where exactly between 3.3 and 4.x each came is
#: not checked: 3.4 and 4.0 are the bounds used. 3.3 handles PREFLIGHT_CALIBRATION gyro and baro but not level
#: (p5=2) nor the simple accel calibration (p5=4); its six-position accel calibration (p5=1) is the older one: the
#: start is answered FAILED though it runs, each position is asked only in a STATUSTEXT and confirmed with a bare
#: COMMAND_ACK, never with ACCELCAL_VEHICLE_POS (its AP_AccelCal.cpp), and a success reboots the vehicle.
SETUP_SINCE = {
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
BODY_FRAME_SINCE = (3, 5)          # SET_POSITION_TARGET_LOCAL_NED reads its frame and its yaw rate
COMMAND_LONG_MOUNT_SINCE = (3, 4)  # DO_MOUNT_CONTROL, DO_SET_ROI_LOCATION, SET_MESSAGE_INTERVAL by COMMAND_LONG
MOTOR_TEST_SEQUENCE_SINCE = (3, 4)
MOTOR_TEST_LONGEST = 600.0         # s: ArduCopter's MOTOR_TEST_TIMEOUT_MAX
MOTOR_TEST_LONGEST_33 = 30.0       # s: the Solo's 3.3 (motor_test.pde MOTOR_TEST_TIMEOUT_MS_MAX)


def version_of(firmware: str) -> tuple[int, int] | None:
    """(major, minor) of "3.3.1", None when unknown ("")."""
    try:
        major, minor = firmware.split(".")[:2]
        return int(major), int(minor)
    except ValueError:
        return None


def unavailable(action: str, firmware: str) -> str:
    """Why the setup ``action`` is not available on ``firmware`` ("3.3.1"), or "" when it is (or the version is
    unknown): each setup page says so instead of failing. A function of the reported version alone, so a viewer
    reached over Ice asks it of ``VehicleState.firmware`` too."""
    if action not in SETUP_ACTIONS:
        raise ValueError(f"unknown setup action {action!r}")
    have = version_of(firmware)
    since = SETUP_SINCE.get(action)
    if have is None or since is None or have >= since[0]:
        return ""
    return since[1].format(v=firmware)


class FirmwareProfile:
    """One vehicle's firmware as learnt so far. ``mavlink2``: whether the link speaks MAVLink 2 now (the reader
    follows the autopilot's framing)."""

    def __init__(self, mavlink2: Callable[[], bool] = lambda: True) -> None:
        self._mavlink2 = mavlink2
        self.version: tuple[int, int, int] | None = None     # AUTOPILOT_VERSION's flight software
        self._advertised: int | None = None                  # its capability bits (None: not heard yet)
        self._ftp_failed = False                              # an FTP read failed: the vehicle's FTP is not used
        self._known: dict[int, bool] = {}                     # MAV_CMD -> answered other than UNSUPPORTED

    # -- what the vehicle shows (reader thread, lock held) ----------------------------------------------------
    def heard_version(self, m) -> str:
        """AUTOPILOT_VERSION; returns what the pilot is to be told of it ("" when nothing)."""
        self._advertised, self._ftp_failed = m.capabilities, False     # FTP offered again is tried again
        v = m.flight_sw_version
        major, minor, patch = (v >> 24) & 0xFF, (v >> 16) & 0xFF, (v >> 8) & 0xFF
        if not major:
            return ""
        self.version = (major, minor, patch)
        if not self.body_frame_velocity:
            return (f"Firmware {self.firmware}: velocity goes north/east and the nose is steered with CONDITION_YAW "
                    "(it ignores body frames and yaw rates)")
        return ""

    def heard_answer(self, command: int, result: int) -> str:
        """A COMMAND_ACK for ``command`` (ours or not); returns what the pilot is to be told ("" when nothing).
        A command once answered UNSUPPORTED stays unknown: a firmware does not learn commands while it runs."""
        known = result != mavlink.MAV_RESULT_UNSUPPORTED
        if self._known.get(command) is False:
            return ""
        self._known[command] = known
        if not known and command == mavlink.MAV_CMD_DO_SET_MODE:
            return ("The vehicle does not know MAV_CMD_DO_SET_MODE (old firmware): modes are set with SET_MODE and "
                    "confirmed by its heartbeat")
        return ""

    def ftp_failed(self) -> None:
        """A read over MAVLink FTP failed: every part reads the other way from now on (until the vehicle advertises
        FTP again)."""
        self._ftp_failed = True

    # -- what the parts ask ------------------------------------------------------------------------------------
    @property
    def firmware(self) -> str:
        """"3.3.1"; "" until known."""
        return ".".join(map(str, self.version)) if self.version else ""

    @property
    def mavlink2(self) -> bool:
        """The autopilot frames MAVLink 2 now: messages may carry its extension fields (mission_type)."""
        return self._mavlink2()

    def _before(self, since: tuple[int, int]) -> bool:
        """The version is known and older than ``since``."""
        return self.version is not None and self.version[:2] < since

    def knows(self, command: int) -> bool | None:
        """Whether the firmware handles ``command`` in COMMAND_LONG: False once it answered UNSUPPORTED, True once
        it answered otherwise, None while not known."""
        return self._known.get(command)

    @property
    def body_frame_velocity(self) -> bool | None:
        """SET_POSITION_TARGET_LOCAL_NED flies body-frame velocities and a yaw rate (3.5 and later); False: send
        north/east velocities and steer the nose with CONDITION_YAW; None while not known."""
        return None if self.version is None else not self._before(BODY_FRAME_SINCE)

    @property
    def mode_by_message(self) -> bool:
        """Modes go by the SET_MODE message (the firmware has no MAV_CMD_DO_SET_MODE)."""
        return self.knows(mavlink.MAV_CMD_DO_SET_MODE) is False

    @property
    def payload_commands(self) -> bool:
        """COMMAND_LONG carries the mount, ROI-location and message-interval commands (3.4 and later, and while the
        version is not known); False: the Solo's 3.3, whose mount takes MOUNT_CONTROL messages and its ROI
        DO_SET_ROI."""
        return not self._before(COMMAND_LONG_MOUNT_SINCE)

    @property
    def ftp(self) -> bool | None:
        """MAVLink FTP is advertised (MAV_PROTOCOL_CAPABILITY_FTP, ArduPilot 4.1+) and has not failed; None before
        AUTOPILOT_VERSION."""
        if self._ftp_failed:
            return False
        return None if self._advertised is None else bool(self._advertised & mavlink.MAV_PROTOCOL_CAPABILITY_FTP)

    @property
    def mission_int(self) -> bool | None:
        """MISSION_ITEM_INT is advertised (None: AUTOPILOT_VERSION not heard yet)."""
        return None if self._advertised is None else bool(
            self._advertised & mavlink.MAV_PROTOCOL_CAPABILITY_MISSION_INT)

    @property
    def integer_items(self) -> bool:
        """Mission items go as MISSION_ITEM_INT: advertised, or (not said yet) a MAVLink 2 vehicle, which is
        ArduCopter 3.5 or later."""
        return self.mission_int if self.mission_int is not None else self.mavlink2

    @property
    def mission_types(self) -> bool:
        """The mission protocol carries fences and rally points (its mission_type): not on 3.3, which fences only
        with FENCE_RADIUS and FENCE_ALT_MAX and sends rally points as RALLY_POINT messages."""
        return self.mission_int is not False and self.mavlink2

    @property
    def mission_current_by_message(self) -> bool:
        """A jump to a mission item goes by MISSION_SET_CURRENT (3.3 has no DO_SET_MISSION_CURRENT)."""
        return self.mission_int is False or self.knows(mavlink.MAV_CMD_DO_SET_MISSION_CURRENT) is False

    def unavailable(self, action: str) -> str:
        """Why the setup ``action`` is not available on this firmware ("" when it is, or the version is unknown)."""
        return unavailable(action, self.firmware)

    def motor_test_bound(self, seconds: float, count: int) -> float:
        """How long the vehicle runs a motor test: each motor its seconds, then half as long at rest before the next
        (ArduCopter/motor_test.cpp); the Solo's 3.3 runs one motor, at most 30 s, whatever the count."""
        if self._before(MOTOR_TEST_SEQUENCE_SINCE):
            return min(seconds, MOTOR_TEST_LONGEST_33)
        seconds = min(seconds, MOTOR_TEST_LONGEST)
        return seconds * count + 0.5 * seconds * (count - 1)

