"""The payload part of the embedded driver: point the gimbal, look at a point, take pictures and video.

Which protocol, decided from what the vehicle has shown (and learnt again from an UNSUPPORTED):

* **gimbal manager** (ArduCopter 4.1+, the gimbal recording): DO_GIMBAL_MANAGER_PITCHYAW by angle; a rate
  is stepped here as angles every 0.1 s, because the protocol's own rate form needs NaN in the angle fields
  ("not used") and no NaN ever goes on the wire; attitude from GIMBAL_DEVICE_ATTITUDE_STATUS, asked at 5 Hz
  as the recording's GCS did.
* **DO_MOUNT_CONTROL** (MAV_MOUNT_MODE_MAVLINK_TARGETING) on firmware that answers MOUNT_STATUS only; a rate
  there is stepped as angles too.
* **MOUNT_CONTROL message** on 3DR's Solo (ArduCopter 3.3, AP_Mount_MAVLink on component 154): its
  COMMAND_LONG knows no mount command, so MOUNT_CONFIGURE(MAVLINK_TARGETING) + MOUNT_CONTROL (centidegrees)
  as the Solo's shotmanager did, confirmed by MOUNT_STATUS showing the angle; a rate is stepped at 10 Hz.

Region of interest: DO_SET_ROI_LOCATION / DO_SET_ROI_NONE, or the Solo's DO_SET_ROI (zeros stop it).
Pictures: IMAGE_START_CAPTURE where CAMERA_INFORMATION says a MAVLink camera exists, the Solo's GoPro through
GOPRO_SET_REQUEST (component 154), else DO_DIGICAM_CONTROL. An ACK never counts as a picture: only
CAMERA_FEEDBACK, CAMERA_IMAGE_CAPTURED or the GoPro's answer do; video only on CAMERA_CAPTURE_STATUS or the
GoPro heartbeat's recording flag.

All methods run with the driver's state lock held unless they say otherwise; messages are returned or posted,
never written here.
"""
from __future__ import annotations

import logging
import time
from concurrent.futures import Future
from dataclasses import dataclass, replace

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core import frames
from ..core.results import CommandResult, CommandStatus, Severity, chain
from .model import (
    GIMBAL_PITCH_RANGE, RETRACT_FLAG, YAW_IN_EARTH_FRAME, CameraKind, Gimbal, GimbalControl, VehicleCamera,
    gimbal_from_quaternion,
)

log = logging.getLogger(__name__)

__all__ = ["Payload", "PAYLOAD_MESSAGES", "CONFIRM_TIMEOUT", "MAX_GIMBAL_RATE"]

PAYLOAD_MESSAGES = frozenset({
    "GIMBAL_DEVICE_ATTITUDE_STATUS", "MOUNT_STATUS", "GIMBAL_MANAGER_INFORMATION", "GIMBAL_MANAGER_STATUS",
    "CAMERA_INFORMATION", "CAMERA_FEEDBACK", "CAMERA_IMAGE_CAPTURED", "CAMERA_CAPTURE_STATUS",
    "GOPRO_HEARTBEAT", "GOPRO_SET_RESPONSE"})
CONFIRM_TIMEOUT = 3.0        # s after the vehicle's ACK for the camera's own confirmation
MOUNT_TOLERANCE = 3.0        # deg: MOUNT_STATUS this close to the target confirms a MOUNT_CONTROL
MOUNT_RESEND = 1.0           # s between MOUNT_CONTROL messages while MOUNT_STATUS has not shown the angle
STEP_INTERVAL = 0.1          # s between stepped angles of a rate on mounts without rates
GOPRO_WAIT = 1.0             # s the GoPro may take to answer one request before the next goes
MAX_GIMBAL_RATE = 90.0       # deg/s
ATTITUDE_RATE_HZ = 5         # GIMBAL_DEVICE_ATTITUDE_STATUS, as the recording's GCS asked
MANAGER = "gimbal manager"
MOUNT_CMD = "DO_MOUNT_CONTROL"
MOUNT_MSG = "MOUNT_CONTROL"
GIMBAL_COMPONENT = mavlink.MAV_COMP_ID_GIMBAL        # 154: the Solo's gimbal and its GoPro


