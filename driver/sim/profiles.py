"""Firmware profiles: how one ArduCopter generation answers, so the sim is not only the driver's own notes.

``copter-4`` follows tests/data/recordings/arducopter-4.7-sitl-flight.tlog (ArduCopter
4.7-dev SITL, read with pymavlink); ``solo`` is a stock 3DR Solo (ArduCopter 3.3 era),
from 3DR's sources (github.com/3drobotics/ardupilot-solo: ArduCopter/GCS_Mavlink.pde,
motors.pde, takeoff.pde, land_detector.pde) and shared/reference/arducopter.md.

The start-up of a 4.7 vehicle is replayed as :data:`COPTER4_BOOT`: what it says and why it
refuses to arm while the EKF and GPS come up, stage by stage, at the recording's times
scaled to ``SimConfig.ready_after`` (the recording was ready 40.56 s after its first frame).
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Profile", "Stage", "PROFILES", "COPTER4_BOOT", "SOLO_BOOT", "POSITION_REASONS", "profile_of",
           "speaks_mavlink2", "SOLO_SEVERITY_HIGH"]

# ArduCopter 3.x sent its own gcs_severity numbers in STATUSTEXT (libraries/GCS_MAVLink/GCS_MAVLink.h:
# SEVERITY_LOW=1, MEDIUM, HIGH, CRITICAL): "PreArm: ..." came with 3 (SEVERITY_HIGH), which a modern
# ground station reads as MAV_SEVERITY_ERROR.
SOLO_SEVERITY_HIGH = 3

RECORDED_READY = 40.56      # s from the recording's first frame to "EKF3 IMU0 is using GPS"


@dataclass(frozen=True)
class Stage:
    """One step of the start-up: reached at ``share`` of ready_after (``cap`` s at most, for the steps that
    do not wait for satellites), it says ``texts`` and from then on refuses arming with ``arm_reasons``."""
    share: float
    texts: tuple[str, ...] = ()
    arm_reasons: tuple[str, ...] = ()
    cap: float | None = None
    initialised: bool = True        # "ArduPilot Ready": SYS_STATUS sent, HEARTBEAT no longer BOOT
    ekf: str = "none"               # none | uninitialised | aligning | good   (EKF_STATUS_REPORT)
    gps_fix: bool = False           # GPS_RAW_INT 3D fix, SYS_STATUS GPS healthy
    origin: bool = False            # EKF origin and home set (HOME_POSITION exists)
    ahrs_ok: bool = False           # SYS_STATUS AHRS healthy (gyros consistent)
    ready: bool = False             # EKF has a position: ready to arm, LOCAL_POSITION_NED sent

    def at(self, ready_after: float) -> float:
        scaled = self.share * ready_after
        return scaled if self.cap is None else min(scaled, self.cap)


def _s(seconds: float) -> float:
    return seconds / RECORDED_READY


# Arm reasons that only hold in modes needing a position (GUIDED, LOITER, ...): AP_Arming_Copter's GPS checks
# and the AHRS home check (4.x), pre_arm_gps_checks() with mode_requires_GPS() (3.3) skip the other modes.
POSITION_REASONS = ("Arm: AHRS: waiting for home", "Arm: Need Position Estimate", "PreArm: Need 3D Fix")

# The recording's start-up (its tlog seconds in _s(...)) and the "Arm: ..." lines of each refusal in it;
# "Arm: System not initialised" (before "ArduPilot Ready") is from arducopter.md's first SITL round.
COPTER4_BOOT = (
    Stage(0.0, initialised=False, arm_reasons=("Arm: System not initialised",)),
    Stage(_s(0.86), ("Barometer 1 calibration complete", "Barometer 2 calibration complete"), initialised=False,
          arm_reasons=("Arm: System not initialised",), cap=0.86),
    Stage(_s(1.40), ("ArduPilot Ready", "AHRS: DCM active"), cap=1.40, ekf="uninitialised",
          arm_reasons=("Arm: Accels inconsistent", "Arm: EKF attitude is bad", "Arm: AHRS: EKF3 still initialising")),
    Stage(_s(1.69), ("RC7: SaveWaypoint LOW",), cap=1.69, ekf="uninitialised",       # SITL's RC aux switch
          arm_reasons=("Arm: Accels inconsistent", "Arm: EKF attitude is bad", "Arm: AHRS: EKF3 still initialising")),
    Stage(_s(3.39), ("EKF3 IMU0 initialised", "EKF3 IMU1 initialised", "AHRS: EKF3 active"), cap=3.39,
          arm_reasons=("Arm: Accels inconsistent", "Arm: EKF attitude is bad", "Arm: AHRS: EKF3 still initialising")),
    Stage(_s(4.84), ("EKF3 IMU0 tilt alignment complete", "EKF3 IMU1 tilt alignment complete",
                     "EKF3 IMU0 MAG0 initial yaw alignment complete", "EKF3 IMU1 MAG0 initial yaw alignment complete"),
          cap=4.84, ekf="aligning", arm_reasons=("Arm: Gyros inconsistent", "Arm: AHRS: waiting for home")),
    Stage(_s(8.77), ("GPS 1: probing for u-blox at 230400 baud", "GPS 1: detected u-blox"), ekf="aligning",
          gps_fix=True, arm_reasons=("Arm: Gyros inconsistent", "Arm: AHRS: waiting for home")),
    Stage(_s(18.97), ("EKF3 IMU0 origin set", "Field Elevation Set: {elevation}m", "EKF3 IMU1 origin set"),
          ekf="aligning", gps_fix=True, origin=True,
          arm_reasons=("Arm: Gyros inconsistent", "Arm: Need Position Estimate")),
    Stage(_s(22.0), ekf="aligning", gps_fix=True, origin=True, ahrs_ok=True,
          arm_reasons=("Arm: Need Position Estimate",)),
    Stage(1.0, ("EKF3 IMU0 is using GPS", "EKF3 IMU1 is using GPS"), ekf="good", gps_fix=True, origin=True,
          ahrs_ok=True, ready=True),
)

# 3DR Solo (3.3): pre_arm_checks() refuses "PreArm: Waiting for navigation alignment" until the AHRS is
# healthy, then, in modes that need GPS, "PreArm: Need 3D Fix" until position_ok() (motors.pde).
SOLO_BOOT = (
    Stage(0.0, initialised=False, arm_reasons=("PreArm: Waiting for navigation alignment",)),
    Stage(_s(1.40), cap=1.40, ekf="uninitialised", arm_reasons=("PreArm: Waiting for navigation alignment",)),
    Stage(_s(4.84), cap=4.84, ekf="aligning", ahrs_ok=True, arm_reasons=("PreArm: Need 3D Fix",)),
    Stage(_s(8.77), ekf="aligning", ahrs_ok=True, gps_fix=True, arm_reasons=("PreArm: Need 3D Fix",)),
    Stage(1.0, ekf="good", gps_fix=True, origin=True, ahrs_ok=True, ready=True),
)


@dataclass(frozen=True)
class Profile:
    name: str
    banner: str
    version: tuple[int, int, int, int]      # AUTOPILOT_VERSION.flight_sw_version: major, minor, patch, type
    boot: tuple[Stage, ...]
    mavlink2: bool                  # False: MAVLink 1 only, MAVLink 2 frames are not even parsed
    do_set_mode: bool               # MAV_CMD_DO_SET_MODE (else UNSUPPORTED: SET_MODE + HEARTBEAT only)
    message_commands: bool          # MAV_CMD_REQUEST_MESSAGE, SET/GET_MESSAGE_INTERVAL (else REQUEST_DATA_STREAM)
    extended_sys_state: bool        # EXTENDED_SYS_STATE exists
    home_pushed: bool               # HOME_POSITION (+ GPS_GLOBAL_ORIGIN) sent when set, not only on request
    mode_heartbeat: bool            # a HEARTBEAT goes out at once on a mode change
    setpoint_frames: bool           # SET_POSITION_TARGET_LOCAL_NED's coordinate_frame is read
    setpoint_yaw: bool              # ... and its yaw / yaw_rate
    local_z_from_home: bool         # LOCAL_NED target z is above home, x/y from the EKF origin
    arming_delay: float             # s after arming before the motors spin
    liftoff_after: float            # s of spool-up after that (or the takeoff) before land_complete clears
    arm_severity: int               # STATUSTEXT severity of the arming refusals
    arm_texts: bool                 # "Arming motors" / "Disarming motors"
    calibration_text: bool          # "Disarm to allow calibration" when PREFLIGHT_CALIBRATION is refused
    disarm_in_air_result: int       # COMMAND_ACK result of an unforced disarm in the air
    sitl_texts: bool                # SITL's own lines ("SIM Hit ground at ... m/s")
    texts_after_ack: bool           # a command's STATUSTEXT follows its COMMAND_ACK (4.x queues text)
    banner_id: str = ""             # the banner's system-id line (GCS_MAVLINK::send_banner, see driver/setup/banner.py)
    banner_os: str = ""             # its OS line ("" on SITL: AP_FWVersion has no os_name there)
    banner_id_on_list: bool = True  # the id line comes with every banner (4.x); 3.3: only on DO_SEND_BANNER
    git_hash: str = ""              # fw_string's "(hash)" and AUTOPILOT_VERSION.flight_custom_version
    fence_types: int = 7            # FENCE_TYPE's default: 4.x ceiling|circle|polygon, 3.3 ceiling|circle (3)
    mount: str = "servo"            # gimbal.py: "servo" (4.6 recording, gimbal manager) or "solo" (3.3, MOUNT_*)


# copter-4, from the recording: DO_SET_MODE GUIDED answered ACCEPTED then an immediate HEARTBEAT (7.03 s);
# motors at 1000 us for 2 s after arming (ArduCopter motors.cpp ARMING_DELAY_SEC 2.0), climbing 3.3 s after
# the NAV_TAKEOFF, HEARTBEAT STANDBY (land_complete) until then, so a second NAV_TAKEOFF 2 s into the "climb" was
# ACCEPTED: Mode::do_user_takeoff() only refuses once !ap.land_complete ("can't takeoff again",
# ArduCopter/takeoff.cpp), and _AutoTakeoff::run() keeps land_complete while the throttle slews up.
# Its name and banner are 4.6.3 SITL's (the params, ftp-params and mission recordings): "ArduCopter V4.6.3
# (92b0cd78)", the host's machine id (AP_HAL_SITL get_system_id: no board name), "Frame: QUAD/PLUS"; its
# AUTOPILOT_VERSION 4.6.3 official (type 255), board_version, USB ids and uid 0, uid2 the machine id.
COPTER_4 = Profile(
    name="copter-4", banner="ArduCopter V4.6.3", version=(4, 6, 3, 255), boot=COPTER4_BOOT, mavlink2=True,
    do_set_mode=True, message_commands=True, extended_sys_state=True, home_pushed=True, mode_heartbeat=True,
    setpoint_frames=True, setpoint_yaw=True, local_z_from_home=False, arming_delay=2.0, liftoff_after=1.3,
    arm_severity=2, arm_texts=True, calibration_text=True, disarm_in_air_result=4, sitl_texts=True,
    texts_after_ack=True, banner_id="7d1219c7c4c5404aaa1f6d2a48adfda4", git_hash="92b0cd78")

# solo, from 3drobotics/ardupilot-solo ArduCopter/GCS_Mavlink.pde (the 3.3-based Solo branch):
# * COMMAND_LONG's switch has no MAV_CMD_DO_SET_MODE, REQUEST_MESSAGE nor SET_MESSAGE_INTERVAL: "default:
#   result = MAV_RESULT_UNSUPPORTED" (modes by SET_MODE: handle_set_mode, confirmed by HEARTBEAT).
# * SET_POSITION_TARGET_LOCAL_NED: "for future use: ... yaw_ignore ... yaw_rate_ignore" - yaw and yaw rate
#   are never read, nor is coordinate_frame (every target is LOCAL_NED); position z goes through
#   pv_alt_above_origin(), i.e. it is altitude above home while x/y are from the EKF origin.
# * NAV_TAKEOFF: do_user_takeoff() needs ap.land_complete (takeoff.pde), which the 3.3 land detector clears
#   as soon as the throttle passes get_non_takeoff_throttle() (land_detector.pde): a second NAV_TAKEOFF
#   during the climb is FAILED. No arming delay in 3.3.
# * Disarm in the air without the 21196 force: "result = MAV_RESULT_UNSUPPORTED".
# * The banner on PARAM_REQUEST_LIST: FIRMWARE_STRING, "PX4: <hash> NuttX: <hash>", "Frame: QUAD"; the board's id
#   line ("PX4v2 " and the serial, AP_HAL_PX4 get_system_id) only on MAV_CMD_DO_SEND_BANNER (the hashes and the
#   serial here are the sim's own).
# * "ARMING MOTORS"/"DISARMING MOTORS" only in SITL/HIL builds (motors.pde #if); PREFLIGHT_CALIBRATION
#   while armed is a bare MAV_RESULT_FAILED.
SOLO = Profile(
    name="solo", banner="APM:Copter solo-1.3.1", version=(3, 3, 1, 255), boot=SOLO_BOOT, mavlink2=False,
    do_set_mode=False, message_commands=False, extended_sys_state=False, home_pushed=False,
    mode_heartbeat=False, setpoint_frames=False, setpoint_yaw=False, local_z_from_home=True, arming_delay=0.0,
    liftoff_after=0.5, arm_severity=SOLO_SEVERITY_HIGH, arm_texts=False, calibration_text=False,
    disarm_in_air_result=3, sitl_texts=False, texts_after_ack=False, fence_types=3, mount="solo",
    banner_id="PX4v2 0030001F 3133470C 35363834", banner_os="PX4: 8a5b1bd1 NuttX: 1f4e7e0f", banner_id_on_list=False,
    git_hash="2a3dc4b7")

PROFILES = {p.name: p for p in (COPTER_4, SOLO)}


def profile_of(config) -> Profile:
    name = getattr(config, "profile", "copter-4")
    try:
        return PROFILES[name]
    except KeyError:
        raise ValueError(f"unknown profile {name!r}: one of {', '.join(PROFILES)}") from None


def speaks_mavlink2(config) -> bool:
    """MAVLink 2 unless the profile or ``SimConfig.mavlink2=False`` says MAVLink 1 only."""
    return bool(config.mavlink2) and profile_of(config).mavlink2
