"""The simulated vehicle's gimbal and camera, mixed into :class:`~driver.sim.autopilot.Autopilot`.

``copter-4`` follows tests/data/recordings/arducopter-4.6-sitl-gimbal.tlog (ArduCopter 4.6.3, a servo mount,
ArduPilot's copter-gimbal.parm): the autopilot itself (component 1) reports GIMBAL_DEVICE_ATTITUDE_STATUS, a
quaternion in the vehicle's frame with flags 44 (45 retracted); DO_MOUNT_CONTROL and DO_GIMBAL_MANAGER_PITCHYAW
(an angle, or a rate with the angles NaN) are ACCEPTED and followed within 0.2 s; the legacy MOUNT_CONTROL
message changes nothing; GIMBAL_DEVICE_INFORMATION is FAILED and GIMBAL_MANAGER_INFORMATION ACCEPTED with
nothing sent; DO_SET_ROI_NONE hands the mount back to its default mode (RC targeting, which holds the pitch at
-90 as RC6 sits); with no camera DO_DIGICAM_CONTROL is ACCEPTED and IMAGE_START_CAPTURE FAILED. With
``SimConfig.camera`` a camera answers triggers (CAMERA_FEEDBACK, CAMERA_IMAGE_CAPTURED, CAMERA_CAPTURE_STATUS).

``solo`` follows 3DR's ardupilot-solo (ArduCopter 3.3): COMMAND_LONG knows no mount, ROI-location, camera or
gimbal-manager command (UNSUPPORTED); MOUNT_CONFIGURE and MOUNT_CONTROL messages point AP_Mount_MAVLink's gimbal
(component 154; no yaw: the vehicle turns), MOUNT_STATUS reports it (centidegrees) in the EXTRA3 stream;
DO_SET_ROI points it at a place (zeros stop it). The gimbal (154) also carries the GoPro: GOPRO_HEARTBEAT at
1 Hz, GOPRO_SET_REQUEST answered with GOPRO_SET_RESPONSE, one at a time (OpenSolo's shotmanager).
"""
from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mavlink
from pymavlink.quaternion import QuaternionBase

from .common import finite

__all__ = ["Payload", "GIMBAL_COMPONENT", "MOUNT_SLEW", "PITCH_LIMITS"]

GIMBAL_COMPONENT = mavlink.MAV_COMP_ID_GIMBAL
MOUNT_SLEW = 450.0                 # deg/s: -90 to -45 in 0.1 s, as the recording's servo (8.30 -> 8.51 s)
PITCH_LIMITS = (-90.0, 0.0)        # MNT1_PITCH_MIN/MAX (copter-gimbal.parm); the Solo gimbal's travel
RC_PITCH = -90.0                   # where RC targeting holds the servo (the recording, before and after ROI)
FLAGS = 4 | 8 | 32                 # ROLL_LOCK | PITCH_LOCK | YAW_IN_VEHICLE_FRAME: the recording's 44
GOPRO_HEARTBEAT_INTERVAL = 1.0
CAMERA_FOV = (74.0, 50.0)          # deg horizontal, vertical of the simulated camera (CAMERA_INFORMATION)