@dataclass(eq=False)
class _Wait:
    """An action that resolves on the vehicle's own confirmation, not its ACK."""
    name: str
    kind: str                        # "photo", "record", "mount"
    future: Future
    want: object = None              # record: True/False; mount: the pitch wanted
    deadline: float | None = None    # set once the command is out (or ACKed)
    next_send: float = 0.0
    message = None                   # mount: the MOUNT_CONTROL to re-send
    photos_before: int = 0


class Payload:
    """Gimbal, ROI and camera of one vehicle; owned by :class:`driver.vehicle.vehicle.Vehicle`."""

    def __init__(self, vehicle) -> None:
        self._v = vehicle
        self._store = vehicle._store
        self._manager: bool | None = None        # DO_GIMBAL_MANAGER_PITCHYAW works (None: not known)
        self._mount_command: bool | None = None  # DO_MOUNT_CONTROL works
        self._roi_location: bool | None = None   # DO_SET_ROI_LOCATION works
        self._asked_at: float | None = None      # when the gimbal/camera information was asked for
        self._waits: list[_Wait] = []
        self._rate: tuple[float, float] | None = None      # stepped rate (deg/s pitch, yaw)
        self._rate_target: tuple[float, float] = (0.0, 0.0)
        self._rate_last = 0.0
        self._gopro_queue: list[tuple[int, int]] = []
        self._gopro_sent_at = -1e9
        self._gopro_busy: int | None = None
        self._gopro_mode: int | None = None      # the GoPro's capture mode (its heartbeat, or what we set)

    # -- what the vehicle says (reader thread) ---------------------------------------------------------
    def on_message(self, m, component: int) -> None:
        """Into the pending fields; the reader publishes them with the telemetry it folds (not here: publishing
        would hold the telemetry fold back, and the newest-of-each-kind would lose a message)."""
        getattr(self, "_on_" + m.get_type().lower())(m, component)

    def _gimbal(self) -> Gimbal:
        return self._store.view()["gimbal"]

    def _camera(self) -> VehicleCamera:
        return self._store.view()["camera"]

    def _on_gimbal_device_attitude_status(self, m, component: int) -> None:
        g = self._gimbal()
        angles = gimbal_from_quaternion(m.q, g.yaw_deg)
        if angles is None:
            self._store.set(rejected_values=self._store.view()["rejected_values"] + 1)
            return
        if component == self._autopilot() and self._manager is None:
            self._manager = True                # ArduPilot 4.1+ reports its mount as a gimbal device
        retracted = bool(m.flags & RETRACT_FLAG)
        control = GimbalControl.RETRACTED if retracted else (
            g.control if g.control is not GimbalControl.RETRACTED else GimbalControl.UNKNOWN)
        self._store.set(gimbal=replace(g, pitch_deg=angles[0], yaw_deg=angles[1],
                                       yaw_earth=bool(m.flags & YAW_IN_EARTH_FRAME), retracted=retracted,
                                       control=control, source="GIMBAL_DEVICE_ATTITUDE_STATUS",
                                       component=component, updated=time.time()))

    def _on_mount_status(self, m, component: int) -> None:
        pitch, yaw = m.pointing_a / 100.0, m.pointing_c / 100.0
        if not (-180.0 <= pitch <= 180.0 and -360.0 <= yaw <= 360.0):
            return
        g = self._gimbal()
        mode = m.mount_mode if m.get_msgbuf()[0] == 0xFD else None    # an extension: MAVLink 2 frames only
        control = {mavlink.MAV_MOUNT_MODE_RETRACT: GimbalControl.RETRACTED,
                   mavlink.MAV_MOUNT_MODE_NEUTRAL: GimbalControl.NEUTRAL,
                   mavlink.MAV_MOUNT_MODE_RC_TARGETING: GimbalControl.RC,
                   mavlink.MAV_MOUNT_MODE_GPS_POINT: GimbalControl.ROI}.get(mode, g.control)
        if g.source == "GIMBAL_DEVICE_ATTITUDE_STATUS" and time.time() - g.updated < 2.0:
            return                              # the richer report is current
        retracted = g.retracted if mode is None else mode == mavlink.MAV_MOUNT_MODE_RETRACT
        self._store.set(gimbal=replace(g, pitch_deg=pitch, yaw_deg=yaw, retracted=retracted,
                                       control=control, source="MOUNT_STATUS", component=component,
                                       updated=time.time()))
        for w in [w for w in self._waits if w.kind == "mount"]:
            if abs(pitch - w.want) <= MOUNT_TOLERANCE:
                self._settle(w, CommandStatus.ACCEPTED, f"MOUNT_STATUS shows {pitch:.0f}°")

    def _on_gimbal_manager_information(self, m, component: int) -> None:
        self._manager = True

    def _on_gimbal_manager_status(self, m, component: int) -> None:
        self._manager = True

    def _on_camera_information(self, m, component: int) -> None:
        name = " ".join(_text(v) for v in (m.vendor_name, m.model_name) if _text(v)) or "camera"
        can_record = bool(m.flags & mavlink.CAMERA_CAP_FLAGS_CAPTURE_VIDEO)
        self._store.set(camera=replace(self._camera(), kind=CameraKind.MAVLINK, name=name, component=component,
                                       can_record=can_record))

    def _on_camera_feedback(self, m, component: int) -> None:
        if self._camera().kind is CameraKind.MAVLINK:
            return                              # the same picture's CAMERA_IMAGE_CAPTURED counts it
        lat, lon = m.lat * 1e-7, m.lng * 1e-7
        self._photo_confirmed(f"CAMERA_FEEDBACK, image {m.img_idx}", (lat, lon) if m.lat or m.lng else None)

    def _on_camera_image_captured(self, m, component: int) -> None:
        if m.capture_result != 1:
            for w in [w for w in self._waits if w.kind == "photo"]:
                self._settle(w, CommandStatus.REFUSED, "the camera reported the capture failed")
            return
        self._photo_confirmed(f"CAMERA_IMAGE_CAPTURED, image {m.image_index}",
                              (m.lat * 1e-7, m.lon * 1e-7) if m.lat or m.lon else None)

    def _on_camera_capture_status(self, m, component: int) -> None:
        recording = m.video_status == 1
        self._store.set(camera=replace(self._camera(), recording=recording))
        self._record_seen(recording, "CAMERA_CAPTURE_STATUS")

    def _on_gopro_heartbeat(self, m, component: int) -> None:
        status = {mavlink.GOPRO_HEARTBEAT_STATUS_DISCONNECTED: "no GoPro",
                  mavlink.GOPRO_HEARTBEAT_STATUS_INCOMPATIBLE: "incompatible GoPro",
                  mavlink.GOPRO_HEARTBEAT_STATUS_CONNECTED: "connected",
                  mavlink.GOPRO_HEARTBEAT_STATUS_ERROR: "GoPro error"}.get(m.status, f"status {m.status}")
        recording = bool(m.flags & mavlink.GOPRO_FLAG_RECORDING)
        cam = self._camera()
        self._store.set(camera=replace(cam, kind=CameraKind.GOPRO, name="GoPro", component=component,
                                       can_record=True, recording=recording, status=status))
        self._gopro_mode = m.capture_mode
        self._record_seen(recording, "the GoPro's heartbeat")

    def _on_gopro_set_response(self, m, component: int) -> None:
        cmd, ok = m.cmd_id, m.status == mavlink.GOPRO_REQUEST_SUCCESS
        self._gopro_busy = None
        if cmd == mavlink.GOPRO_COMMAND_SHUTTER:
            for w in [w for w in self._waits if w.kind == "photo"]:
                if ok:
                    self._photo_confirmed("the GoPro's answer", None)
                else:
                    self._settle(w, CommandStatus.REFUSED, "the GoPro refused the shutter")
        elif not ok:
            self._gopro_queue.clear()
            for w in [w for w in self._waits if w.kind in ("photo", "record")]:
                self._settle(w, CommandStatus.REFUSED, "the GoPro refused to change its capture mode")

    def _photo_confirmed(self, how: str, where) -> None:
        cam = self._camera()
        self._store.set(camera=replace(cam, photos=cam.photos + 1, last_photo=time.time(), last_photo_at=where))
        waiting = [w for w in self._waits if w.kind == "photo"]
        if waiting:
            self._settle(waiting[0], CommandStatus.ACCEPTED, f"confirmed by {how}")

    def _record_seen(self, recording: bool, how: str) -> None:
        for w in [w for w in self._waits if w.kind == "record" and w.want == recording]:
            self._settle(w, CommandStatus.ACCEPTED, f"{how} says {'recording' if recording else 'stopped'}")

    def _settle(self, w: _Wait, status: CommandStatus, reason: str) -> None:
        if w in self._waits:
            self._waits.remove(w)
        self._v._notifier.settle(w.future, self._store.record_locked(w.name, status, reason))

    def _autopilot(self) -> int:
        return self._v._target_ids()[1]

    # -- the ticker ----------------------------------------------------------------------------------------
    def service(self, now: float, state) -> list:
        """Requests, stepped rates, GoPro queue and confirmation timeouts; returns messages to send."""
        out: list = []
        if not state.connected or self._v._replay is not None:
            self._asked_at = None if not state.connected else self._asked_at
            return out
        system, component = self._v._target_ids()
        if self._asked_at is None:
            self._asked_at = now
            caps = self._v._commands.capabilities
            if caps.message_interval is not False and not self._legacy(state):
                out.append(mavlink.MAVLink_command_long_message(
                    system, component, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                    mavlink.MAVLINK_MSG_ID_GIMBAL_DEVICE_ATTITUDE_STATUS, 1e6 / ATTITUDE_RATE_HZ, 0, 0, 0, 0, 0))
                for msg_id in (mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION,
                               mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_INFORMATION):
                    out.append(mavlink.MAVLink_command_long_message(
                        system, component, mavlink.MAV_CMD_REQUEST_MESSAGE, 0, msg_id, 0, 0, 0, 0, 0, 0))
        if self._rate is not None and now - self._rate_last >= STEP_INTERVAL:
            out += self._step_rate(now, state)
        out += self._gopro_next(now, system)
        for w in list(self._waits):
            if w.kind == "mount" and now >= w.next_send and w.message is not None:
                out.append(w.message)
                w.next_send = now + MOUNT_RESEND
            if w.deadline is not None and now >= w.deadline:
                self._settle(w, CommandStatus.TIMED_OUT, self._unconfirmed(w, state))
        return out

    def _unconfirmed(self, w: _Wait, state) -> str:
        if w.kind == "photo":
            return ("the vehicle took the command but no camera confirmed a picture (no CAMERA_FEEDBACK or "
                    "CAMERA_IMAGE_CAPTURED): is a camera configured on it (CAM1_TYPE)?")
        if w.kind == "record":
            return f"the camera did not say it {'started' if w.want else 'stopped'} recording"
        shown = state.gimbal.pitch_deg
        return (f"MOUNT_STATUS still shows {shown:.0f}°" if shown is not None else
                "the vehicle sent no MOUNT_STATUS") + f" after {CONFIRM_TIMEOUT:g} s"

    # -- helpers --------------------------------------------------------------------------------------------
    def _legacy(self, state) -> bool:
        """3DR's ArduCopter 3.3 (the Solo): no mount or message commands in COMMAND_LONG."""
        version = _version(state.firmware)
        return version is not None and version < (3, 4)

    def protocol(self, state) -> str:
        if self._legacy(state) or self._mount_command is False:
            return MOUNT_MSG
        if self._manager is False:
            return MOUNT_CMD
        if self._manager or state.gimbal.source != "MOUNT_STATUS":
            return MANAGER
        return MOUNT_CMD

    def _answered(self, name: str, status: CommandStatus, reason: str) -> Future:
        return self._v._finish(name, status, reason)

    @staticmethod
    def _unsupported(result: CommandResult) -> bool:
        return result.status is CommandStatus.REFUSED and "UNSUPPORTED" in result.reason

    # -- pointing -----------------------------------------------------------------------------------------
    def point(self, pitch: float, yaw: float | None = None) -> Future:
        name = f"gimbal pitch {pitch:g}°" + ("" if yaw is None else f" yaw {yaw:g}°")
        if not frames.finite(pitch) or (yaw is not None and not frames.finite(yaw)):
            return self._answered("gimbal", CommandStatus.REJECTED, "angle is not a finite number")
        pitch = min(max(float(pitch), GIMBAL_PITCH_RANGE[0]), GIMBAL_PITCH_RANGE[1])
        yaw = None if yaw is None else frames.wrap_180(float(yaw))
        state = self._v.state()
        problem = self._problem(state)
        if problem:
            return self._answered(name, CommandStatus.REJECTED, problem)
        with self._store.lock:
            self._rate = None
        return self._point_by(self.protocol(state), name, pitch, yaw)

    def _point_by(self, protocol: str, name: str, pitch: float, yaw: float | None) -> Future:
        if protocol == MANAGER:
            inner = self._v._command_long(mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
                                          (pitch, yaw or 0.0, 0, 0, 0, 0, 0), f"{name} (DO_GIMBAL_MANAGER_PITCHYAW)")
            return chain(inner, lambda r: self._pointed(r, name, pitch, yaw, GimbalControl.ANGLE, MANAGER), name)
        if protocol == MOUNT_CMD:
            inner = self._v._command_long(mavlink.MAV_CMD_DO_MOUNT_CONTROL,
                                          (pitch, 0, yaw or 0.0, 0, 0, 0, mavlink.MAV_MOUNT_MODE_MAVLINK_TARGETING),
                                          f"{name} (DO_MOUNT_CONTROL)")
            return chain(inner, lambda r: self._pointed(r, name, pitch, yaw, GimbalControl.ANGLE, MOUNT_CMD), name)
        return self._mount_message(name, pitch, yaw)

    def _pointed(self, result: CommandResult, name: str, pitch, yaw, control: GimbalControl, protocol: str):
        if self._unsupported(result):
            with self._store.lock:
                if protocol == MANAGER:
                    self._manager = False
                else:
                    self._mount_command = False
                self._store.add_message_locked(Severity.NOTICE, f"The vehicle does not know {protocol}: "
                                               f"pointing its gimbal with {self.protocol(self._v.state())}")
            return self._point_by(self.protocol(self._v.state()), name, pitch, yaw)
        with self._store.lock:
            if result.ok:
                g = self._gimbal()
                self._store.set(gimbal=replace(g, control=control, protocol=protocol, roi=None))
                self._store.publish()
            return result                       # its own record says what went out and what came back

    def _mount_message(self, name: str, pitch: float, yaw: float | None) -> Future:
        """The Solo: MOUNT_CONFIGURE to MAVLink targeting, then MOUNT_CONTROL until MOUNT_STATUS shows it."""
        system, component = self._v._target_ids()
        future: Future = Future()
        with self._store.lock:
            for w in [w for w in self._waits if w.kind == "mount"]:
                self._settle(w, CommandStatus.ABORTED, f"superseded by {name}")
            self._v._post(mavlink.MAVLink_mount_configure_message(
                system, component, mavlink.MAV_MOUNT_MODE_MAVLINK_TARGETING, 1, 1, 0))
            w = _Wait(name, "mount", future, want=pitch, deadline=self._v.clock() + CONFIRM_TIMEOUT)
            w.message = self._mount_control(pitch, yaw)
            self._waits.append(w)
            g = self._gimbal()
            self._store.set(gimbal=replace(g, control=GimbalControl.ANGLE, protocol=MOUNT_MSG, roi=None))
            self._store.publish()
        self._v._wake.set()
        return future

    def _mount_control(self, pitch: float, yaw: float | None):
        system, component = self._v._target_ids()
        return mavlink.MAVLink_mount_control_message(system, component, int(round(pitch * 100)), 0,
                                                     int(round((yaw or 0.0) * 100)), 0)

    def rate(self, pitch_rate: float, yaw_rate: float = 0.0) -> Future:
        name = f"gimbal rate {pitch_rate:+g}°/s" + (f" yaw {yaw_rate:+g}°/s" if yaw_rate else "")
        if not frames.finite(pitch_rate, yaw_rate):
            return self._answered("gimbal rate", CommandStatus.REJECTED, "rate is not a finite number")
        pitch_rate = min(max(float(pitch_rate), -MAX_GIMBAL_RATE), MAX_GIMBAL_RATE)
        yaw_rate = min(max(float(yaw_rate), -MAX_GIMBAL_RATE), MAX_GIMBAL_RATE)
        state = self._v.state()
        problem = self._problem(state)
        if problem:
            return self._answered(name, CommandStatus.REJECTED, problem)
        protocol = self.protocol(state)
        g = state.gimbal
        with self._store.lock:
            if pitch_rate == 0.0 and yaw_rate == 0.0:
                self._rate = None
            else:
                if self._rate is None:
                    self._rate_target = (g.pitch_deg if g.pitch_deg is not None else 0.0, g.yaw_deg or 0.0)
                    self._rate_last = self._v.clock()
                self._rate = (pitch_rate, yaw_rate)
                self._store.set(gimbal=replace(self._gimbal(), control=GimbalControl.RATE, protocol=protocol))
            self._v._wake.set()
            return self._v._finish(name, CommandStatus.ACCEPTED,
                                   f"stepping the {protocol} angle every {STEP_INTERVAL:g} s")

    def _rate_done(self, result: CommandResult, name: str, pitch_rate: float, yaw_rate: float):
        if self._unsupported(result):
            with self._store.lock:
                self._manager = False
            return self.rate(pitch_rate, yaw_rate)
        with self._store.lock:
            if result.ok:
                self._store.set(gimbal=replace(self._gimbal(), control=GimbalControl.RATE, protocol=MANAGER,
                                               roi=None))
                self._store.publish()
            return result                       # its own record says what went out and what came back

    def _step_rate(self, now: float, state) -> list:
        dt = min(now - self._rate_last, 0.5)
        self._rate_last = now
        pitch = self._rate_target[0] + self._rate[0] * dt
        pitch = min(max(pitch, GIMBAL_PITCH_RANGE[0]), GIMBAL_PITCH_RANGE[1])
        yaw = frames.wrap_180(self._rate_target[1] + self._rate[1] * dt)
        self._rate_target = (pitch, yaw)
        return [self.angle_message(pitch, yaw, state)]

    def angle_message(self, pitch: float, yaw: float, state):
        """One angle for the gimbal, unacknowledged, in the protocol this vehicle's mount speaks: for what streams
        angles (a stepped rate, a smart shot's camera), never a retried command each."""
        system, component = self._v._target_ids()
        protocol = self.protocol(state)
        if protocol == MOUNT_MSG:
            return self._mount_control(pitch, yaw)
        if protocol == MANAGER:                 # an angle, never the protocol's NaN "not used" for a rate
            return mavlink.MAVLink_command_long_message(system, component, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
                                                        0, pitch, yaw, 0, 0, 0, 0, 0)
        return mavlink.MAVLink_command_long_message(system, component, mavlink.MAV_CMD_DO_MOUNT_CONTROL, 0,
                                                    pitch, 0, yaw, 0, 0, 0, mavlink.MAV_MOUNT_MODE_MAVLINK_TARGETING)

    # -- region of interest ------------------------------------------------------------------------------
    def look_at(self, lat: float, lon: float, alt: float = 0.0) -> Future:
        name = f"look at {lat:.6f}, {lon:.6f}"
        if not frames.finite(lat, lon, alt) or not (-90 <= lat <= 90 and -180 <= lon <= 180) or abs(alt) > 10000:
            return self._answered("look at", CommandStatus.REJECTED, "not a place on Earth")
        state = self._v.state()
        problem = self._problem(state)
        if problem:
            return self._answered(name, CommandStatus.REJECTED, problem)
        with self._store.lock:
            self._rate = None
        if self._legacy(state) or self._roi_location is False:
            inner = self._v._command_long(mavlink.MAV_CMD_DO_SET_ROI, (0, 0, 0, 0, lat, lon, alt),
                                          f"{name} (DO_SET_ROI)")
        else:
            inner = self._v._command_long(mavlink.MAV_CMD_DO_SET_ROI_LOCATION, (0, 0, 0, 0, lat, lon, alt),
                                          f"{name} (DO_SET_ROI_LOCATION)")

        def done(r: CommandResult):
            if self._unsupported(r) and self._roi_location is not False and not self._legacy(state):
                self._roi_location = False
                return self.look_at(lat, lon, alt)
            with self._store.lock:
                if r.ok:
                    self._store.set(gimbal=replace(self._gimbal(), control=GimbalControl.ROI, roi=(lat, lon, alt)))
                    self._store.publish()
                return r
        return chain(inner, done, name)

    def stop_looking(self) -> Future:
        name = "stop looking (ROI none)"
        state = self._v.state()
        problem = self._problem(state)
        if problem:
            return self._answered(name, CommandStatus.REJECTED, problem)
        if self._legacy(state) or self._roi_location is False:
            inner = self._v._command_long(mavlink.MAV_CMD_DO_SET_ROI, (0, 0, 0, 0, 0, 0, 0), f"{name} (DO_SET_ROI 0)")
        else:
            inner = self._v._command_long(mavlink.MAV_CMD_DO_SET_ROI_NONE, (0,), f"{name} (DO_SET_ROI_NONE)")

        def done(r: CommandResult):
            with self._store.lock:
                if r.ok:      # the mount goes back to its default mode (the recording: RC targeting)
                    self._store.set(gimbal=replace(self._gimbal(), control=GimbalControl.RC, roi=None))
                    self._store.publish()
                return r
        return chain(inner, done, name)

    # -- camera -------------------------------------------------------------------------------------------
    def take_photo(self) -> Future:
        state = self._v.state()
        problem = self._problem(state)
        if problem:
            return self._answered("photo", CommandStatus.REJECTED, problem)
        cam = state.camera
        future: Future = Future()
        with self._store.lock:
            if any(w.kind == "photo" for w in self._waits):
                return self._v._finish("photo", CommandStatus.REJECTED, "the last picture is not confirmed yet")
            w = _Wait("photo", "photo", future, photos_before=cam.photos)
            self._waits.append(w)
            if cam.kind is CameraKind.GOPRO:
                if self._gopro_mode != mavlink.GOPRO_CAPTURE_MODE_PHOTO:
                    self._gopro_queue.append((mavlink.GOPRO_COMMAND_CAPTURE_MODE, mavlink.GOPRO_CAPTURE_MODE_PHOTO))
                self._gopro_queue.append((mavlink.GOPRO_COMMAND_SHUTTER, 1))
                w.deadline = self._v.clock() + CONFIRM_TIMEOUT + GOPRO_WAIT * len(self._gopro_queue)
                self._v._wake.set()
                return future
        if cam.kind is CameraKind.MAVLINK:
            inner = self._v._command_long(mavlink.MAV_CMD_IMAGE_START_CAPTURE, (0, 0, 1, 0), "IMAGE_START_CAPTURE")
        else:
            inner = self._v._command_long(mavlink.MAV_CMD_DO_DIGICAM_CONTROL, (0, 0, 0, 0, 1, 0, 0),
                                          "DO_DIGICAM_CONTROL shoot")
        inner.add_done_callback(lambda f: self._acked(w, f.result()))
        return future

    def _acked(self, w: _Wait, result: CommandResult) -> None:
        """The vehicle answered the trigger: a refusal ends it, an acceptance waits for the camera (any thread)."""
        with self._store.lock:
            if w not in self._waits:
                return
            if not result.ok:
                self._settle(w, result.status, result.reason)
            else:
                w.deadline = self._v.clock() + CONFIRM_TIMEOUT

    def record_video(self, on: bool) -> Future:
        name = f"record {'on' if on else 'off'}"
        state = self._v.state()
        problem = self._problem(state)
        if problem:
            return self._answered(name, CommandStatus.REJECTED, problem)
        cam = state.camera
        if cam.kind is CameraKind.UNKNOWN or (cam.kind is CameraKind.MAVLINK and not cam.can_record):
            return self._answered(name, CommandStatus.REJECTED,
                                  "no camera on the vehicle says it records video (no CAMERA_INFORMATION with video, "
                                  "no GoPro); DO_DIGICAM_CONTROL only takes pictures")
        future: Future = Future()
        with self._store.lock:
            for old in [x for x in self._waits if x.kind == "record"]:
                self._settle(old, CommandStatus.ABORTED, f"superseded by {name}")
            w = _Wait(name, "record", future, want=on)
            self._waits.append(w)
            if cam.kind is CameraKind.GOPRO:
                if on and self._gopro_mode != mavlink.GOPRO_CAPTURE_MODE_VIDEO:
                    self._gopro_queue.append((mavlink.GOPRO_COMMAND_CAPTURE_MODE, mavlink.GOPRO_CAPTURE_MODE_VIDEO))
                self._gopro_queue.append((mavlink.GOPRO_COMMAND_SHUTTER, 1 if on else 0))
                w.deadline = self._v.clock() + CONFIRM_TIMEOUT + GOPRO_WAIT * len(self._gopro_queue)
                self._v._wake.set()
                return future
        command = mavlink.MAV_CMD_VIDEO_START_CAPTURE if on else mavlink.MAV_CMD_VIDEO_STOP_CAPTURE
        inner = self._v._command_long(command, (0, 0), "VIDEO_START_CAPTURE" if on else "VIDEO_STOP_CAPTURE")
        inner.add_done_callback(lambda f: self._acked(w, f.result()))
        return future

    def _gopro_next(self, now: float, system: int) -> list:
        """One GOPRO_SET_REQUEST at a time: the GoPro answers each before it takes the next (shotmanager)."""
        if not self._gopro_queue or (self._gopro_busy is not None and now - self._gopro_sent_at < GOPRO_WAIT):
            return []
        cmd, value = self._gopro_queue.pop(0)
        self._gopro_busy, self._gopro_sent_at = cmd, now
        if cmd == mavlink.GOPRO_COMMAND_CAPTURE_MODE:
            self._gopro_mode = value
        return [mavlink.MAVLink_gopro_set_request_message(system, GIMBAL_COMPONENT, cmd, [value, 0, 0, 0])]

    def _problem(self, state) -> str | None:
        if self._v._replay is not None:
            return "replaying a recording: no vehicle to command"
        if not state.connected:
            return "no vehicle connected"
        return None


def _text(value) -> str:
    if isinstance(value, (bytes, bytearray)):
        value = bytes(value).split(b"\0", 1)[0].decode("ascii", "replace")
    elif isinstance(value, (list, tuple)):
        value = bytes(int(v) & 0xFF for v in value).split(b"\0", 1)[0].decode("ascii", "replace")
    return str(value).rstrip("\0").strip()


def _version(text: str) -> tuple[int, int] | None:
    try:
        major, minor = text.split(".")[:2]
        return int(major), int(minor)
    except ValueError:
        return None
