"""Every other message a ground station sends the simulated ArduCopter: streams, modes, setpoints, parameters.

Mixed into :class:`~driver.sim.autopilot.Autopilot`: ``handle()`` routes a decoded
message to ``_on_<name>``. Setpoints follow the firmware profile: 4.x reads the
coordinate frame and yaw of SET_POSITION_TARGET_LOCAL_NED and takes MAV_FRAME_LOCAL_NED
positions from the EKF origin; the Solo (3.3) reads neither frame nor yaw and takes z
above home (profiles.py has the sources).
"""
from __future__ import annotations

import logging
import math

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .common import (MODES, POS_IGNORE, STREAM_PARAMS, STREAMS, VEL_IGNORE, YAW_IGNORE,
                     YAW_RATE_IGNORE, clamp as _clamp, finite, wrap_pi)

__all__ = ["Messages"]

log = logging.getLogger("driver.sim.autopilot")

AUTO_YAW_SLEW = math.radians(60.0)
ACC_IGNORE = 0b111000000
BODY_FRAMES = (mavlink.MAV_FRAME_BODY_NED, mavlink.MAV_FRAME_BODY_OFFSET_NED)
LOCAL_FRAMES = (mavlink.MAV_FRAME_LOCAL_NED, mavlink.MAV_FRAME_LOCAL_OFFSET_NED) + BODY_FRAMES