class Payload:
    """Mount, camera and (solo) GoPro; state lives on the Autopilot as ``mount_*`` / ``camera_*``."""

    def _payload_init(self) -> None:
        self.mount_pitch = RC_PITCH
        self.mount_yaw = 0.0
        self.mount_mode = mavlink.MAV_MOUNT_MODE_RC_TARGETING
        self.mount_target = (RC_PITCH, 0.0)
        self.mount_rate: tuple[float, float] | None = None
        self.mount_roi: tuple[float, float, float] | None = None
        self.roi_yaw = False               # the vehicle turns its nose to the ROI (the mount has no yaw axis)
        self.images = 0
        self.trigg_dist = 0.0              # m, DO_SET_CAM_TRIGG_DIST (CAM1_TRIGG_DIST): a picture every so far
        self.trigg_from: tuple[float, float] | None = None   # (north, east) of the last picture (or the start)
        self.video = False
        self.gopro_mode = mavlink.GOPRO_CAPTURE_MODE_VIDEO
        self.gopro_recording = False
        self.gopro_next = 0.0
        self.gimbal_outbox: list = []      # messages the gimbal (component 154) says; SimVehicle sends them

    @property
    def _camera_kind(self) -> str | None:
        """SimConfig.camera: True or "mavlink" (4.5+ AP_Camera: the camera protocol and CAMERA_FEEDBACK),
        "trigger" (a servo/relay camera before 4.5: DO_DIGICAM_CONTROL and CAMERA_FEEDBACK only), or None."""
        camera = getattr(self.config, "camera", False)
        return None if not camera else "trigger" if camera == "trigger" else "mavlink"

    @property
    def _solo_mount(self) -> bool:
        return getattr(self.profile, "mount", "servo") == "solo"

    def take_gimbal_messages(self) -> list:
        out, self.gimbal_outbox = self.gimbal_outbox, []
        return out

    def _for_gimbal(self, msg) -> bool:
        """A message addressed to the Solo's gimbal component that it answers (its GoPro)."""
        return (self._solo_mount and getattr(msg, "target_component", 0) == GIMBAL_COMPONENT
                and msg.get_type() == "GOPRO_SET_REQUEST")

    # -- time ----------------------------------------------------------------------------------------------
    def _payload_step(self, dt: float) -> None:
        if self.mount_mode == mavlink.MAV_MOUNT_MODE_RETRACT:
            target = (0.0, 0.0)
        elif self.mount_mode == mavlink.MAV_MOUNT_MODE_RC_TARGETING:
            target = (RC_PITCH, 0.0)
        elif self.mount_mode == mavlink.MAV_MOUNT_MODE_GPS_POINT and self.mount_roi is not None:
            target = self._roi_angles()
        elif self.mount_rate is not None:
            pitch = self.mount_target[0] + self.mount_rate[0] * dt
            target = (pitch, 0.0)
        else:
            target = self.mount_target
        self._face_roi()
        self._trigger_by_distance()
        pitch = min(max(target[0], PITCH_LIMITS[0]), PITCH_LIMITS[1])
        self.mount_target = (pitch, 0.0)          # neither mount has a yaw axis: the vehicle turns
        step = MOUNT_SLEW * dt
        self.mount_pitch += max(-step, min(step, pitch - self.mount_pitch))
        if self._solo_mount:
            if self.t >= self.gopro_next:
                self.gopro_next = self.t + GOPRO_HEARTBEAT_INTERVAL
                flags = mavlink.GOPRO_FLAG_RECORDING if self.gopro_recording else 0
                self.gimbal_outbox.append(mavlink.MAVLink_gopro_heartbeat_message(
                    mavlink.GOPRO_HEARTBEAT_STATUS_CONNECTED, self.gopro_mode, flags))

    def set_trigger_distance(self, metres: float, now: bool = False) -> None:
        """DO_SET_CAM_TRIGG_DIST as AP_Mission runs it: the distance (0 stops), and a picture at once when its
        param3 is 1. With no camera nothing happens (AP_Camera has no backend)."""
        if not self._camera_kind or not finite(metres):
            return
        self.trigg_dist = max(0.0, float(metres))
        self.trigg_from = None
        if now:
            self._picture(captured=self._camera_kind == "mavlink")

    def _trigger_by_distance(self) -> None:
        """AP_Camera_Backend::update: the first pass notes where the vehicle is; a picture each time it has moved
        the trigger distance from the last picture (CAM_AUTO_ONLY 0: in any mode)."""
        if self.trigg_dist <= 0 or not self._camera_kind:
            self.trigg_from = None
            return
        here = (self.n, self.e)
        if self.trigg_from is None:
            self.trigg_from = here
        elif math.hypot(here[0] - self.trigg_from[0], here[1] - self.trigg_from[1]) >= self.trigg_dist:
            self._picture(captured=self._camera_kind == "mavlink")
            self.trigg_from = here

    def _face_roi(self) -> None:
        """ArduCopter's auto_yaw ROI mode (set by the ROI commands when the mount cannot pan): in GUIDED and AUTO,
        flying, the nose turns to the point; a pilot's yaw rate ends it (auto_yaw.set_rate)."""
        if not self.roi_yaw or self.mount_roi is None:
            return
        if self.yaw_mode == "rate":
            self.roi_yaw = False
            return
        if self.landed or not self.armed or self.mode_name not in ("GUIDED", "AUTO"):
            return
        north, east = self._roi_offset()
        if math.hypot(north, east) < 1.0:
            return
        self.yaw_mode = "fixed"
        self.yaw_remaining = math.remainder(math.atan2(east, north) - self.yaw, 2 * math.pi)
        self.yaw_slew = math.radians(60.0)

    def _roi_offset(self) -> tuple[float, float]:
        north, east = self.ned_from(*self.mount_roi[:2])
        return north - self.n, east - self.e

    def _roi_angles(self) -> tuple[float, float]:
        north, east = self._roi_offset()
        below = -self.d - self.mount_roi[2]                     # metres the vehicle is above the point
        return math.degrees(math.atan2(-below, max(math.hypot(north, east), 0.01))), 0.0

    # -- telemetry -------------------------------------------------------------------------------------------
    def _msg_gimbal_device_attitude_status(self):
        if self._solo_mount:
            return None
        retracted = self.mount_mode == mavlink.MAV_MOUNT_MODE_RETRACT
        q = QuaternionBase([0.0, math.radians(self.mount_pitch), math.radians(self.mount_yaw)]).q
        nan = float("nan")
        return mavlink.MAVLink_gimbal_device_attitude_status_message(
            0, 0, self.time_boot_ms(), FLAGS | (1 if retracted else 0), [float(v) for v in q], nan, nan, nan, 0,
            nan, nan, 1)

    def _msg_mount_status(self):
        """3.3's EXTRA3 stream (common.STREAMS) carries it; 4.x's servo mount sends none."""
        if not self._solo_mount:
            return None
        return mavlink.MAVLink_mount_status_message(0, 0, int(round(self.mount_pitch * 100)), 0,
                                                    int(round(self.mount_yaw * 100)), self.mount_mode)

    def _msg_gimbal_manager_information(self):
        return None                    # ACCEPTED and never sent by the recorded servo mount

    def _msg_camera_information(self):
        if self._camera_kind != "mavlink" or self._solo_mount:
            return None                # the recording: ACCEPTED, nothing sent without a camera
        flags = mavlink.CAMERA_CAP_FLAGS_CAPTURE_IMAGE | mavlink.CAMERA_CAP_FLAGS_CAPTURE_VIDEO
        return mavlink.MAVLink_camera_information_message(
            self.time_boot_ms(), list(b"UavViewer".ljust(32, b"\0")), list(b"SimCam".ljust(32, b"\0")), 1, 4.0,
            6.17, 4.55, 1920, 1080, 0, flags, 0, b"", 1, 1)

    def _msg_camera_capture_status(self):
        if not self._camera_kind:
            return None
        return mavlink.MAVLink_camera_capture_status_message(self.time_boot_ms(), 0, 1 if self.video else 0, 0,
                                                             0, 1000.0, self.images, 1)

    # -- commands (COMMAND_LONG / COMMAND_INT) ---------------------------------------------------------------
    def _cmd_do_mount_control(self, p1, p2, p3, p4, p5, p6, p7):
        if self._solo_mount:
            return mavlink.MAV_RESULT_UNSUPPORTED, None
        mode = int(p7)
        if mode == mavlink.MAV_MOUNT_MODE_MAVLINK_TARGETING:
            if not finite(p1):
                return mavlink.MAV_RESULT_FAILED, None
            self.mount_target, self.mount_rate = (float(p1), 0.0), None
        self.mount_mode = mode
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_do_gimbal_manager_pitchyaw(self, p1, p2, p3, p4, *_):
        """AP_Mount::handle_command_do_gimbal_manager_pitchyaw: angles when both are numbers, else rates."""
        if self._solo_mount:
            return mavlink.MAV_RESULT_UNSUPPORTED, None
        if not math.isnan(p1) and not math.isnan(p2):
            self.mount_target, self.mount_rate = (float(p1), 0.0), None
        elif not math.isnan(p3) and not math.isnan(p4):
            self.mount_target, self.mount_rate = (self.mount_pitch, 0.0), (float(p3), float(p4))
        else:
            return mavlink.MAV_RESULT_FAILED, None
        self.mount_mode = mavlink.MAV_MOUNT_MODE_MAVLINK_TARGETING
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_do_mount_configure(self, p1, *_):
        if self._solo_mount:
            return mavlink.MAV_RESULT_UNSUPPORTED, None
        self.mount_mode = int(p1)
        self.mount_rate = None
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_do_set_roi_location(self, p1, p2, p3, p4, p5, p6, p7):
        if self._solo_mount:
            return mavlink.MAV_RESULT_UNSUPPORTED, None
        return self._set_roi(p5, p6, p7)

    def _cmd_do_set_roi_none(self, *_):
        if self._solo_mount:
            return mavlink.MAV_RESULT_UNSUPPORTED, None
        self.mount_roi, self.mount_mode, self.mount_rate = None, mavlink.MAV_MOUNT_MODE_RC_TARGETING, None
        self.roi_yaw = False
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_do_set_roi(self, p1, p2, p3, p4, p5, p6, p7):
        if p5 == 0 and p6 == 0 and p7 == 0:      # 3.3's set_auto_yaw_roi: a zero location turns the ROI off
            self.mount_roi, self.mount_mode = None, mavlink.MAV_MOUNT_MODE_RC_TARGETING
            self.roi_yaw = False
            return mavlink.MAV_RESULT_ACCEPTED, None
        return self._set_roi(p5, p6, p7)

    def _set_roi(self, lat, lon, alt):
        if not finite(lat, lon, alt) or not (-90 <= lat <= 90 and -180 <= lon <= 180):
            return mavlink.MAV_RESULT_FAILED, None
        self.mount_roi = (float(lat), float(lon), float(alt))
        self.mount_mode, self.mount_rate = mavlink.MAV_MOUNT_MODE_GPS_POINT, None
        self.roi_yaw = True
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_do_digicam_control(self, p1, p2, p3, p4, p5, *_):
        if self._solo_mount:
            return mavlink.MAV_RESULT_UNSUPPORTED, None
        if int(p5) == 1 and self._camera_kind:
            return mavlink.MAV_RESULT_ACCEPTED, self._picture
        return mavlink.MAV_RESULT_ACCEPTED, None   # the recording: ACCEPTED with no camera, nothing taken

    def _cmd_image_start_capture(self, *_):
        if self._solo_mount or self._camera_kind == "trigger":
            return mavlink.MAV_RESULT_UNSUPPORTED, None
        if not self._camera_kind:
            return mavlink.MAV_RESULT_FAILED, None  # the recording, 101.52 s
        return mavlink.MAV_RESULT_ACCEPTED, lambda: self._picture(captured=True)

    def _cmd_video_start_capture(self, *_):
        return self._video(True)

    def _cmd_video_stop_capture(self, *_):
        return self._video(False)

    def _video(self, on: bool):
        if self._solo_mount or self._camera_kind == "trigger":
            return mavlink.MAV_RESULT_UNSUPPORTED, None
        if not self._camera_kind:
            return mavlink.MAV_RESULT_FAILED, None
        self.video = on
        return mavlink.MAV_RESULT_ACCEPTED, lambda: self._send_now("CAMERA_CAPTURE_STATUS")

    def _picture(self, captured: bool = False) -> None:
        """AP_Camera: CAMERA_FEEDBACK for every picture; the camera protocol's CAMERA_IMAGE_CAPTURED too."""
        self.images += 1
        self.log_camera()
        lat, lon = self._lat_lon()
        lat_i, lon_i = int(round(lat * 1e7)), int(round(lon * 1e7))
        alt_msl = self.home_alt - self.d
        self.emit(mavlink.MAVLink_camera_feedback_message(
            self.time_boot_ms() * 1000, self.config.system_id, 0, self.images, lat_i, lon_i, alt_msl, -self.d,
            math.degrees(self.roll), math.degrees(self.pitch), math.degrees(self.yaw) % 360.0, 4.0, 0, self.images))
        if captured:
            q = QuaternionBase([0.0, math.radians(self.mount_pitch), self.yaw]).q
            self.emit(mavlink.MAVLink_camera_image_captured_message(
                self.time_boot_ms(), 0, 1, lat_i, lon_i, int(alt_msl * 1000), int(-self.d * 1000),
                [float(v) for v in q], self.images - 1, 1, b""))

    # -- messages ------------------------------------------------------------------------------------------
    def _on_mount_configure(self, msg) -> None:
        if self._solo_mount:                       # 3.3: camera_mount.configure_msg
            self.mount_mode = msg.mount_mode
            self.mount_rate = None

    def _on_mount_control(self, msg) -> None:
        """3.3's AP_Mount_Backend::control_msg: angles in centidegrees while MAVLink targeting; ignored on 4.6
        (the recording, 13.31 s)."""
        if self._solo_mount and self.mount_mode == mavlink.MAV_MOUNT_MODE_MAVLINK_TARGETING:
            self.mount_target, self.mount_rate = (msg.input_a / 100.0, 0.0), None

    def _on_gopro_set_request(self, msg) -> None:
        if not self._solo_mount:
            return
        value = msg.value[0] if len(msg.value) else 0
        ok = True
        if msg.cmd_id == mavlink.GOPRO_COMMAND_CAPTURE_MODE:
            ok = not self.gopro_recording and value in (mavlink.GOPRO_CAPTURE_MODE_VIDEO,
                                                          mavlink.GOPRO_CAPTURE_MODE_PHOTO)
            if ok:
                self.gopro_mode = value
        elif msg.cmd_id == mavlink.GOPRO_COMMAND_SHUTTER:
            if self.gopro_mode == mavlink.GOPRO_CAPTURE_MODE_PHOTO:
                ok = value == 1
                if ok:
                    self.images += 1
            else:
                self.gopro_recording = value == 1
                self.gopro_next = self.t               # the heartbeat tells the new state at once
        else:
            ok = False
        self.gimbal_outbox.append(mavlink.MAVLink_gopro_set_response_message(
            msg.cmd_id, mavlink.GOPRO_REQUEST_SUCCESS if ok else mavlink.GOPRO_REQUEST_FAILED))
