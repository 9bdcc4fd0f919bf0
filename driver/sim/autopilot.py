"""ArduCopter as seen over MAVLink, without sockets: start-up, arming, modes, streams.

:class:`Autopilot` is stepped by a clock (``step(dt)``), fed decoded MAVLink
messages (``handle(msg, version)``) and hands every message it sends to
``emit``. Its parts are mixins: telemetry.py builds the messages, commands.py
answers MAV_CMDs, messages.py handles the rest, flight.py flies. All timers run on
its own sim time, so a test may step it as fast as it likes.

The behaviour follows the firmware profile (profiles.py): ``copter-4`` was matched
to a real ArduCopter 4.7 recording, ``solo`` to 3DR's Solo sources. Positions are
kept NED from HOME (``SimTruth``); the EKF origin, which LOCAL_POSITION_NED and
MAV_FRAME_LOCAL_NED targets use, is ``SimConfig.origin_offset`` away from home (the
origin is where the vehicle was at GPS lock, home where it armed).
"""
from __future__ import annotations

import logging
import math
import random
from dataclasses import dataclass
from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .auto import Auto
from .commands import Commands
from .circle import CircleNav
from ..core.frames import offset_ned
from .common import (DEFAULT_PARAMS, MODE_NAMES, MODES, NOT_ARMABLE, POSITION_MODES, STREAMS, command_name,
                     wrap_pi)
from .faults import Faults
from .flight import LAND_DISARM_DELAY, Flight
from .follow import FollowMode
from .gimbal import Payload
from .messages import Messages
from .failsafe import GcsFailsafe
from .ftp import FtpServer
from .logs import LogServer
from .params import ParamProtocol, SimParams
from .missions import Missions
from .motors import FRAME_CLASSES, FRAME_TYPES
from .profiles import POSITION_REASONS, profile_of
from .setup import Setup
from .telemetry import EARTH_RADIUS, GRAVITY, METRES_PER_DEG, Telemetry

log = logging.getLogger(__name__)

__all__ = ["Autopilot", "SimTruth", "MODES", "MODE_NAMES", "EARTH_RADIUS", "DEFAULT_PARAMS", "STREAMS",
           "wrap_pi", "command_name"]

REBOOT_SILENCE = 1.5     # s without a word while "rebooting"
PREARM_REPORT = 30.0     # s: ArduCopter repeats the failing pre-arm check this often while disarmed


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
    mount_pitch: float = 0.0         # degrees, the gimbal's pitch as it is (0 level, -90 down)
    follow_target: tuple | None = None   # FOLLOW: (north, east, up) of the lead as AP_Follow last heard it

    @property
    def altitude(self) -> float:
        return -self.down

    @property
    def heading_deg(self) -> float:
        return math.degrees(self.yaw) % 360.0

    @property
    def ground_speed(self) -> float:
        return math.hypot(self.vn, self.ve)


