"""ArduCopter as seen over MAVLink, without sockets: physics, modes, commands, streams.

:class:`Autopilot` is stepped by a clock (``step(dt)``), fed decoded MAVLink
messages (``handle(msg, version)``) and hands every message it sends to
``emit`` (the messages themselves are built in telemetry.py). All timers run on
its own sim time, so a test may step it as fast as it likes. The behaviour
follows /work/shared/reference/arducopter.md, which was measured on ArduCopter
SITL, including its quirks: a takeoff ends at 95 % of the altitude and any
setpoint during it aborts the climb; CONDITION_YAW is ACKed but ignored from the
takeoff until the first setpoint; a retried NAV_TAKEOFF in the air is refused.
"""
from __future__ import annotations

import logging
import math
import random
from dataclasses import dataclass
from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .faults import Faults
from .telemetry import EARTH_RADIUS, GRAVITY, METRES_PER_DEG, Telemetry, clamp as _clamp

log = logging.getLogger(__name__)

__all__ = ["Autopilot", "SimTruth", "MODES", "MODE_NAMES", "EARTH_RADIUS"]

FORCE_ARM_MAGIC = 21196

MODES = {
    "STABILIZE": 0, "ACRO": 1, "ALT_HOLD": 2, "AUTO": 3, "GUIDED": 4, "LOITER": 5, "RTL": 6,
    "CIRCLE": 7, "LAND": 9, "DRIFT": 11, "SPORT": 13, "FLIP": 14, "AUTOTUNE": 15, "POSHOLD": 16,
    "BRAKE": 17, "THROW": 18, "AVOID_ADSB": 19, "GUIDED_NOGPS": 20, "SMART_RTL": 21,
    "FLOWHOLD": 22, "FOLLOW": 23, "ZIGZAG": 24,
}
MODE_NAMES = {number: name for name, number in MODES.items()}
# Modes that need a position estimate ("Mode change failed: X requires position").
POSITION_MODES = {3, 4, 5, 6, 7, 11, 16, 17, 19, 21, 23, 24}
# Modes from which ArduCopter refuses to arm.
NOT_ARMABLE = {3, 6, 7, 9, 19, 21, 23}
# REQUEST_DATA_STREAM ids → the messages ArduCopter puts in them (GCS_Mavlink.cpp).
STREAMS = {
    mavlink.MAV_DATA_STREAM_RAW_SENSORS: ("RAW_IMU", "SCALED_IMU2", "SCALED_PRESSURE"),
    mavlink.MAV_DATA_STREAM_EXTENDED_STATUS: ("SYS_STATUS", "POWER_STATUS", "MEMINFO", "MISSION_CURRENT",
                                              "GPS_RAW_INT", "NAV_CONTROLLER_OUTPUT", "EXTENDED_SYS_STATE"),
    mavlink.MAV_DATA_STREAM_RC_CHANNELS: ("SERVO_OUTPUT_RAW", "RC_CHANNELS"),
    mavlink.MAV_DATA_STREAM_POSITION: ("GLOBAL_POSITION_INT", "LOCAL_POSITION_NED"),
    mavlink.MAV_DATA_STREAM_EXTRA1: ("ATTITUDE",),
    mavlink.MAV_DATA_STREAM_EXTRA2: ("VFR_HUD",),
    mavlink.MAV_DATA_STREAM_EXTRA3: ("SYSTEM_TIME", "BATTERY_STATUS", "EKF_STATUS_REPORT", "VIBRATION", "WIND"),
}

# Flight dynamics (SITL-like): first-order velocity response, limited acceleration.
VEL_TAU = 0.7            # s, following a velocity command (SITL: body vx 2 m/s for 5 s moved 8.3 m)
POS_TAU = 0.3            # s, under position control (the controller's feed-forward hides the lag)
YAW_RATE_TAU = 0.12      # s
ATT_TAU = 0.15           # s
ACC_XY = 2.5             # m/s², normal manoeuvres (WPNAV_ACCEL)
ACC_XY_BRAKE = 7.5       # m/s², BRAKE mode
ACC_Z = 2.5              # m/s²
KP_XY = 1.0              # 1/s, position error → speed
KP_Z = 1.0
DECEL_XY = 2.0           # m/s², sqrt law when approaching a target
DECEL_Z = 0.5
TAKEOFF_SPEED = 1.0      # m/s (SITL: 5 m in about 6.5 s)
TAKEOFF_DONE = 0.95      # share of the takeoff altitude at which landed_state turns IN_AIR
LOOK_AHEAD_SPEED = 0.5   # m/s, nose turns to the direction of travel above this
AUTO_YAW_SLEW = math.radians(60.0)
MAX_TILT = math.radians(30.0)
DRAG = 0.15              # 1/s, tilt needed to hold a speed
LAND_DISARM_DELAY = 1.5  # s after touchdown
REBOOT_SILENCE = 1.5     # s without a word while "rebooting"

# SET_POSITION_TARGET type_mask bits (set = ignore).
POS_IGNORE = 0b111
VEL_IGNORE = 0b111000
YAW_IGNORE = 1024
YAW_RATE_IGNORE = 2048

