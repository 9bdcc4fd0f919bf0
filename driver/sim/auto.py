"""AUTO: the simulated ArduCopter flies its mission, as tests/data/recordings/arducopter-4.6-sitl-mission shows.

Mixed into :class:`~driver.sim.autopilot.Autopilot`, next to :mod:`.missions` (which keeps the items).

* Entering AUTO starts the mission, or resumes it (disarmed too, as ModeAuto::run does; it then stays on the ground): the current item is flown again from its start
  ("Mission: 2 WP" once more). Leaving AUTO (BRAKE: a pause) stops it; MISSION_CURRENT then says 2.
* Each navigation item starts with "Mission: N NAME" and MISSION_CURRENT; it ends with MISSION_ITEM_REACHED
  (and "Reached command #N" for waypoints and loiters, after their hold time). DO_ items between two
  navigation items run when the first is done; DO_JUMP jumps (param2 times; -1 for ever).
* MISSION_SET_CURRENT (message) and DO_SET_MISSION_CURRENT (command; 4.x only) jump at once.
* The RTL item climbs, returns, lands and disarms; the mission is then complete (mission_state 5) and the
  vehicle stays in AUTO. A LAND item is never reached: the vehicle disarms on the ground first, which resets the
  mission, and AUTO starts it again from item 1, disarmed ("Mission: 1 Takeoff", MISSION_CURRENT active). Armed on the ground, AUTO needs a mission that starts with a takeoff
  ("Auto: Missing Takeoff Cmd"); disarmed in AUTO with no mission, "PreArm: Mode requires mission" (4.x).

Speed is WPNAV_SPEED (``wp_speed``, the same accessor GUIDED flies with; DO_CHANGE_SPEED overrides it).
"""
from __future__ import annotations

import logging
import math

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .common import MODES
from .flight import LAND_DISARM_DELAY
from .missions import MISSION, StoredItem, is_nav

__all__ = ["Auto", "COMMAND_NAMES"]

log = logging.getLogger("driver.sim.autopilot")

AUTO = MODES["AUTO"]
ALT_REACHED = 0.3            # m from the target altitude
JERK = 1.0                   # m/s³: WPNAV_JERK's default; 4.x's S-curves build acceleration up this slowly
MAX_JUMPS = 100              # DO_JUMPs followed in one walk (a jump loop without a navigation item)
# AP_Mission::Mission_Command::type(): what "Mission: N NAME" says.
COMMAND_NAMES = {
    16: "WP", 17: "LoitUnlim", 18: "LoitTurns", 19: "LoitTime", 20: "RTL", 21: "Land", 22: "Takeoff",
    30: "ContinueAndChangeAlt", 31: "LoitAltitude", 82: "SplineWP", 92: "GuidedEnable", 93: "Delay",
    112: "CondDelay", 113: "CondChangeAlt", 114: "CondDist", 115: "CondYaw", 177: "Jump", 178: "ChangeSpeed",
    179: "SetHome", 181: "SetRelay", 182: "RepeatRelay", 183: "SetServo", 184: "RepeatServo", 189: "LandStart",
    195: "ROILocation", 201: "ROI", 202: "DigiCamCfg", 203: "DigiCamCtrl", 205: "MountControl",
    206: "SetCamTrigDst", 211: "Gripper",
}
_HOLDING = {mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_CMD_NAV_SPLINE_WAYPOINT, mavlink.MAV_CMD_NAV_LOITER_TIME,
            mavlink.MAV_CMD_NAV_LOITER_TURNS}
_LANDING = {mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH, mavlink.MAV_CMD_NAV_LAND}