class Autopilot(Setup, Telemetry, Commands, ParamProtocol, FtpServer, LogServer, GcsFailsafe, Missions, Auto, Messages,
                Flight, FollowMode,
                Payload):
    """One ArduCopter: state, flight modes, command handling and telemetry streams."""

    def __init__(self, config, faults: Faults | None = None,
                 emit: Callable[[object], None] | None = None,
                 emit_to: Callable[[object, object], None] | None = None) -> None:
        """``emit(msg)`` sends on every link; ``emit_to(msg, link)`` only on ``link`` (default: every link)."""
        self.config = config
        self.profile = profile_of(config)
        self.faults = faults if faults is not None else Faults()
        self.emit = emit or (lambda msg: None)
        self.emit_to = emit_to or (lambda msg, link: self.emit(msg))
        self.sender = None               # the link of the message being handled (ArduPilot: its GCS_MAVLINK)
        self.signing = None              # the vehicle's Signing (signing.py); None: SETUP_SIGNING is not handled
        self.rng = random.Random(config.seed)
        self.factory = mavlink.MAVLink(None, srcSystem=config.system_id, srcComponent=config.component_id)
        lat, lon, alt, heading = config.home
        self.home_lat, self.home_lon, self.home_alt = float(lat), float(lon), float(alt)
        self.m_per_deg_lon = METRES_PER_DEG * math.cos(math.radians(self.home_lat))
        self.origin = tuple(float(v) for v in getattr(config, "origin_offset", (0.0, 0.0, 0.0)))
        self.params = SimParams(DEFAULT_PARAMS)          # ArduCopter 4.6.3's table, the sim's values over it
        self.params["SYSID_THISMAV"] = config.system_id
        self.params["BATT_CAPACITY"] = config.battery_capacity_mah
        self.params["DISARM_DELAY"] = config.auto_disarm_after
        self.params["FENCE_TYPE"] = self.profile.fence_types
        self.t = 0.0
        # vehicle state
        self.n = self.e = self.d = 0.0
        self.vn = self.ve = self.vd = 0.0
        self.roll = self.pitch = 0.0
        self.yaw = wrap_pi(math.radians(float(heading)))
        self.roll_rate = self.pitch_rate = self.yaw_rate = 0.0
        self.acc_body = (0.0, 0.0, -GRAVITY)
        self._tau = 0.3
        self.consumed_mah = 0.0
        self.current = 0.5
        self.voltage = self._ocv(1.0) * config.battery_cells
        self.last_command = ""
        # message scheduling: name → [interval s, next due]
        self.intervals: dict[str, list[float]] = {}
        self.heartbeat_interval = 1.0
        self.next_heartbeat = 0.0
        self.manual = None               # (x, y, z, r, time) from MANUAL_CONTROL
        self.safety_on = False
        self.chute_released = False
        self.speed_override = None       # DO_CHANGE_SPEED, m/s
        self.circle: CircleNav | None = None    # CIRCLE's path, made as the mode is entered
        self.param_links: dict = {}     # link → _LinkParams: what it still has to hear of the parameters (params.py)
        self.rebooting_until: float | None = None
        self.deferred_texts: list | None = None   # STATUSTEXT held until a command's ACK is out
        self.mode_changed = False
        self._payload_init()             # the mount and camera (gimbal.py)
        self._missions_init()             # missions.py: the plans outlive a reboot
        self._auto_init()                 # auto.py
        self._setup_init()                # setup.py: calibrations, motor test, radio, traffic
        self._follow_init()               # follow.py: the lead AP_Follow hears
        self._boot()

    # -- lifecycle -------------------------------------------------------------------------------
    def _boot(self) -> None:
        """Power-on (and reboot) state: disarmed on the ground, coming up stage by stage (profiles.py)."""
        self.boot_time = self.t
        self.frame_at_boot = (int(self.params["FRAME_CLASS"]), int(self.params["FRAME_TYPE"]))   # AP_Motors reads it once
        self.stage_index = -1
        self.stage = self.profile.boot[0]
        self.ready = False
        self.home_set = False
        self.next_prearm_report = PREARM_REPORT
        self.armed = False
        self.auto_armed = False           # ap.auto_armed: AUTO may lift off (MISSION_START or a GUIDED takeoff set it)
        self.mode = MODES["STABILIZE"]
        self.landed = True
        self.d = 0.0
        self.vn = self.ve = self.vd = 0.0
        self.armed_at = None
        self.liftoff_at = None
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
        self.yaw_target = 0.0             # angle_rate: the heading AutoYaw moves on with the rate
        self.posvel_time = 0.0            # posvel: when the target was last moved on
        self.yaw_slew = math.radians(60.0)
        self.yaw_cmds_enabled = True
        self.rtl_phase = None
        self.rtl_alt = 0.0
        self.rtl_loiter_until = 0.0
        self.fence_breaches = 0           # AC_FENCE_TYPE bits breached now
        self.fence_breach_count = 0
        self.fence_breach_time = 0        # time_boot_ms of the last new breach
        self.chute_released = False

    def reboot(self) -> None:
        self.rebooting_until = self.t + REBOOT_SILENCE
        self.armed = False

    def _banner(self, asked: bool = False) -> None:
        """GCS_MAVLINK_Copter::send_banner (4.x), the PARAM_REQUEST_LIST / DO_SEND_BANNER texts of 3.3: the
        firmware, the OS, the board's id line (3.3: only when ``asked``), the frame it booted with."""
        p = self.profile
        lines = [f"{p.banner} ({p.git_hash})", p.banner_os, p.banner_id if asked or p.banner_id_on_list else "",
                 f"Frame: {self._frame_string()}"]
        for line in lines:
            if line:
                self._text(mavlink.MAV_SEVERITY_INFO, line)

    def _frame_string(self) -> str:
        """AP_Motors::get_frame_and_type_string of the frame read at boot ("QUAD/X"); 3.3's FRAME_CONFIG_STRING
        ("QUAD") was fixed at build time."""
        frame_class, frame_type = self.frame_at_boot
        name = FRAME_CLASSES.get(frame_class, str(frame_class))
        return name if self.profile.version[0] < 4 else f"{name}/{FRAME_TYPES.get(frame_type, frame_type)}"

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
            self._banner()
        self._readiness()
        self._missions_step()
        self._auto_step()
        self._timers()
        self._physics(dt)
        self._fence_check()
        self._battery(dt)
        self._payload_step(dt)
        self._setup_step(dt)
        self._send_due()
        self.params_step(dt)
        self.logs_step(dt)
        self.failsafe_step()

    @property
    def boot_seconds(self) -> float:
        return self.t - self.boot_time

    def time_boot_ms(self) -> int:
        return int(self.boot_seconds * 1000) & 0xFFFFFFFF

    @property
    def initialised(self) -> bool:
        return self.stage.initialised

    def _readiness(self) -> None:
        """Walk the start-up stages whose time has come: their texts, home and origin, readiness."""
        boot = self.profile.boot
        ready_after = self.config.ready_after
        while self.stage_index + 1 < len(boot) and self.boot_seconds >= boot[self.stage_index + 1].at(ready_after):
            self.stage_index += 1
            self.stage = stage = boot[self.stage_index]
            for text in stage.texts:
                self._text(mavlink.MAV_SEVERITY_INFO, text.format(elevation=round(self.home_alt - self.origin[2])))
            if stage.origin and not self.home_set:
                self.home_set = True          # ArduCopter sets home with the EKF origin, and again at arming
                if self.profile.home_pushed:
                    self._send_home()
            if stage.ready and not self.ready:
                self.ready = True
                log.info("ready to arm")
        if not self.ready and not self.armed and self.boot_seconds >= self.next_prearm_report:
            self.next_prearm_report = self.boot_seconds + PREARM_REPORT
            reasons = self._prearm_failure()
            if reasons and self.params["ARMING_CHECK"]:
                self._text(self.profile.arm_severity, "PreArm: " + reasons[0].split(": ", 1)[-1])

    def _timers(self) -> None:
        """Disarm on the ground: soon after a landing, DISARM_DELAY after arming without takeoff."""
        if not self.armed or not self.landed:
            return
        if self.liftoff_at is not None or self.touchdown_at is None:
            self.touchdown_at = self.t        # a takeoff spooling up is no idle vehicle
            return
        on_ground = self.t - self.touchdown_at
        text = "Disarming motors" if self.profile.arm_texts else None
        if self.mode == MODES["LAND"] or self.rtl_phase == "land":
            if on_ground >= LAND_DISARM_DELAY:
                self._disarm(text)
            return
        delay = float(self.params["DISARM_DELAY"])
        if delay > 0 and on_ground >= delay:
            self._disarm(text)

    # -- arming ----------------------------------------------------------------------------------
    def _prearm_failure(self) -> list[str]:
        """Why arming is refused now (all the reasons, as ArduCopter lists them), or []."""
        if self.faults.refuse_arm:
            return [f"PreArm: {self.faults.refuse_arm}"]
        if self.safety_on:
            return ["PreArm: Hardware safety switch"]
        if self.calibration_arm_reasons():
            return self.calibration_arm_reasons()
        if self.ready or not self.params["ARMING_CHECK"]:
            return []
        reasons = list(self.stage.arm_reasons)
        if self.mode not in POSITION_MODES:
            reasons = [r for r in reasons if r not in POSITION_REASONS]
        return reasons

    def _arm(self, force: bool) -> tuple[int, list[str]]:
        if self.armed:
            return mavlink.MAV_RESULT_ACCEPTED, []
        if not force:
            reasons = self._prearm_failure()
            if reasons:
                return mavlink.MAV_RESULT_FAILED, reasons
            if self.mode in NOT_ARMABLE:
                return mavlink.MAV_RESULT_FAILED, ["Arm: Mode not armable"]
        self.armed = True
        self.armed_at = self.t
        self.liftoff_at = None
        self.landed = self.d >= -0.05
        self.touchdown_at = self.t if self.landed else None
        self.hold_point = None
        self.guided = "hold"
        log.info("armed in %s", MODE_NAMES.get(self.mode, self.mode))
        return mavlink.MAV_RESULT_ACCEPTED, []

    def _announce_arming(self) -> None:
        """After the ACK (recording, 41.45 s): GPS_GLOBAL_ORIGIN, HOME_POSITION (home set again), "Arming motors"."""
        if self.profile.home_pushed:
            self._send_home()
        if self.profile.arm_texts:
            self._text(mavlink.MAV_SEVERITY_INFO, "Arming motors")

    def _disarm(self, text: str | None = None) -> None:
        if not self.armed:
            return
        self.armed = False
        self.auto_armed = False           # Copter::update_auto_armed: disarmed, never auto-armed
        self.armed_at = None
        self.liftoff_at = None
        self.takeoff_alt = None
        self.rtl_phase = None if self.mode != MODES["RTL"] else self.rtl_phase
        if text:
            self._text(mavlink.MAV_SEVERITY_INFO, text)
        log.info("disarmed")
        self._auto_disarmed()

    # -- modes -------------------------------------------------------------------------------------
    def set_mode(self, number: int) -> bool:
        if number not in MODE_NAMES:
            self._text(mavlink.MAV_SEVERITY_WARNING, f"No such mode {number}")
            return False
        if number in POSITION_MODES and self.armed and not self.ready:
            self._text(mavlink.MAV_SEVERITY_WARNING, f"Mode change failed: {MODE_NAMES[number]} requires position")
            return False
        if number == self.mode:
            return True
        refusal = self._auto_refusal() if number == MODES["AUTO"] else None
        if refusal is not None:
            if refusal:
                self._text(mavlink.MAV_SEVERITY_WARNING, refusal)
            return False
        if number == MODES["FOLLOW"] and not self._follow_entered():
            return False
        if self.mode == MODES["AUTO"]:
            self._auto_left()
        if self.mode == MODES["FOLLOW"]:
            self._follow_left()
        self.mode = number
        self.mode_changed = True
        self.hold_point = None
        self.takeoff_alt = None
        self.liftoff_at = None
        self.rtl_phase = None
        if self.guided == "takeoff":
            self.guided = "hold"
        if number in (MODES["GUIDED"], MODES["FOLLOW"]):
            self.guided = "hold"
            self.yaw_cmds_enabled = True
            self.yaw_mode = "hold"
        elif number == MODES["RTL"]:
            self.rtl_phase = "land" if self.landed else "climb"
            self.yaw_mode = "hold"
        elif number == MODES["CIRCLE"]:
            self.circle = CircleNav.entering(self)       # centre CIRCLE_RADIUS ahead of the nose
            self.yaw_mode = "rate"
        else:
            self.yaw_mode = "hold"
        log.info("mode %s", MODE_NAMES[number])
        if number == MODES["AUTO"]:
            self._auto_entered()
        return True

    @property
    def mode_name(self) -> str:
        return MODE_NAMES.get(self.mode, str(self.mode))

    def landed_state(self) -> int:
        if self.landed or (not self.armed and self.d >= -0.05):
            return mavlink.MAV_LANDED_STATE_ON_GROUND
        if self.armed and self.mode == MODES["GUIDED"] and self.guided == "takeoff":
            return mavlink.MAV_LANDED_STATE_TAKEOFF
        if self.armed and (self.mode == MODES["LAND"] or (self.mode in (MODES["RTL"], MODES["AUTO"])
                                                                    and self.rtl_phase == "land")):
            return mavlink.MAV_LANDED_STATE_LANDING
        return mavlink.MAV_LANDED_STATE_IN_AIR

    def ned_from(self, lat: float, lon: float) -> tuple[float, float]:
        """North/east metres of (lat, lon) from home (across the antimeridian too); the sim's one conversion."""
        return offset_ned(self.home_lat, self.home_lon, lat, lon)

    # -- outgoing ----------------------------------------------------------------------------------
    def _text(self, severity: int, text: str) -> None:
        if self.deferred_texts is not None:
            self.deferred_texts.append((severity, text))
            return
        log.info("STATUSTEXT %s", text)
        self.log_text(text)
        self.emit(self.factory.statustext_encode(severity, text.encode()[:50]))

    def _send_now(self, name: str) -> None:
        if name == "HOME_POSITION" and not self.home_set:
            return
        msg = getattr(self, "_msg_" + name.lower())()
        if msg is not None:
            self.emit(msg)

    def _send_home(self) -> None:
        """HOME_POSITION, and on 4.x the EKF origin with it (GCS_MAVLINK: MSG_HOME, MSG_ORIGIN)."""
        if self.profile.home_pushed:
            self._send_now("GPS_GLOBAL_ORIGIN")
        self._send_now("HOME_POSITION")

    def _send_due(self) -> None:
        if self.t >= self.next_heartbeat:
            self.next_heartbeat = max(self.next_heartbeat + self.heartbeat_interval, self.t)
            if self.faults.heartbeats:
                self.emit(self._msg_heartbeat())
        streaming = self.initialised              # nothing is streamed before "ArduPilot Ready"
        for name, entry in list(self.intervals.items()):
            interval, due = entry
            if self.t + 1e-9 >= due:
                due += interval
                entry[1] = due if due > self.t else self.t + interval
                if streaming:
                    self._send_now(name)

    # -- ground truth ------------------------------------------------------------------------------
    def truth(self) -> SimTruth:
        return SimTruth(
            time=self.t, armed=self.armed, mode=self.mode_name, custom_mode=self.mode,
            landed_state=self.landed_state(), north=self.n, east=self.e, down=self.d,
            vn=self.vn, ve=self.ve, vd=self.vd, roll=self.roll, pitch=self.pitch, yaw=self.yaw,
            yaw_rate=self.yaw_rate, battery_voltage=self.voltage, battery_remaining=self.remaining,
            ready=self.ready, last_command=self.last_command, mount_pitch=self.mount_pitch,
            follow_target=self.follow_truth())