# name → (value, MAV_PARAM_TYPE)
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
    "WPNAV_SPEED": (500.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "WPNAV_SPEED_UP": (250.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "WPNAV_SPEED_DN": (150.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "WPNAV_ACCEL": (250.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "LAND_SPEED": (50, mavlink.MAV_PARAM_TYPE_INT16),
    "LAND_SPEED_HIGH": (0, mavlink.MAV_PARAM_TYPE_INT16),
    "PILOT_SPEED_UP": (250, mavlink.MAV_PARAM_TYPE_INT16),
    "PILOT_SPEED_DN": (0, mavlink.MAV_PARAM_TYPE_INT16),
    "LOIT_SPEED": (1250.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "ANGLE_MAX": (3000, mavlink.MAV_PARAM_TYPE_INT16),
    "WP_YAW_BEHAVIOR": (2, mavlink.MAV_PARAM_TYPE_INT8),
    "FRAME_CLASS": (1, mavlink.MAV_PARAM_TYPE_INT8),
    "FRAME_TYPE": (1, mavlink.MAV_PARAM_TYPE_INT8),
    "BATT_MONITOR": (4, mavlink.MAV_PARAM_TYPE_INT8),
    "BATT_CAPACITY": (5200, mavlink.MAV_PARAM_TYPE_INT32),
    "BATT_LOW_VOLT": (0.0, mavlink.MAV_PARAM_TYPE_REAL32),
    "FS_GCS_ENABLE": (0, mavlink.MAV_PARAM_TYPE_INT8),
    "FENCE_ENABLE": (0, mavlink.MAV_PARAM_TYPE_INT8),
    "CHUTE_ENABLED": (1, mavlink.MAV_PARAM_TYPE_INT8),
    "CHUTE_ALT_MIN": (10, mavlink.MAV_PARAM_TYPE_INT16),
    "SERIAL0_PROTOCOL": (2, mavlink.MAV_PARAM_TYPE_INT8),
    "SR0_EXT_STAT": (0, mavlink.MAV_PARAM_TYPE_INT16),
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


@dataclass(frozen=True)
class SimTruth:
    """What the simulated vehicle really does, for test assertions (NED from home, radians)."""
    time: float
    armed: bool
    mode: str
    custom_mode: int
    landed_state: int
    north: float
    east: float
    down: float
    vn: float
    ve: float
    vd: float
    roll: float
    pitch: float
    yaw: float
    yaw_rate: float
    battery_voltage: float
    battery_remaining: float
    ready: bool
    last_command: str

    @property
    def altitude(self) -> float:
        return -self.down

    @property
    def heading_deg(self) -> float:
        return math.degrees(self.yaw) % 360.0

    @property
    def ground_speed(self) -> float:
        return math.hypot(self.vn, self.ve)


def wrap_pi(angle: float) -> float:
    """Angle in (-pi, pi]."""
    a = math.fmod(angle + math.pi, 2.0 * math.pi)
    if a <= 0.0:
        a += 2.0 * math.pi
    return a - math.pi


def _finite(*values: float) -> bool:
    return all(math.isfinite(v) for v in values)


def command_name(command: int) -> str:
    entry = mavlink.enums["MAV_CMD"].get(command)
    return entry.name if entry is not None else str(command)


class Autopilot(Telemetry):
    """One ArduCopter: state, flight modes, command handling and telemetry streams."""

    def __init__(self, config, faults: Faults | None = None,
                 emit: Callable[[object], None] | None = None) -> None:
        self.config = config
        self.faults = faults if faults is not None else Faults()
        self.emit = emit or (lambda msg: None)
        self.rng = random.Random(config.seed)
        self.factory = mavlink.MAVLink(None, srcSystem=config.system_id, srcComponent=config.component_id)
        lat, lon, alt, heading = config.home
        self.home_lat, self.home_lon, self.home_alt = float(lat), float(lon), float(alt)
        self.m_per_deg_lon = METRES_PER_DEG * math.cos(math.radians(self.home_lat))
        self.params = {name: value for name, (value, _type) in DEFAULT_PARAMS.items()}
        self.params["SYSID_THISMAV"] = config.system_id
        self.params["BATT_CAPACITY"] = config.battery_capacity_mah
        self.params["DISARM_DELAY"] = config.auto_disarm_after
        self.param_names = list(DEFAULT_PARAMS)
        self.t = 0.0
        # vehicle state
        self.n = self.e = self.d = 0.0
        self.vn = self.ve = self.vd = 0.0
        self.roll = self.pitch = 0.0
        self.yaw = wrap_pi(math.radians(float(heading)))
        self.roll_rate = self.pitch_rate = self.yaw_rate = 0.0
        self.acc_body = (0.0, 0.0, -GRAVITY)
        self._tau = POS_TAU
        self.consumed_mah = 0.0
        self.current = 0.5
        self.voltage = self._ocv(1.0) * config.battery_cells
        self.last_command = ""
        # message scheduling: name → [interval s, next due]
        self.intervals: dict[str, list[float]] = {}
        self.heartbeat_interval = 1.0
        self.next_heartbeat = 0.0
        self.next_prearm_report = 30.0
        self.manual = None               # (x, y, z, r, time) from MANUAL_CONTROL
        self.safety_on = False
        self.chute_released = False
        self.speed_override = None       # DO_CHANGE_SPEED, m/s
        self.rebooting_until: float | None = None
        self._boot()

    # -- lifecycle -------------------------------------------------------------------------------
    def _boot(self) -> None:
        """Power-on (and reboot) state: disarmed on the ground, not ready for ready_after seconds."""
        self.boot_time = self.t
        self.ready = False
        self.armed = False
        self.mode = MODES["STABILIZE"]
        self.landed = True
        self.d = 0.0
        self.vn = self.ve = self.vd = 0.0
        self.armed_at = None
        self.touchdown_at = None
        self.takeoff_alt = None
        self.guided = "hold"              # takeoff | hold | velocity | position
        self.vel_target = (0.0, 0.0, 0.0)
        self.vel_time = 0.0
        self.pos_target = (0.0, 0.0, 0.0)
        self.hold_point = None
        self.yaw_mode = "hold"            # hold | rate | fixed | look_ahead
        self.yaw_rate_cmd = 0.0
        self.yaw_remaining = 0.0
        self.yaw_slew = AUTO_YAW_SLEW
        self.yaw_cmds_enabled = True
        self.rtl_phase = None
        self.rtl_alt = 0.0
        self.rtl_loiter_until = 0.0
        self.chute_released = False
        self.home_set = False

    def reboot(self) -> None:
        self.rebooting_until = self.t + REBOOT_SILENCE
        self.armed = False

    # -- time --------------------------------------------------------------------------------------
    def step(self, dt: float) -> None:
        self.t += dt
        if self.rebooting_until is not None:
            if self.t < self.rebooting_until:
                self._physics(dt)
                return
            self.rebooting_until = None
            self._boot()
            self.next_heartbeat = self.t
            self._text(mavlink.MAV_SEVERITY_INFO, "ArduCopter V4.5.7 (2a3dc4b7)")
            self._text(mavlink.MAV_SEVERITY_INFO, "Frame: QUAD/X")
        self._readiness()
        self._timers()
        self._physics(dt)
        self._battery(dt)
        self._send_due()

    @property
    def boot_seconds(self) -> float:
        return self.t - self.boot_time

    def time_boot_ms(self) -> int:
        return int(self.boot_seconds * 1000) & 0xFFFFFFFF

    def _readiness(self) -> None:
        if not self.ready and self.boot_seconds >= self.config.ready_after:
            self.ready = True
            self.home_set = True
            self._text(mavlink.MAV_SEVERITY_INFO, "EKF3 IMU0 origin set")
            self._text(mavlink.MAV_SEVERITY_INFO, "EKF3 IMU0 is using GPS")
            self._send_now("HOME_POSITION")
        if not self.ready and not self.armed and self.boot_seconds >= self.next_prearm_report:
            # ArduCopter repeats the failing pre-arm check every 30 s while disarmed.
            self.next_prearm_report = self.boot_seconds + 30.0
            if self.params["ARMING_CHECK"]:
                self._text(mavlink.MAV_SEVERITY_CRITICAL, self._prearm_failure())

    def _timers(self) -> None:
        """Disarm on the ground: soon after a landing, DISARM_DELAY after arming without takeoff."""
        if not self.armed or not self.landed:
            return
        if self.touchdown_at is None:
            self.touchdown_at = self.t
        on_ground = self.t - self.touchdown_at
        if self.mode == MODES["LAND"] or self.rtl_phase == "land":
            if on_ground >= LAND_DISARM_DELAY:
                self._disarm("Disarming motors")
            return
        delay = float(self.params["DISARM_DELAY"])
        if delay > 0 and on_ground >= delay:
            self._disarm("Disarming motors")

    # -- arming ----------------------------------------------------------------------------------
    def _prearm_failure(self) -> str | None:
        if self.faults.refuse_arm:
            return f"PreArm: {self.faults.refuse_arm}"
        if self.safety_on:
            return "PreArm: Hardware safety switch"
        if not self.ready and self.params["ARMING_CHECK"]:
            if self.boot_seconds < 0.6 * self.config.ready_after:
                return "PreArm: Need 3D Fix"
            return "PreArm: EKF attitude is bad"
        return None

    def _arm(self, force: bool) -> tuple[int, str | None]:
        if self.armed:
            return mavlink.MAV_RESULT_ACCEPTED, None
        if not force:
            reason = self._prearm_failure()
            if reason:
                return mavlink.MAV_RESULT_FAILED, reason
            if self.mode in NOT_ARMABLE:
                return mavlink.MAV_RESULT_FAILED, "Arm: Mode not armable"
        self.armed = True
        self.armed_at = self.t
        self.landed = self.d >= -0.05
        self.touchdown_at = self.t if self.landed else None
        self.hold_point = None
        self.guided = "hold"
        log.info("armed in %s", MODE_NAMES.get(self.mode, self.mode))
        self._send_now("HOME_POSITION")          # ArduCopter (re)sets home when it arms
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _disarm(self, text: str | None = None) -> None:
        if not self.armed:
            return
        self.armed = False
        self.armed_at = None
        self.takeoff_alt = None
        self.rtl_phase = None if self.mode != MODES["RTL"] else self.rtl_phase
        if text:
            self._text(mavlink.MAV_SEVERITY_INFO, text)
        log.info("disarmed")

    # -- modes -------------------------------------------------------------------------------------
    def set_mode(self, number: int) -> bool:
        if number not in MODE_NAMES:
            self._text(mavlink.MAV_SEVERITY_WARNING, f"No such mode {number}")
            return False
        if number in POSITION_MODES and not self.ready:
            self._text(mavlink.MAV_SEVERITY_WARNING, f"Mode change failed: {MODE_NAMES[number]} requires position")
            return False
        if number == self.mode:
            return True
        self.mode = number
        self.hold_point = None
        self.takeoff_alt = None
        self.rtl_phase = None
        if number == MODES["GUIDED"]:
            self.guided = "hold"
            self.yaw_cmds_enabled = True
            self.yaw_mode = "hold"
        elif number == MODES["RTL"]:
            self.rtl_phase = "land" if self.landed else "climb"
            self.yaw_mode = "hold"
        else:
            self.yaw_mode = "hold"
        log.info("mode %s", MODE_NAMES[number])
        return True

    @property
    def mode_name(self) -> str:
        return MODE_NAMES.get(self.mode, str(self.mode))

    def landed_state(self) -> int:
        if self.landed or (not self.armed and self.d >= -0.05):
            return mavlink.MAV_LANDED_STATE_ON_GROUND
        if self.armed and self.mode == MODES["GUIDED"] and self.guided == "takeoff":
            return mavlink.MAV_LANDED_STATE_TAKEOFF
        if self.armed and (self.mode == MODES["LAND"] or (self.mode == MODES["RTL"] and self.rtl_phase == "land")):
            return mavlink.MAV_LANDED_STATE_LANDING
        return mavlink.MAV_LANDED_STATE_IN_AIR

    # -- physics -------------------------------------------------------------------------------------
    def _physics(self, dt: float) -> None:
        old = (self.vn, self.ve, self.vd)
        if self.armed:
            self._tau = POS_TAU
            want_n, want_e, want_d, acc_xy = self._controller()
            gain = min(1.0, dt / self._tau)
            dvn, dve = (want_n - self.vn) * gain, (want_e - self.ve) * gain
            limit = acc_xy * dt
            size = math.hypot(dvn, dve)
            if size > limit:
                dvn, dve = dvn * limit / size, dve * limit / size
            dvd = _clamp((want_d - self.vd) * gain, -ACC_Z * dt, ACC_Z * dt)
            self.vn, self.ve, self.vd = self.vn + dvn, self.ve + dve, self.vd + dvd
            if self.landed:
                if want_d < -0.05:           # climbing away: no longer landed
                    self.landed = False
                    self.touchdown_at = None
                else:
                    self.vn = self.ve = self.vd = 0.0
            self._yaw(dt)
        else:
            # Motors off: fall (under a canopy once the parachute is out), drift to a stop.
            drag = 0.6 if self.chute_released else 0.045
            self.vd += (GRAVITY - drag * self.vd * abs(self.vd)) * dt
            self.vn -= self.vn * min(1.0, 0.5 * dt)
            self.ve -= self.ve * min(1.0, 0.5 * dt)
            self.yaw_rate -= self.yaw_rate * min(1.0, dt / 0.5)
            self.yaw = wrap_pi(self.yaw + self.yaw_rate * dt)
        self.n += self.vn * dt
        self.e += self.ve * dt
        self.d += self.vd * dt
        if self.guided == "takeoff" and self.takeoff_alt is not None and -self.d >= TAKEOFF_DONE * self.takeoff_alt:
            # ArduCopter ends the takeoff when its climb target arrives; the vehicle is then ~95 % up
            self.guided = "hold"
            self.hold_point = (self.hold_point or (self.n, self.e))[:2] + (-self.takeoff_alt,)
            log.info("takeoff complete at %.2f m", -self.d)
        if self.d >= 0.0:
            self.d = 0.0
            if self.vd > 0.0 or self.landed or not self.armed:
                if self.armed and not self.landed and self.vd >= 0.0:
                    self._touchdown()
                self.vd = 0.0
                self.vn = self.ve = 0.0
                if not self.armed:
                    self.chute_released = False
        self._attitude(dt, old)

    def _touchdown(self) -> None:
        self.landed = True
        self.touchdown_at = self.t
        self.takeoff_alt = None
        self.hold_point = None
        if self.mode == MODES["LAND"] or self.rtl_phase == "land":
            self._text(mavlink.MAV_SEVERITY_INFO, "Land complete")
        log.info("touchdown at %.1f, %.1f", self.n, self.e)

    def _attitude(self, dt: float, old: tuple[float, float, float]) -> None:
        an = (self.vn - old[0]) / dt + DRAG * self.vn
        ae = (self.ve - old[1]) / dt + DRAG * self.ve
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        fwd, right = c * an + s * ae, -s * an + c * ae
        if self.armed and not self.landed:
            pitch_t = _clamp(-math.atan2(fwd, GRAVITY), -MAX_TILT, MAX_TILT)
            roll_t = _clamp(math.atan2(right * math.cos(pitch_t), GRAVITY), -MAX_TILT, MAX_TILT)
        else:
            pitch_t = roll_t = 0.0
        gain = min(1.0, dt / ATT_TAU)
        roll = self.roll + (roll_t - self.roll) * gain
        pitch = self.pitch + (pitch_t - self.pitch) * gain
        self.roll_rate, self.pitch_rate = (roll - self.roll) / dt, (pitch - self.pitch) / dt
        self.roll, self.pitch = roll, pitch
        az = (self.vd - old[2]) / dt
        self.acc_body = (fwd - DRAG * (c * self.vn + s * self.ve), right, az - GRAVITY)

    def _yaw(self, dt: float) -> None:
        fixed = self.yaw_mode == "fixed"
        if self.landed:
            target = 0.0
        elif self.yaw_mode == "rate":
            target = self.yaw_rate_cmd
        elif fixed:
            rem = self.yaw_remaining
            target = math.copysign(min(self.yaw_slew, abs(rem) * 3.0), rem) if abs(rem) > 1e-4 else 0.0
        elif self.yaw_mode == "look_ahead" and math.hypot(self.vn, self.ve) > LOOK_AHEAD_SPEED:
            error = wrap_pi(math.atan2(self.ve, self.vn) - self.yaw)
            target = _clamp(error * 3.0, -AUTO_YAW_SLEW, AUTO_YAW_SLEW)
        else:
            target = 0.0
        rate = self.yaw_rate + (target - self.yaw_rate) * min(1.0, dt / YAW_RATE_TAU)
        turn = rate * dt
        if fixed and not self.landed:
            rem = self.yaw_remaining
            if (rem >= 0 and turn > rem) or (rem <= 0 and turn < rem):
                turn = rem
            self.yaw_remaining = rem - turn
        self.yaw_rate = turn / dt
        self.yaw = wrap_pi(self.yaw + turn)

    def _pos_ctrl(self, target, speed_xy: float, speed_up: float, speed_dn: float,
                  decel_z: float = DECEL_Z) -> tuple[float, float, float]:
        """Velocity toward a point: proportional, square-root shaped so it stops on it."""
        dn, de, dd = target[0] - self.n, target[1] - self.e, target[2] - self.d
        dist = math.hypot(dn, de)
        vn = ve = 0.0
        if dist > 1e-6:
            speed = min(speed_xy, KP_XY * dist, math.sqrt(2.0 * DECEL_XY * dist))
            vn, ve = speed * dn / dist, speed * de / dist
        speed = min(KP_Z * abs(dd), math.sqrt(2.0 * decel_z * abs(dd)))
        vd = _clamp(math.copysign(speed, dd), -speed_up, speed_dn)
        return vn, ve, vd

    def _hold(self, keep_down: float | None = None) -> tuple[float, float, float]:
        """Brake, then hold the point where the vehicle stopped."""
        if self.hold_point is None:
            if math.hypot(self.vn, self.ve) < 0.2 and abs(self.vd) < 0.2:
                self.hold_point = (self.n, self.e, self.d if keep_down is None else keep_down)
            else:
                return 0.0, 0.0, 0.0
        return self._pos_ctrl(self.hold_point, self._wp_speed(), self._speed_up(), self._speed_dn())

    def _wp_speed(self) -> float:
        if self.speed_override:
            return self.speed_override
        return max(0.5, float(self.params["WPNAV_SPEED"]) / 100.0)

    def _speed_up(self) -> float:
        return max(0.1, float(self.params["WPNAV_SPEED_UP"]) / 100.0)

    def _speed_dn(self) -> float:
        return max(0.1, float(self.params["WPNAV_SPEED_DN"]) / 100.0)

    def _land_speed(self) -> float:
        if -self.d > 10.0:
            high = float(self.params["LAND_SPEED_HIGH"]) / 100.0
            return high if high > 0 else self._speed_dn()
        return max(0.1, float(self.params["LAND_SPEED"]) / 100.0)

    def _controller(self) -> tuple[float, float, float, float]:
        """Desired NED velocity for the current mode, and the acceleration limit."""
        if self.landed and not (self.mode == MODES["GUIDED"] and self.guided == "takeoff"):
            manual = self._manual()
            if manual is not None and manual[2] < -0.3 and self.mode not in (MODES["GUIDED"], MODES["LAND"],
                                                                            MODES["RTL"], MODES["AUTO"]):
                return 0.0, 0.0, manual[2], ACC_XY
            return 0.0, 0.0, 0.0, ACC_XY
        mode = self.mode
        if mode == MODES["GUIDED"]:
            return (*self._guided(), ACC_XY)
        if mode == MODES["LAND"]:
            vn, ve, _ = self._hold(keep_down=self.d)
            return vn, ve, self._land_speed(), ACC_XY
        if mode == MODES["RTL"]:
            return (*self._rtl(), ACC_XY)
        if mode == MODES["BRAKE"]:
            return (*self._hold(), ACC_XY_BRAKE)
        # LOITER, POSHOLD, ALT_HOLD and the rest: hold, nudged by MANUAL_CONTROL sticks.
        manual = self._manual()
        if manual is not None and any(abs(v) > 1e-3 for v in manual):
            fwd, right, down, yaw_rate = manual
            self.yaw_mode, self.yaw_rate_cmd = "rate", yaw_rate
            if abs(fwd) > 1e-3 or abs(right) > 1e-3 or abs(down) > 1e-3:
                c, s = math.cos(self.yaw), math.sin(self.yaw)
                self.hold_point = None
                self._tau = VEL_TAU
                return c * fwd - s * right, s * fwd + c * right, down, ACC_XY
        elif self.yaw_mode == "rate":
            self.yaw_mode = "hold"
        return (*self._hold(), ACC_XY)

    def _manual(self) -> tuple[float, float, float, float] | None:
        """MANUAL_CONTROL sticks as (forward, right, down m/s, yaw rate rad/s), None when stale."""
        if self.manual is None or self.t - self.manual[4] > 1.0:
            return None
        x, y, z, r, _ = self.manual
        dead = lambda v: 0.0 if abs(v) < 0.1 else v  # noqa: E731
        speed = 5.0
        climb = (z - 0.5) * 2.0
        climb = 0.0 if abs(climb) < 0.2 else climb
        down = -climb * self._speed_up() if climb > 0 else -climb * self._speed_dn()
        return dead(x) * speed, dead(y) * speed, down, dead(r) * math.radians(90.0)

    def _guided(self) -> tuple[float, float, float]:
        if self.guided == "takeoff":
            target = self.hold_point or (self.n, self.e, 0.0)
            return self._pos_ctrl((target[0], target[1], -self.takeoff_alt), 2.0, TAKEOFF_SPEED,
                                  self._speed_dn())
        if self.guided == "velocity":
            if self.t - self.vel_time > float(self.params["GUID_TIMEOUT"]):
                self.guided = "hold"
                self.hold_point = None
                if self.yaw_mode == "rate":
                    self.yaw_mode, self.yaw_rate_cmd = "hold", 0.0
                return self._hold()
            self._tau = VEL_TAU
            return self.vel_target
        if self.guided == "position":
            return self._pos_ctrl(self.pos_target, self._wp_speed(), self._speed_up(), self._speed_dn())
        return self._hold()

    def _rtl(self) -> tuple[float, float, float]:
        rtl_alt = max(float(self.params["RTL_ALT"]) / 100.0, 1.0)
        if self.rtl_phase == "climb":
            if self.hold_point is None:
                self._hold()
                if self.hold_point is None:
                    return 0.0, 0.0, 0.0
            self.rtl_alt = max(rtl_alt, -self.d)
            target = (self.hold_point[0], self.hold_point[1], -self.rtl_alt)
            if -self.d >= self.rtl_alt - 0.2:
                self.rtl_phase = "return"
                self.yaw_mode = "look_ahead"
            return self._pos_ctrl(target, self._wp_speed(), self._speed_up(), self._speed_dn())
        if self.rtl_phase == "return":
            speed = float(self.params["RTL_SPEED"]) / 100.0 or self._wp_speed()
            target = (0.0, 0.0, -self.rtl_alt)
            if math.hypot(self.n, self.e) < 0.3 and math.hypot(self.vn, self.ve) < 0.3:
                self.rtl_phase = "loiter"
                self.rtl_loiter_until = self.t + float(self.params["RTL_LOIT_TIME"]) / 1000.0
                self.yaw_mode = "hold"
            return self._pos_ctrl(target, speed, self._speed_up(), self._speed_dn())
        if self.rtl_phase == "loiter":
            if self.t >= self.rtl_loiter_until:
                self.rtl_phase = "land"
                self.hold_point = None
            return self._pos_ctrl((0.0, 0.0, -self.rtl_alt), self._wp_speed(), self._speed_up(), self._speed_dn())
        # final descent
        vn, ve, _ = self._hold(keep_down=self.d)
        return vn, ve, self._land_speed()

    def _battery(self, dt: float) -> None:
        if not self.armed:
            current = 0.5
        elif self.landed:
            current = 2.0
        else:
            current = 15.0 + 0.6 * math.hypot(self.vn, self.ve) + 3.0 * max(0.0, -self.vd)
        self.current = current
        self.consumed_mah += current * dt / 3.6
        cells = self.config.battery_cells
        self.voltage = max(0.0, cells * self._ocv(self.remaining / 100.0) - current * 0.01 * cells)

    @property
    def remaining(self) -> float:
        return _clamp(100.0 * (1.0 - self.consumed_mah / max(1.0, float(self.params["BATT_CAPACITY"]))), 0.0, 100.0)

    @staticmethod
    def _ocv(charge: float) -> float:
        """Open-circuit LiPo cell voltage for a state of charge 0..1."""
        table = ((0.0, 3.0), (0.05, 3.3), (0.17, 3.81), (0.5, 3.93), (0.9, 4.1), (1.0, 4.2))
        charge = _clamp(charge, 0.0, 1.0)
        for (c0, v0), (c1, v1) in zip(table, table[1:]):
            if charge <= c1:
                return v0 + (v1 - v0) * (charge - c0) / (c1 - c0)
        return table[-1][1]

    # -- incoming ------------------------------------------------------------------------------------
    def handle(self, msg, version: int = 2) -> None:
        """One decoded MAVLink message from a ground station."""
        if self.rebooting_until is not None:
            return
        kind = msg.get_type()
        if getattr(msg, "target_system", 0) not in (0, self.config.system_id):
            return
        if getattr(msg, "target_component", 0) not in (0, self.config.component_id):
            return
        handler = getattr(self, "_on_" + kind.lower(), None)
        if handler is not None:
            try:
                handler(msg)
            except Exception:  # a malformed field must never stop the vehicle
                log.exception("handling %s", kind)

    def _on_heartbeat(self, msg) -> None:
        pass

    def _on_request_data_stream(self, msg) -> None:
        if msg.req_stream_id == mavlink.MAV_DATA_STREAM_ALL:
            streams = list(STREAMS)
        elif msg.req_stream_id in STREAMS:
            streams = [msg.req_stream_id]
        else:
            return
        rate = msg.req_message_rate if msg.start_stop else 0
        rate = min(int(rate), 50)
        for stream in streams:
            if stream in STREAM_PARAMS:
                self.params[STREAM_PARAMS[stream]] = rate
            for name in STREAMS[stream]:
                self._set_interval(name, 1.0 / rate if rate > 0 else None)

    def _set_interval(self, name: str, interval: float | None) -> None:
        if name == "HEARTBEAT":
            self.heartbeat_interval = interval if interval else 1.0
            return
        if interval is None:
            self.intervals.pop(name, None)
        else:
            interval = max(interval, 1.0 / float(self.config.rate_hz))
            current = self.intervals.get(name)
            due = self.t if current is None else min(current[1], self.t + interval)
            self.intervals[name] = [interval, due]

    def _on_command_long(self, msg) -> None:
        params = (msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6, msg.param7)
        self._command(msg, msg.command, params)

    def _on_command_int(self, msg) -> None:
        params = (msg.param1, msg.param2, msg.param3, msg.param4, float(msg.x), float(msg.y), msg.z)
        self._command(msg, msg.command, params)

    def _command(self, msg, command: int, params) -> None:
        self.last_command = command_name(command)
        if self.faults.ignores(command):
            self.faults.ignored.append(command)
            log.info("ignoring %s (fault)", self.last_command)
            return
        handler = getattr(self, "_cmd_" + self.last_command.removeprefix("MAV_CMD_").lower(), None)
        if handler is None:
            result, follow = mavlink.MAV_RESULT_UNSUPPORTED, None
        else:
            try:
                result, follow = handler(*params)
            except (ValueError, OverflowError, TypeError):
                result, follow = mavlink.MAV_RESULT_DENIED, None
        src_system, src_component = msg.get_srcSystem(), msg.get_srcComponent()
        self.emit(self.factory.command_ack_encode(command, result, 0, 0, src_system, src_component))
        if follow is not None:
            follow()

    # each returns (MAV_RESULT, callable to run after the ACK or None)
    def _cmd_component_arm_disarm(self, p1, p2, *_):
        force = int(p2) == FORCE_ARM_MAGIC
        if p1 == 1:
            result, reason = self._arm(force)
            if reason:
                self._text(mavlink.MAV_SEVERITY_CRITICAL, reason)
            return result, None
        if p1 == 0:
            if self.armed and not self.landed and not force:
                return mavlink.MAV_RESULT_FAILED, None
            self._disarm()
            return mavlink.MAV_RESULT_ACCEPTED, None
        return mavlink.MAV_RESULT_DENIED, None

    def _cmd_do_set_mode(self, p1, p2, *_):
        return self._set_mode_common(int(p1), int(p2)), None

    def _set_mode_common(self, base_mode: int, custom_mode: int) -> int:
        if base_mode & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
            return mavlink.MAV_RESULT_ACCEPTED if self.set_mode(custom_mode) else mavlink.MAV_RESULT_FAILED
        if base_mode == mavlink.MAV_MODE_FLAG_DECODE_POSITION_SAFETY:
            if custom_mode == 0:
                self.safety_on = False
                return mavlink.MAV_RESULT_ACCEPTED
            if custom_mode == 1:
                if self.armed:
                    return mavlink.MAV_RESULT_FAILED
                self.safety_on = True
                return mavlink.MAV_RESULT_ACCEPTED
        return mavlink.MAV_RESULT_DENIED

    def _cmd_nav_takeoff(self, p1, p2, p3, p4, p5, p6, p7):
        if self.mode != MODES["GUIDED"] or not self.armed or not self.landed or not _finite(p7):
            return mavlink.MAV_RESULT_FAILED, None
        altitude = _clamp(float(p7), 1.0, 1000.0)
        self.takeoff_alt = altitude
        self.guided = "takeoff"
        self.hold_point = (self.n, self.e, 0.0)
        self.yaw_cmds_enabled = False
        self.yaw_mode = "hold"
        self.landed = False
        self.touchdown_at = None
        log.info("takeoff to %.1f m", altitude)
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_nav_land(self, *_):
        return (mavlink.MAV_RESULT_ACCEPTED if self.set_mode(MODES["LAND"]) else mavlink.MAV_RESULT_FAILED), None

    def _cmd_nav_return_to_launch(self, *_):
        return (mavlink.MAV_RESULT_ACCEPTED if self.set_mode(MODES["RTL"]) else mavlink.MAV_RESULT_FAILED), None

    def _cmd_condition_yaw(self, p1, p2, p3, p4, *_):
        if not (0.0 <= p1 <= 360.0) or p4 not in (0.0, 1.0) or not _finite(p2, p3):
            return mavlink.MAV_RESULT_FAILED, None
        if self.mode != MODES["GUIDED"] or self.landed or not self.armed or not self.yaw_cmds_enabled:
            return mavlink.MAV_RESULT_ACCEPTED, None   # accepted, but nothing turns (ArduCopter)
        angle = math.radians(p1)
        direction = int(p3)
        if p4 == 1.0:
            remaining = angle * (-1.0 if direction < 0 else 1.0)
        else:
            delta = wrap_pi(angle - self.yaw)
            if direction > 0 and delta < 0:
                delta += 2.0 * math.pi
            elif direction < 0 and delta > 0:
                delta -= 2.0 * math.pi
            remaining = delta
        self.yaw_mode = "fixed"
        self.yaw_remaining = remaining
        self.yaw_slew = math.radians(p2) if p2 > 0 else AUTO_YAW_SLEW
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_do_change_speed(self, p1, p2, *_):
        if _finite(p2) and p2 > 0:
            self.speed_override = min(float(p2), 20.0)
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_set_message_interval(self, p1, p2, *_):
        msg_id = int(p1)
        cls = mavlink.mavlink_map.get(msg_id)
        if cls is None or (cls.msgname != "HEARTBEAT" and not hasattr(self, "_msg_" + cls.msgname.lower())):
            return mavlink.MAV_RESULT_FAILED, None
        if p2 < 0:
            self._set_interval(cls.msgname, None)
        elif p2 == 0:   # default rate: what the data streams say
            rate = 0
            for stream, names in STREAMS.items():
                if cls.msgname in names and stream in STREAM_PARAMS:
                    rate = self.params[STREAM_PARAMS[stream]]
            self._set_interval(cls.msgname, 1.0 / rate if rate else None)
        else:
            self._set_interval(cls.msgname, float(p2) / 1e6)
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_get_message_interval(self, p1, *_):
        cls = mavlink.mavlink_map.get(int(p1))
        if cls is None:
            return mavlink.MAV_RESULT_FAILED, None
        if cls.msgname == "HEARTBEAT":
            interval = int(self.heartbeat_interval * 1e6)
        else:
            entry = self.intervals.get(cls.msgname)
            interval = int(entry[0] * 1e6) if entry else -1
        return mavlink.MAV_RESULT_ACCEPTED, lambda: self.emit(self.factory.message_interval_encode(cls.id, interval))

    def _cmd_request_message(self, p1, *_):
        cls = mavlink.mavlink_map.get(int(p1))
        if cls is None or not hasattr(self, "_msg_" + cls.msgname.lower()):
            return mavlink.MAV_RESULT_FAILED, None
        return mavlink.MAV_RESULT_ACCEPTED, lambda: self._send_now(cls.msgname)

    def _cmd_get_home_position(self, *_):
        return mavlink.MAV_RESULT_ACCEPTED, lambda: self._send_now("HOME_POSITION")

    def _cmd_request_autopilot_capabilities(self, *_):
        return mavlink.MAV_RESULT_ACCEPTED, lambda: self._send_now("AUTOPILOT_VERSION")

    def _cmd_preflight_calibration(self, *_):
        if self.armed:
            return mavlink.MAV_RESULT_TEMPORARILY_REJECTED, None   # "*preflight*, remember?"
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_preflight_reboot_shutdown(self, p1, *_):
        if self.armed:
            return mavlink.MAV_RESULT_FAILED, None
        if int(p1) in (1, 3):
            return mavlink.MAV_RESULT_ACCEPTED, self.reboot
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_do_parachute(self, p1, *_):
        action = int(p1)
        if action == mavlink.PARACHUTE_DISABLE:
            self.params["CHUTE_ENABLED"] = 0
        elif action == mavlink.PARACHUTE_ENABLE:
            self.params["CHUTE_ENABLED"] = 1
        elif action == mavlink.PARACHUTE_RELEASE:
            return mavlink.MAV_RESULT_ACCEPTED, self._release_parachute
        else:
            return mavlink.MAV_RESULT_FAILED, None
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _release_parachute(self) -> None:
        if not self.params["CHUTE_ENABLED"]:
            return
        if self.landed or not self.armed:
            self._text(mavlink.MAV_SEVERITY_INFO, "Parachute: Landed")
            return
        if -self.d < float(self.params["CHUTE_ALT_MIN"]):
            self._text(mavlink.MAV_SEVERITY_ALERT, "Parachute: Too low")
            return
        self._text(mavlink.MAV_SEVERITY_INFO, "Parachute: Released")
        self.chute_released = True
        self._disarm()

    # -- guided targets ---------------------------------------------------------------------------
    def _guided_accepts(self) -> bool:
        return self.mode == MODES["GUIDED"] and self.armed and not self.landed

    def _on_set_position_target_local_ned(self, msg) -> None:
        frame, mask = msg.coordinate_frame, msg.type_mask
        if not self._guided_accepts():
            return
        values = (msg.x, msg.y, msg.z, msg.vx, msg.vy, msg.vz, msg.yaw, msg.yaw_rate)
        if not _finite(*values):
            log.warning("non-finite SET_POSITION_TARGET_LOCAL_NED ignored")
            return
        body = frame in (mavlink.MAV_FRAME_BODY_NED, mavlink.MAV_FRAME_BODY_OFFSET_NED)
        if frame not in (mavlink.MAV_FRAME_LOCAL_NED, mavlink.MAV_FRAME_LOCAL_OFFSET_NED) and not body:
            return
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        use_pos = not (mask & POS_IGNORE)
        use_vel = not (mask & VEL_IGNORE)
        if use_pos:
            x, y, z = msg.x, msg.y, msg.z
            if body:
                x, y = c * x - s * y, s * x + c * y
            if frame != mavlink.MAV_FRAME_LOCAL_NED:
                x, y, z = x + self.n, y + self.e, z + self.d
            self._go_to(x, y, z)
        elif use_vel:
            vx, vy, vz = msg.vx, msg.vy, msg.vz
            if body:
                vx, vy = c * vx - s * vy, s * vx + c * vy
            self._fly_velocity(vx, vy, vz)
        else:
            return
        self._target_yaw(mask, msg.yaw, msg.yaw_rate, relative=body)

    def _on_set_position_target_global_int(self, msg) -> None:
        if not self._guided_accepts():
            return
        mask = msg.type_mask
        if not _finite(msg.alt, msg.vx, msg.vy, msg.vz, msg.yaw, msg.yaw_rate):
            return
        if not (mask & POS_IGNORE):
            north = (msg.lat_int / 1e7 - self.home_lat) * METRES_PER_DEG
            east = (msg.lon_int / 1e7 - self.home_lon) * self.m_per_deg_lon
            if msg.coordinate_frame in (mavlink.MAV_FRAME_GLOBAL, mavlink.MAV_FRAME_GLOBAL_INT):
                down = -(msg.alt - self.home_alt)
            else:
                down = -msg.alt
            self._go_to(north, east, down)
        elif not (mask & VEL_IGNORE):
            self._fly_velocity(msg.vx, msg.vy, msg.vz)
        else:
            return
        self._target_yaw(mask, msg.yaw, msg.yaw_rate, relative=False)

    def _fly_velocity(self, vn: float, ve: float, vd: float) -> None:
        self.vel_target = (_clamp(vn, -20, 20), _clamp(ve, -20, 20), _clamp(vd, -5, 5))
        self.vel_time = self.t
        self.guided = "velocity"
        self.hold_point = None

    def _go_to(self, north: float, east: float, down: float) -> None:
        self.pos_target = (_clamp(north, -1e5, 1e5), _clamp(east, -1e5, 1e5), _clamp(down, -1000.0, 0.0))
        self.guided = "position"
        self.hold_point = None

    def _target_yaw(self, mask: int, yaw: float, yaw_rate: float, relative: bool) -> None:
        self.yaw_cmds_enabled = True
        if not (mask & YAW_IGNORE):
            target = yaw + (self.yaw if relative else 0.0)
            self.yaw_mode = "fixed"
            self.yaw_remaining = wrap_pi(target - self.yaw)
            self.yaw_slew = AUTO_YAW_SLEW
        elif not (mask & YAW_RATE_IGNORE):
            self.yaw_mode = "rate"
            self.yaw_rate_cmd = _clamp(yaw_rate, -3.5, 3.5)
        else:
            self.yaw_mode = "look_ahead"

    def _on_set_mode(self, msg) -> None:
        self._set_mode_common(msg.base_mode, msg.custom_mode)

    def _on_manual_control(self, msg) -> None:
        if msg.target not in (0, self.config.system_id) or msg.get_srcSystem() != int(self.params["SYSID_MYGCS"]):
            return
        self.manual = (_clamp(msg.x / 1000.0, -1, 1), _clamp(msg.y / 1000.0, -1, 1),
                       _clamp(msg.z / 1000.0, 0, 1), _clamp(msg.r / 1000.0, -1, 1), self.t)

    # -- parameters, missions, misc -----------------------------------------------------------------
    def _param_value(self, name: str):
        value = self.params[name]
        ptype = DEFAULT_PARAMS[name][1]
        return self.factory.param_value_encode(name.encode(), float(value), ptype, len(self.param_names),
                                               self.param_names.index(name))

    def _on_param_request_list(self, msg) -> None:
        self._text(mavlink.MAV_SEVERITY_INFO, "ArduCopter V4.5.7 (2a3dc4b7)")
        self._text(mavlink.MAV_SEVERITY_INFO, "Frame: QUAD/X")
        for name in self.param_names:
            self.emit(self._param_value(name))

    def _on_param_request_read(self, msg) -> None:
        name = msg.param_id
        if msg.param_index >= 0:
            if msg.param_index >= len(self.param_names):
                return
            name = self.param_names[msg.param_index]
        if name in self.params:
            self.emit(self._param_value(name))

    def _on_param_set(self, msg) -> None:
        name = msg.param_id
        if name not in self.params or not _finite(msg.param_value):
            return
        ptype = DEFAULT_PARAMS[name][1]
        value = float(msg.param_value) if ptype == mavlink.MAV_PARAM_TYPE_REAL32 else int(round(msg.param_value))
        self.params[name] = value
        self.emit(self._param_value(name))

    def _on_mission_request_list(self, msg) -> None:
        self.emit(self.factory.mission_count_encode(msg.get_srcSystem(), msg.get_srcComponent(), 0,
                                                    getattr(msg, "mission_type", 0)))

    def _on_mission_clear_all(self, msg) -> None:
        self.emit(self.factory.mission_ack_encode(msg.get_srcSystem(), msg.get_srcComponent(),
                                                  mavlink.MAV_MISSION_ACCEPTED, getattr(msg, "mission_type", 0)))

    def _on_mission_count(self, msg) -> None:
        result = mavlink.MAV_MISSION_ACCEPTED if msg.count == 0 else mavlink.MAV_MISSION_UNSUPPORTED
        self.emit(self.factory.mission_ack_encode(msg.get_srcSystem(), msg.get_srcComponent(), result,
                                                  getattr(msg, "mission_type", 0)))

    def _on_autopilot_version_request(self, msg) -> None:
        self._send_now("AUTOPILOT_VERSION")

    def _on_timesync(self, msg) -> None:
        if msg.tc1 == 0:
            self.emit(self.factory.timesync_encode(int(self.t * 1e9), msg.ts1))

    # -- outgoing ----------------------------------------------------------------------------------
    def _text(self, severity: int, text: str) -> None:
        log.info("STATUSTEXT %s", text)
        self.emit(self.factory.statustext_encode(severity, text.encode()[:50]))

    def _send_now(self, name: str) -> None:
        if name == "HOME_POSITION" and not self.home_set:
            return
        msg = getattr(self, "_msg_" + name.lower())()
        if msg is not None:
            self.emit(msg)

    def _send_due(self) -> None:
        if self.t >= self.next_heartbeat:
            self.next_heartbeat = max(self.next_heartbeat + self.heartbeat_interval, self.t)
            if self.faults.heartbeats:
                self.emit(self._msg_heartbeat())
        for name, entry in list(self.intervals.items()):
            interval, due = entry
            if self.t + 1e-9 >= due:
                due += interval
                entry[1] = due if due > self.t else self.t + interval
                self._send_now(name)

    # -- ground truth ------------------------------------------------------------------------------
    def truth(self) -> SimTruth:
        return SimTruth(
            time=self.t, armed=self.armed, mode=self.mode_name, custom_mode=self.mode,
            landed_state=self.landed_state(), north=self.n, east=self.e, down=self.d,
            vn=self.vn, ve=self.ve, vd=self.vd, roll=self.roll, pitch=self.pitch, yaw=self.yaw,
            yaw_rate=self.yaw_rate, battery_voltage=self.voltage, battery_remaining=self.remaining,
            ready=self.ready, last_command=self.last_command)