class Auto:
    """Mission execution; the vehicle's state belongs to the Autopilot."""

    def _auto_init(self) -> None:
        self.mission_current = 0           # the item flown (vehicle numbering), 0: none
        self.mission_run = "stopped"       # stopped | running | complete (AP_Mission's state)
        self.auto_stage = "idle"           # fly | hold | land | done
        self.auto_target: tuple[float, float, float] | None = None
        self.auto_hold_until = 0.0
        self.auto_accel = 0.0              # m/s²: the acceleration allowed now, ramped up at JERK
        self.jumps_done: dict[int, int] = {}

    # -- what MISSION_CURRENT says -------------------------------------------------------------------
    def mission_total(self) -> int:
        return max(len(self.plans[MISSION]) - 1, 0)

    def mission_running(self) -> bool:
        return self.mission_run == "running"

    def _msg_mission_current(self):
        total = self.mission_total()
        state = (mavlink.MISSION_STATE_NO_MISSION if total == 0 else
                 mavlink.MISSION_STATE_ACTIVE if self.mission_run == "running" else
                 mavlink.MISSION_STATE_COMPLETE if self.mission_run == "complete" else
                 mavlink.MISSION_STATE_NOT_STARTED)
        seq = 0 if self.mission_run == "complete" else self.mission_current
        return self.factory.mission_current_encode(seq, total, state, 1 if self.mode == AUTO else 0)

    def _mission_changed(self) -> None:
        """After an upload, a clear or a timeout: the current item may be gone."""
        if self.mission_current > self.mission_total():
            self.mission_current = 0
            if self.mission_run == "running":
                self._auto_finish()
        self._send_now("MISSION_CURRENT")

    # -- entering and leaving AUTO (from set_mode) --------------------------------------------------------
    def _auto_refusal(self) -> str | None:
        """ModeAuto::init: why AUTO cannot be entered now (armed only; disarmed any mode may be set)."""
        if not self.armed:
            return None
        failed = "Mode change to AUTO failed: init failed" if self.profile.mavlink2 else ""
        if self.mission_total() == 0:
            return failed
        first = self._next_nav(1)
        if self.landed and (first is None or self.plans[MISSION][first].command != mavlink.MAV_CMD_NAV_TAKEOFF):
            return "Auto: Missing Takeoff Cmd"
        return None

    def _auto_entered(self) -> None:
        """Start or resume (AP_Mission::start_or_resume with MIS_RESTART 0), disarmed too: ModeAuto::run starts
        the mission once there is an origin, armed or not (4.6.3 SITL: disarmed in AUTO, "Mission: 1 Takeoff"
        and MISSION_CURRENT active); a disarmed vehicle just stays on the ground."""
        if self.mission_total() == 0:
            return
        if self.mission_run == "complete" or self.mission_current == 0:
            self.jumps_done = {}
            self._auto_walk(1)
        else:
            self._auto_start_item(self.mission_current)

    def _auto_left(self) -> None:
        """AUTO left (BRAKE pauses): stopped, the current item kept; MISSION_CURRENT tells at its next turn."""
        if self.mission_run == "running":
            self.mission_run = "stopped"
            self.auto_stage = "idle"

    # -- jumps ------------------------------------------------------------------------------------------
    def set_mission_current(self, seq: int) -> bool:
        """AP_Mission::set_current_cmd: ``seq`` becomes current; flown at once while the mission runs."""
        if not 1 <= seq <= self.mission_total():
            return False
        if self.mission_run == "running":
            self._auto_walk(seq)
        else:
            self.mission_current = seq
            if self.mission_run == "complete":
                self.mission_run = "stopped"
            self._send_now("MISSION_CURRENT")
        return True

    def _on_mission_set_current(self, msg) -> None:
        self.set_mission_current(int(msg.seq))

    def _cmd_do_set_mission_current(self, p1, *_):
        if not self.profile.mavlink2:
            return mavlink.MAV_RESULT_UNSUPPORTED, None        # 3.3's COMMAND_LONG switch has no such case
        seq = int(p1)
        if not 1 <= seq <= self.mission_total():
            return mavlink.MAV_RESULT_DENIED, None
        return mavlink.MAV_RESULT_ACCEPTED, lambda: self.set_mission_current(seq)

    def _cmd_mission_start(self, *_):
        """GCS_MAVLINK_Copter::handle_MAV_CMD_MISSION_START: AUTO, auto_armed (the takeoff item may lift off with
        the throttle at zero), and the mission started unless it already runs."""
        if not self.set_mode(AUTO):
            return mavlink.MAV_RESULT_FAILED, None
        self.auto_armed = self.armed
        if self.mission_run != "running":
            self._auto_entered()
        else:
            self._auto_liftoff()
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _auto_liftoff(self) -> None:
        """The takeoff item flies once armed *and* auto-armed (ModeAuto::takeoff_run: auto_takeoff.run() holds
        the motors at ground idle otherwise): AUTO entered armed with the throttle at zero waits on the ground
        for MISSION_START."""
        item = self.plans[MISSION][self.mission_current] if self.mission_current else None
        if (item is not None and item.command == mavlink.MAV_CMD_NAV_TAKEOFF and self.armed and self.auto_armed
                and self.landed and self.liftoff_at is None):
            self.liftoff_at = max(self.armed_at + self.profile.arming_delay, self.t) + self.profile.liftoff_after
            self.touchdown_at = None

    # -- walking the items --------------------------------------------------------------------------------
    def _next_nav(self, seq: int) -> int | None:
        plan = self.plans[MISSION]
        while seq < len(plan):
            if is_nav(plan[seq].command):
                return seq
            seq += 1
        return None

    def _auto_walk(self, seq: int) -> None:
        """Run DO_ items from ``seq`` (jumps followed) up to the next navigation item, and start that."""
        plan = self.plans[MISSION]
        for _ in range(MAX_JUMPS + len(plan)):
            if seq >= len(plan) or seq < 1:
                self._auto_finish()
                return
            item = plan[seq]
            if item.command == mavlink.MAV_CMD_DO_JUMP:
                repeat, done = int(item.params[1]), self.jumps_done.get(seq, 0)
                if repeat < 0 or done < repeat:
                    self.jumps_done[seq] = done + 1
                    seq = int(item.params[0])
                else:
                    seq += 1
                continue
            if is_nav(item.command):
                self._auto_start_item(seq)
                return
            self._text(mavlink.MAV_SEVERITY_INFO, f"Mission: {seq} {COMMAND_NAMES.get(item.command, '?')}")
            self._auto_do(item)
            seq += 1
        self._auto_finish()

    def _auto_do(self, item: StoredItem) -> None:
        if item.command == mavlink.MAV_CMD_DO_CHANGE_SPEED:
            self._cmd_do_change_speed(*item.params)           # commands.py: the same checks as the command
        elif item.command == mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST:   # AP_Mission::start_command_camera
            self.set_trigger_distance(item.params[0], now=int(item.params[2]) == 1)

    def _auto_start_item(self, seq: int) -> None:
        item = self.plans[MISSION][seq]
        self.mission_current = seq
        self.mission_run = "running"
        self.auto_hold_until = 0.0
        self.auto_accel = 0.0
        self.auto_stage = "fly"
        self.hold_point = None
        self.rtl_phase = None
        here = (self.n, self.e)
        place = self.ned_of(item) or here
        if item.command == mavlink.MAV_CMD_NAV_TAKEOFF:
            self.auto_target = (here[0], here[1], -max(item.z, 1.0))
            self._auto_liftoff()
        elif item.command == mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            self.auto_target = None
            self.rtl_phase = "climb"
        elif item.command == mavlink.MAV_CMD_NAV_LAND:
            self.auto_target = (place[0], place[1], self.d)
        else:
            down = self.down_of(item) if item.z or item.frame == mavlink.MAV_FRAME_GLOBAL else self.d
            self.auto_target = (place[0], place[1], down)
        self.yaw_mode = "look_ahead"
        self._send_now("MISSION_CURRENT")
        self._text(mavlink.MAV_SEVERITY_INFO, f"Mission: {seq} {COMMAND_NAMES.get(item.command, '?')}")
        log.info("AUTO: item %d %s", seq, COMMAND_NAMES.get(item.command, item.command))

    def _auto_disarmed(self) -> None:
        """AP_Arming_Copter::disarm resets the mission (AP_Mission::reset), and ModeAuto::run, still in AUTO,
        starts a running one again from item 1, disarmed: after a mission that ends with a LAND item, 4.6.3 SITL says
        "Disarming motors", "Mission: 1 Takeoff" and MISSION_CURRENT seq 1 active."""
        if self.mode == AUTO and self.mission_run == "running":
            self.jumps_done = {}
            self._auto_walk(1)

    def _auto_finish(self) -> None:
        self.mission_run = "complete"
        self.auto_stage = "done"
        self.mission_current = 0
        self.hold_point = None
        self._send_now("MISSION_CURRENT")

    def _auto_reached(self, text: bool) -> None:
        seq = self.mission_current
        self.emit(self.factory.mission_item_reached_encode(seq))
        if text:
            self._text(mavlink.MAV_SEVERITY_INFO, f"Reached command #{seq}")
        self._auto_walk(seq + 1)

    # -- flying (the controller asks _auto, the step asks _auto_step) ----------------------------------------
    def _auto_climbing(self) -> bool:
        """Armed on the ground in AUTO with a takeoff item to fly: the controller may lift off."""
        return (self.armed and self.auto_armed and self.mode == AUTO and self.mission_run == "running"
                and self.auto_stage == "fly"
                and self.plans[MISSION][self.mission_current].command == mavlink.MAV_CMD_NAV_TAKEOFF)

    def _auto_acceleration(self) -> float:
        """The horizontal acceleration AUTO may use this step: ramped up at JERK to WPNAV_ACCEL (S-curves)."""
        accel = max(0.5, float(self.params.get("WPNAV_ACCEL", 250.0)) / 100.0)     # cm/s², as CIRCLE reads it
        self.auto_accel = min(accel, self.auto_accel + JERK / float(self.config.rate_hz))
        return self.auto_accel

    def _auto(self) -> tuple[float, float, float]:
        if self.mission_run != "running" or self.auto_stage in ("idle", "done"):
            return self._hold()
        item = self.plans[MISSION][self.mission_current]
        if item.command == mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH or self.auto_stage == "land":
            return self._rtl()
        if self.auto_stage == "hold" or self.auto_target is None:
            return self._hold()
        speed_up = 1.5 if item.command == mavlink.MAV_CMD_NAV_TAKEOFF else self._speed_up()
        return self._pos_ctrl(self.auto_target, self.wp_speed(), speed_up, self._speed_dn())

    def _auto_step(self) -> None:
        """Judge the current item: reached, held long enough, landed."""
        if self.mode == AUTO and not self.armed and self.mission_total() == 0 and self.profile.mavlink2 \
                and self.boot_seconds >= self.next_prearm_report:
            self.next_prearm_report = self.boot_seconds + 30.0     # ArduCopter's pre-arm report, every 30 s
            self._text(mavlink.MAV_SEVERITY_CRITICAL, "PreArm: Mode requires mission")
        if self.mode != AUTO or self.mission_run != "running":
            return
        item = self.plans[MISSION][self.mission_current]
        command = item.command
        if command in _LANDING:
            if self.auto_stage == "fly" and command == mavlink.MAV_CMD_NAV_LAND and self._at_target(vertical=False):
                self.auto_stage, self.rtl_phase, self.hold_point = "land", "land", None
            # RTL's verify sees it landed before the disarm: reached, and the mission complete; a LAND item is
            # never reached: the disarm comes first (_timers), and resets the mission (_auto_disarmed)
            if command == mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH and self.armed and self.landed \
                    and self.touchdown_at is not None and self.t - self.touchdown_at >= LAND_DISARM_DELAY - 1e-9:
                self.emit(self.factory.mission_item_reached_encode(self.mission_current))
                self._auto_finish()              # _timers disarms next: "Disarming motors"
            return
        if not self.armed:
            return
        if self.auto_stage == "fly":
            if command == mavlink.MAV_CMD_NAV_TAKEOFF:
                if not self.landed and -self.d >= -self.auto_target[2] - ALT_REACHED:
                    self.hold_point = None
                    self._auto_reached(text=False)
                return
            if not self._at_target(vertical=True):
                return
            if command not in _HOLDING:
                if command != mavlink.MAV_CMD_NAV_LOITER_UNLIM:
                    self._auto_reached(text=False)
                return
            self.auto_stage = "hold"
            self.hold_point = self.auto_target
            hold = item.params[0] if command != mavlink.MAV_CMD_NAV_LOITER_TURNS else 0.0
            self.auto_hold_until = self.t + max(float(hold), 0.0)
        if self.auto_stage == "hold" and self.t >= self.auto_hold_until:
            self._auto_reached(text=True)

    def _at_target(self, vertical: bool) -> bool:
        target = self.auto_target
        if target is None:
            return True
        radius = max(0.05, float(self.params.get("WPNAV_RADIUS", 200.0)) / 100.0)    # cm; ArduPilot's minimum 5
        close = math.hypot(target[0] - self.n, target[1] - self.e) <= radius
        return close and (not vertical or abs(target[2] - self.d) <= 1.0)