class Messages:
    """Handlers of incoming messages other than commands; the state belongs to the Autopilot."""

    def handle(self, msg, version: int = 2) -> None:
        """One decoded MAVLink message from a ground station."""
        if self.rebooting_until is not None:
            return
        kind = msg.get_type()
        if getattr(msg, "target_system", 0) not in (0, self.config.system_id):
            return
        if getattr(msg, "target_component", 0) not in (0, self.config.component_id) and not self._for_gimbal(msg):
            return
        handler = getattr(self, "_on_" + kind.lower(), None)
        if handler is not None:
            try:
                handler(msg)
            except Exception:  # a malformed field must never stop the vehicle
                log.exception("handling %s", kind)
        if self.mode_changed:
            self.mode_changed = False
            if self.profile.mode_heartbeat and self.faults.heartbeats:
                self.emit(self._msg_heartbeat())     # 4.7 announces a new mode at once (after the ACK)

    def _on_heartbeat(self, msg) -> None:
        pass

    # -- streams --------------------------------------------------------------------------------------
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

    # -- modes and sticks -----------------------------------------------------------------------------
    def _on_set_mode(self, msg) -> None:
        """The legacy message: no COMMAND_ACK, the HEARTBEAT shows the mode (recording, 65.79 s)."""
        self._set_mode_common(msg.base_mode, msg.custom_mode)

    def _on_manual_control(self, msg) -> None:
        if msg.target not in (0, self.config.system_id) or msg.get_srcSystem() != int(self.params["SYSID_MYGCS"]):
            return
        self.manual = (_clamp(msg.x / 1000.0, -1, 1), _clamp(msg.y / 1000.0, -1, 1),
                       _clamp(msg.z / 1000.0, 0, 1), _clamp(msg.r / 1000.0, -1, 1), self.t)

    # -- guided targets ---------------------------------------------------------------------------
    def _guided_accepts(self) -> bool:
        return self.mode == MODES["GUIDED"] and self.armed and not self.landed

    def _on_set_position_target_local_ned(self, msg) -> None:
        frame, mask = msg.coordinate_frame, msg.type_mask
        if not self._guided_accepts():
            return
        if not finite(msg.x, msg.y, msg.z, msg.vx, msg.vy, msg.vz, msg.yaw, msg.yaw_rate):
            log.warning("non-finite SET_POSITION_TARGET_LOCAL_NED ignored")
            return
        profile = self.profile
        if not profile.setpoint_frames:
            frame = mavlink.MAV_FRAME_LOCAL_NED          # 3.3 never reads coordinate_frame
            if mask & ACC_IGNORE != ACC_IGNORE:
                return                                   # 3.3: "result = MAV_RESULT_FAILED", nothing flies
        if frame not in LOCAL_FRAMES:
            return
        body = frame in BODY_FRAMES
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        use_pos = not (mask & POS_IGNORE)
        use_vel = not (mask & VEL_IGNORE)
        vx, vy, vz = msg.vx, msg.vy, msg.vz
        if body:
            vx, vy = c * vx - s * vy, s * vx + c * vy
        if use_pos:
            x, y, z = msg.x, msg.y, msg.z
            if body:
                x, y = c * x - s * y, s * x + c * y
            if frame == mavlink.MAV_FRAME_LOCAL_NED:     # from the EKF origin, not from home
                on, oe, od = self.origin
                x, y = x + on, y + oe
                z = z if profile.local_z_from_home else z + od
            else:
                x, y, z = x + self.n, y + self.e, z + self.d
            if not self._target_position(x, y, z, (vx, vy, vz) if use_vel else None, mask):
                return
        elif use_vel:
            self._fly_velocity(vx, vy, vz)
        else:
            return
        self._target_yaw(mask, msg.yaw, msg.yaw_rate, relative=body)

    def _on_set_position_target_global_int(self, msg) -> None:
        if not self._guided_accepts():
            return
        mask = msg.type_mask
        if not finite(msg.alt, msg.vx, msg.vy, msg.vz, msg.yaw, msg.yaw_rate):
            return
        if not (mask & POS_IGNORE):
            north, east = self.ned_from(msg.lat_int / 1e7, msg.lon_int / 1e7)
            if msg.coordinate_frame in (mavlink.MAV_FRAME_GLOBAL, mavlink.MAV_FRAME_GLOBAL_INT):
                down = -(msg.alt - self.home_alt)
            else:
                down = -msg.alt
            velocity = None if mask & VEL_IGNORE else (msg.vx, msg.vy, msg.vz)
            if not self._target_position(north, east, down, velocity, mask):
                return
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

    def _target_position(self, north: float, east: float, down: float, velocity, mask: int) -> bool:
        """GCS_MAVLINK_Copter's choice: position with velocity is the PosVelAccel target (set_destination_posvel);
        a position alone the destination; a position with an acceleration and no velocity is refused by stopping
        (mode_guided.init)."""
        if velocity is not None:
            if not self._within_fence(north, east, -down):
                return False                 # set_destination_posvelaccel: outside the fence, ignored
            self.pos_target = (_clamp(north, -1e5, 1e5), _clamp(east, -1e5, 1e5), _clamp(down, -1000.0, 0.0))
            self.vel_target = tuple(_clamp(v, -20.0, 20.0) for v in velocity)
            self.vel_time = self.posvel_time = self.t
            self.guided = "posvel"
            self.hold_point = None
            return True
        if mask & ACC_IGNORE != ACC_IGNORE:
            self.guided, self.hold_point = "hold", None
            return False
        return self._go_to(north, east, down)

    def _go_to(self, north: float, east: float, down: float) -> bool:
        if not self._within_fence(north, east, -down):
            log.info("guided target N%.0f E%.0f alt %.0f outside the fence ignored", north, east, -down)
            return False             # ModeGuided::set_destination returns false: no answer, nothing flies
        self.pos_target = (_clamp(north, -1e5, 1e5), _clamp(east, -1e5, 1e5), _clamp(down, -1000.0, 0.0))
        self.guided = "position"
        self.hold_point = None
        return True

    def _within_fence(self, north: float, east: float, up: float) -> bool:
        """AC_Fence::check_destination_within_fence for the ceiling, the circle around home and the polygons."""
        if not self.params["FENCE_ENABLE"]:
            return True
        types = int(self.params["FENCE_TYPE"])
        if types & 1 and up > float(self.params["FENCE_ALT_MAX"]):
            return False
        if types & 4 and self.polygon_fence_breach(north, east):     # missions.py
            return False
        return not (types & 2 and math.hypot(north, east) > float(self.params["FENCE_RADIUS"]))

    def _target_yaw(self, mask: int, yaw: float, yaw_rate: float, relative: bool) -> None:
        self.yaw_cmds_enabled = True
        if not self.profile.setpoint_yaw:
            # 3.3: yaw and yaw_rate are "for future use"; the nose keeps its auto heading (to the travel)
            if self.yaw_mode in ("hold", "rate"):
                self.yaw_mode = "look_ahead"
            return
        self.roi_yaw = False                 # auto_yaw leaves ROI for the target's yaw (or its default)
        if not (mask & YAW_IGNORE) and not (mask & YAW_RATE_IGNORE) and not relative:
            self.yaw_mode = "angle_rate"     # AutoYaw::set_yaw_angle_rate: the heading moves on with the rate
            self.yaw_target, self.yaw_rate_cmd = wrap_pi(yaw), _clamp(yaw_rate, -3.5, 3.5)
        elif not (mask & YAW_IGNORE):
            target = yaw + (self.yaw if relative else 0.0)
            self.yaw_mode = "fixed"
            self.yaw_remaining = wrap_pi(target - self.yaw)
            self.yaw_slew = AUTO_YAW_SLEW
        elif not (mask & YAW_RATE_IGNORE):
            self.yaw_mode = "rate"
            self.yaw_rate_cmd = _clamp(yaw_rate, -3.5, 3.5)
        else:
            self.yaw_mode = "look_ahead"

    # -- parameters, missions, misc -----------------------------------------------------------------

    def _on_autopilot_version_request(self, msg) -> None:
        self._send_now("AUTOPILOT_VERSION")

    def _on_setup_signing(self, msg) -> None:
        """GCS_MAVLINK::handle_setup_signing: never while armed (a WARNING on the asking link only, nothing
        changes); else the key goes to every link at once. A MAVLink 1 vehicle never gets here: message 256
        does not fit a MAVLink 1 frame and the Solo's 3.3 firmware has no GCS_Signing at all."""
        if self.signing is None:
            return
        if self.armed:
            self.signing.counters.refused_armed += 1
            self.emit_to(self.factory.statustext_encode(mavlink.MAV_SEVERITY_WARNING,
                                                        b"ERROR: Won't setup signing when armed"), self.sender)
            return
        self.signing.setup(bytes(msg.secret_key), msg.initial_timestamp)

    def _on_timesync(self, msg) -> None:
        if msg.tc1 == 0:
            self.emit(self.factory.timesync_encode(int(self.t * 1e9), msg.ts1))
