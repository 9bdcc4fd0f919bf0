"""COMMAND_LONG / COMMAND_INT as ArduCopter answers them: one ``_cmd_<name>`` per MAV_CMD.

Mixed into :class:`~driver.sim.autopilot.Autopilot`. Each handler returns
(MAV_RESULT, callable to run after the COMMAND_ACK or None); what is not handled
here is UNSUPPORTED, as ArduPilot's default case. The answers follow the firmware
profile (profiles.py): 4.7's from the recording, the Solo's from 3DR's sources. The
COMMAND_ACK is addressed to whoever sent the command (target_system/component), as
ArduPilot's mavlink_msg_command_ack_send_buf does, so on a shared link every peer
sees it but only the sender takes it as its own.
"""
from __future__ import annotations

import logging
import math

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .common import FORCE_ARM_MAGIC, MODES, STREAM_PARAMS, STREAMS, command_name, finite, wrap_pi

__all__ = ["Commands"]

log = logging.getLogger("driver.sim.autopilot")

AUTO_YAW_SLEW = math.radians(60.0)
# MAV_CMDs a profile may lack (Profile.do_set_mode, Profile.message_commands).
SET_MODE_COMMANDS = {mavlink.MAV_CMD_DO_SET_MODE}
MESSAGE_COMMANDS = {mavlink.MAV_CMD_REQUEST_MESSAGE, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL,
                    mavlink.MAV_CMD_GET_MESSAGE_INTERVAL}


class Commands:
    """MAV_CMD handlers; the state they change belongs to the Autopilot."""

    def _on_command_long(self, msg) -> None:
        params = (msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6, msg.param7)
        self._command(msg, msg.command, params)

    def _on_command_int(self, msg) -> None:
        params = (msg.param1, msg.param2, msg.param3, msg.param4, float(msg.x), float(msg.y), msg.z)
        self._command(msg, msg.command, params)

    def _supports(self, command: int) -> bool:
        profile = self.profile
        if command in SET_MODE_COMMANDS:
            return profile.do_set_mode
        if command in MESSAGE_COMMANDS:
            return profile.message_commands
        return True

    def _command(self, msg, command: int, params) -> None:
        self.last_command = command_name(command)
        self._sender_ids = (msg.get_srcSystem(), msg.get_srcComponent())   # for an ACK sent later (setup.py)
        if self.faults.ignores(command):
            self.faults.ignored.append(command)
            log.info("ignoring %s (fault)", self.last_command)
            return
        handler = getattr(self, "_cmd_" + self.last_command.removeprefix("MAV_CMD_").lower(), None)
        # 4.x queues STATUSTEXT and sends the COMMAND_ACK at once: the reasons come after the ACK
        # (recording: ACK 400 FAILED at 13.581 s, then "Arm: Gyros inconsistent"). 3.3 sent text at once.
        self.deferred_texts = [] if self.profile.texts_after_ack else None
        try:
            if handler is None or not self._supports(command):
                result, follow = mavlink.MAV_RESULT_UNSUPPORTED, None
            else:
                try:
                    result, follow = handler(*params)
                except (ValueError, OverflowError, TypeError):
                    result, follow = mavlink.MAV_RESULT_DENIED, None
        finally:
            texts, self.deferred_texts = self.deferred_texts, None
        if result is None:
            pass                           # the handler answers later itself (calibration.py)
        elif self.faults.loses_reply(command):
            log.info("the COMMAND_ACK of %s is lost (fault)", self.last_command)
        else:
            self.emit(self.factory.command_ack_encode(command, result, 0, 0, msg.get_srcSystem(),
                                                      msg.get_srcComponent()))
        for severity, text in texts or ():
            self._text(severity, text)
        if follow is not None:
            follow()

    # -- arming, modes, takeoff ---------------------------------------------------------------------
    def _cmd_component_arm_disarm(self, p1, p2, *_):
        force = int(p2) == FORCE_ARM_MAGIC
        if p1 == 1:
            result, reasons = self._arm(force)
            for reason in reasons:
                self._text(self.profile.arm_severity, reason)
            return result, (self._announce_arming if result == mavlink.MAV_RESULT_ACCEPTED else None)
        if p1 == 0:
            if self.armed and not self.landed and not force:
                return self.profile.disarm_in_air_result, None
            self._disarm("Disarming motors" if self.profile.arm_texts else None)
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
        """Mode::do_user_takeoff: armed, GUIDED, still land_complete (else "can't takeoff again"), going up.

        land_complete lasts through the arming delay and the spool-up (Profile.arming_delay, liftoff_after),
        so on 4.x a retry in those seconds is ACCEPTED (recording: 2.05 s after the first) and restarts the
        same takeoff; once the vehicle has left the ground it is FAILED.
        """
        if self.mode != MODES["GUIDED"] or not self.armed or not self.landed or not finite(p7):
            return mavlink.MAV_RESULT_FAILED, None
        if p7 <= -self.d:                                   # "can't takeoff downwards"
            return mavlink.MAV_RESULT_FAILED, None
        altitude = min(float(p7), 1000.0)
        self.takeoff_alt = altitude
        self.guided = "takeoff"
        self.hold_point = (self.n, self.e, 0.0)
        self.yaw_cmds_enabled = False
        self.yaw_mode = "hold"
        self.touchdown_at = None
        self.auto_armed = True            # Copter::start_takeoff (mode_guided.cpp) sets it
        if self.liftoff_at is None:
            spinning = self.armed_at + self.profile.arming_delay
            self.liftoff_at = max(spinning, self.t) + self.profile.liftoff_after
        log.info("takeoff to %.1f m", altitude)
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_nav_land(self, *_):
        return (mavlink.MAV_RESULT_ACCEPTED if self.set_mode(MODES["LAND"]) else mavlink.MAV_RESULT_FAILED), None

    def _cmd_nav_return_to_launch(self, *_):
        return (mavlink.MAV_RESULT_ACCEPTED if self.set_mode(MODES["RTL"]) else mavlink.MAV_RESULT_FAILED), None

    def _cmd_condition_yaw(self, p1, p2, p3, p4, *_):
        if not (0.0 <= p1 <= 360.0) or p4 not in (0.0, 1.0) or not finite(p2, p3):
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
        if finite(p2) and p2 > 0:
            self.speed_override = min(float(p2), 20.0)
        return mavlink.MAV_RESULT_ACCEPTED, None

    # -- messages on request ----------------------------------------------------------------------
    def _cmd_set_message_interval(self, p1, p2, *_):
        msg_id = int(p1)
        cls = mavlink.mavlink_map.get(msg_id)
        if cls is None or (cls.msgname != "HEARTBEAT" and not self._can_send(cls.msgname)):
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
        if cls is None or not self._can_send(cls.msgname):
            return mavlink.MAV_RESULT_FAILED, None
        return mavlink.MAV_RESULT_ACCEPTED, lambda: self._send_now(cls.msgname)

    def _cmd_get_home_position(self, *_):
        """GCS_MAVLINK::handle_command_get_home_position: FAILED until home is set (recording, 2.03 s)."""
        if not self.home_set:
            return mavlink.MAV_RESULT_FAILED, None
        return mavlink.MAV_RESULT_ACCEPTED, self._send_home

    def _cmd_request_autopilot_capabilities(self, *_):
        return mavlink.MAV_RESULT_ACCEPTED, lambda: self._send_now("AUTOPILOT_VERSION")

    def _cmd_do_send_banner(self, *_):
        """GCS_MAVLINK::handle_command_long_packet: send_banner(), ACCEPTED (3.3: the same, with the board's id)."""
        self._banner(asked=True)
        return mavlink.MAV_RESULT_ACCEPTED, None

    # -- the rest ------------------------------------------------------------------------------------
    def _cmd_preflight_calibration(self, *_):
        if self.armed:       # recording, 44.50 s: FAILED, then "Disarm to allow calibration" (NOTICE)
            if self.profile.calibration_text:
                self._text(mavlink.MAV_SEVERITY_NOTICE, "Disarm to allow calibration")
            return mavlink.MAV_RESULT_FAILED, None
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
