"""The payload part of the embedded driver: point the gimbal, look at a point, take pictures and video.

Which protocol, decided from what the vehicle has shown and what its firmware profile
(:class:`driver.core.firmware.FirmwareProfile`) learnt, its UNSUPPORTED answers among them:

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
Pictures and video: the camera's part (driver.payload.camera), which this one owns.

All methods run with the driver's state lock held unless they say otherwise; messages are returned or posted,
never written here. The part is handed the ports it uses (driver.core.ports), never the vehicle.
"""
from __future__ import annotations

import logging
import time
from concurrent.futures import Future
from dataclasses import replace

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core import frames
from ..core.firmware import FirmwareProfile
from ..core.ports import Clock, CommandPort, Outbox, Settler, StatePort
from ..core.results import CommandResult, CommandStatus, Severity, chain
from .camera import CAMERA_MESSAGES, CONFIRM_TIMEOUT, CameraControl, Wait, payload_problem
from .model import (
    GIMBAL_PITCH_RANGE, RETRACT_FLAG, YAW_IN_EARTH_FRAME, Gimbal, GimbalControl, gimbal_from_quaternion,
)

log = logging.getLogger(__name__)

__all__ = ["Payload", "PAYLOAD_MESSAGES", "CONFIRM_TIMEOUT", "MAX_GIMBAL_RATE"]

PAYLOAD_MESSAGES = frozenset({
    "GIMBAL_DEVICE_ATTITUDE_STATUS", "MOUNT_STATUS", "GIMBAL_MANAGER_INFORMATION", "GIMBAL_MANAGER_STATUS"}
) | CAMERA_MESSAGES
MOUNT_TOLERANCE = 3.0        # deg: MOUNT_STATUS this close to the target confirms a MOUNT_CONTROL
MOUNT_RESEND = 1.0           # s between MOUNT_CONTROL messages while MOUNT_STATUS has not shown the angle
STEP_INTERVAL = 0.1          # s between stepped angles of a rate on mounts without rates
MAX_GIMBAL_RATE = 90.0       # deg/s
ATTITUDE_RATE_HZ = 5         # GIMBAL_DEVICE_ATTITUDE_STATUS, as the recording's GCS asked
MANAGER = "gimbal manager"
MOUNT_CMD = "DO_MOUNT_CONTROL"
MOUNT_MSG = "MOUNT_CONTROL"


class Payload:
    """Gimbal, ROI and camera of one vehicle; owned by :class:`driver.vehicle.vehicle.Vehicle`."""

    def __init__(self, state: StatePort, outbox: Outbox, commands: CommandPort, settler: Settler, clock: Clock,
                 firmware: FirmwareProfile, replaying: bool = False) -> None:
        self._store, self._outbox, self._commands, self._settler = state, outbox, commands, settler
        self._clock, self._firmware, self._replaying = clock, firmware, replaying
        self._manager: bool | None = None        # a gimbal manager was heard (None: not known)
        self._asked_at: float | None = None      # when the gimbal/camera information was asked for
        self._waits: list[Wait] = []
        self._rate: tuple[float, float] | None = None      # stepped rate (deg/s pitch, yaw)
        self._rate_target: tuple[float, float] = (0.0, 0.0)
        self._rate_last = 0.0
        self.camera = CameraControl(state, outbox, commands, settler, clock, replaying)   # pictures and video

    # -- what the vehicle says (reader thread) ---------------------------------------------------------
    def on_message(self, m) -> None:
        """From any component of the vehicle (the gimbal, the camera, the autopilot): into the pending fields; the
        reader publishes them with the telemetry it folds (not here: publishing would hold the telemetry fold back,
        and the newest-of-each-kind would lose a message)."""
        mtype, component = m.get_type(), m.get_header().srcComponent
        if mtype in CAMERA_MESSAGES:
            self.camera.on_message(m, component)
        else:
            getattr(self, "_on_" + mtype.lower())(m, component)

    def _gimbal(self) -> Gimbal:
        return self._store.view()["gimbal"]

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

    def _settle(self, w: Wait, status: CommandStatus, reason: str) -> None:
        if w in self._waits:
            self._waits.remove(w)
        self._settler.settle(w.future, self._store.record_locked(w.name, status, reason))

    def _autopilot(self) -> int:
        return self._outbox.target()[1]

    # -- the ticker ----------------------------------------------------------------------------------------
    def service(self, now: float, state) -> list:
        """Requests, stepped rates, GoPro queue and confirmation timeouts; returns messages to send."""
        out: list = []
        if not state.connected or self._replaying:
            self._asked_at = None if not state.connected else self._asked_at
            return out
        system, component = self._outbox.target()
        if self._asked_at is None:
            self._asked_at = now
            fw = self._firmware
            if fw.payload_commands and fw.knows(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL) is not False:
                out.append(mavlink.MAVLink_command_long_message(
                    system, component, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                    mavlink.MAVLINK_MSG_ID_GIMBAL_DEVICE_ATTITUDE_STATUS, 1e6 / ATTITUDE_RATE_HZ, 0, 0, 0, 0, 0))
                for msg_id in (mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION,
                               mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_INFORMATION):
                    out.append(mavlink.MAVLink_command_long_message(
                        system, component, mavlink.MAV_CMD_REQUEST_MESSAGE, 0, msg_id, 0, 0, 0, 0, 0, 0))
        if self._rate is not None and now - self._rate_last >= STEP_INTERVAL:
            out += self._step_rate(now, state)
        out += self.camera.service(now, system)
        for w in list(self._waits):
            if now >= w.next_send and w.message is not None:
                out.append(w.message)
                w.next_send = now + MOUNT_RESEND
            if w.deadline is not None and now >= w.deadline:
                self._settle(w, CommandStatus.TIMED_OUT, self._unconfirmed(state))
        return out

    @staticmethod
    def _unconfirmed(state) -> str:
        shown = state.gimbal.pitch_deg
        return (f"MOUNT_STATUS still shows {shown:.0f}°" if shown is not None else
                "the vehicle sent no MOUNT_STATUS") + f" after {CONFIRM_TIMEOUT:g} s"

    # -- helpers --------------------------------------------------------------------------------------------
    def protocol(self, state) -> str:
        fw = self._firmware
        if not fw.payload_commands or fw.knows(mavlink.MAV_CMD_DO_MOUNT_CONTROL) is False:
            return MOUNT_MSG
        if fw.knows(mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW) is False:
            return MOUNT_CMD
        if self._manager or state.gimbal.source != "MOUNT_STATUS":
            return MANAGER
        return MOUNT_CMD

    def _answered(self, name: str, status: CommandStatus, reason: str) -> Future:
        return self._commands.answer(name, status, reason)

    def _roi_by_location(self) -> bool:
        """DO_SET_ROI_LOCATION (else the Solo's DO_SET_ROI, whose zeros stop it)."""
        fw = self._firmware
        return fw.payload_commands and fw.knows(mavlink.MAV_CMD_DO_SET_ROI_LOCATION) is not False

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
        state = self._store.state
        problem = self._problem(state)
        if problem:
            return self._answered(name, CommandStatus.REJECTED, problem)
        with self._store.lock:
            self._rate = None
        return self._point_by(self.protocol(state), name, pitch, yaw)

    def _point_by(self, protocol: str, name: str, pitch: float, yaw: float | None) -> Future:
        if protocol == MANAGER:
            inner = self._commands.long(mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
                                          (pitch, yaw or 0.0, 0, 0, 0, 0, 0), f"{name} (DO_GIMBAL_MANAGER_PITCHYAW)")
            return chain(inner, lambda r: self._pointed(r, name, pitch, yaw, GimbalControl.ANGLE, MANAGER), name)
        if protocol == MOUNT_CMD:
            inner = self._commands.long(mavlink.MAV_CMD_DO_MOUNT_CONTROL,
                                          (pitch, 0, yaw or 0.0, 0, 0, 0, mavlink.MAV_MOUNT_MODE_MAVLINK_TARGETING),
                                          f"{name} (DO_MOUNT_CONTROL)")
            return chain(inner, lambda r: self._pointed(r, name, pitch, yaw, GimbalControl.ANGLE, MOUNT_CMD), name)
        return self._mount_message(name, pitch, yaw)

    def _pointed(self, result: CommandResult, name: str, pitch, yaw, control: GimbalControl, protocol: str):
        if self._unsupported(result):           # (the firmware profile learnt it from the answer)
            with self._store.lock:
                self._store.add_message_locked(Severity.NOTICE, f"The vehicle does not know {protocol}: "
                                               f"pointing its gimbal with {self.protocol(self._store.state)}")
            return self._point_by(self.protocol(self._store.state), name, pitch, yaw)
        with self._store.lock:
            if result.ok:
                g = self._gimbal()
                self._store.set(gimbal=replace(g, control=control, protocol=protocol, roi=None))
                self._store.publish()
            return result                       # its own record says what went out and what came back

    def _mount_message(self, name: str, pitch: float, yaw: float | None) -> Future:
        """The Solo: MOUNT_CONFIGURE to MAVLink targeting, then MOUNT_CONTROL until MOUNT_STATUS shows it."""
        system, component = self._outbox.target()
        future: Future = Future()
        with self._store.lock:
            for w in [w for w in self._waits if w.kind == "mount"]:
                self._settle(w, CommandStatus.ABORTED, f"superseded by {name}")
            self._outbox.post(mavlink.MAVLink_mount_configure_message(
                system, component, mavlink.MAV_MOUNT_MODE_MAVLINK_TARGETING, 1, 1, 0))
            w = Wait(name, "mount", future, want=pitch, deadline=self._clock() + CONFIRM_TIMEOUT)
            w.message = self._mount_control(pitch, yaw)
            self._waits.append(w)
            g = self._gimbal()
            self._store.set(gimbal=replace(g, control=GimbalControl.ANGLE, protocol=MOUNT_MSG, roi=None))
            self._store.publish()
        self._outbox.wake()
        return future

    def _mount_control(self, pitch: float, yaw: float | None):
        system, component = self._outbox.target()
        return mavlink.MAVLink_mount_control_message(system, component, int(round(pitch * 100)), 0,
                                                     int(round((yaw or 0.0) * 100)), 0)

    def rate(self, pitch_rate: float, yaw_rate: float = 0.0) -> Future:
        name = f"gimbal rate {pitch_rate:+g}°/s" + (f" yaw {yaw_rate:+g}°/s" if yaw_rate else "")
        if not frames.finite(pitch_rate, yaw_rate):
            return self._answered("gimbal rate", CommandStatus.REJECTED, "rate is not a finite number")
        pitch_rate = min(max(float(pitch_rate), -MAX_GIMBAL_RATE), MAX_GIMBAL_RATE)
        yaw_rate = min(max(float(yaw_rate), -MAX_GIMBAL_RATE), MAX_GIMBAL_RATE)
        state = self._store.state
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
                    self._rate_last = self._clock()
                self._rate = (pitch_rate, yaw_rate)
                self._store.set(gimbal=replace(self._gimbal(), control=GimbalControl.RATE, protocol=protocol))
            self._outbox.wake()
            return self._commands.answer(name, CommandStatus.ACCEPTED,
                                         f"stepping the {protocol} angle every {STEP_INTERVAL:g} s")

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
        system, component = self._outbox.target()
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
        state = self._store.state
        problem = self._problem(state)
        if problem:
            return self._answered(name, CommandStatus.REJECTED, problem)
        with self._store.lock:
            self._rate = None
        by_location = self._roi_by_location()
        if not by_location:
            inner = self._commands.long(mavlink.MAV_CMD_DO_SET_ROI, (0, 0, 0, 0, lat, lon, alt),
                                        f"{name} (DO_SET_ROI)")
        else:
            inner = self._commands.long(mavlink.MAV_CMD_DO_SET_ROI_LOCATION, (0, 0, 0, 0, lat, lon, alt),
                                        f"{name} (DO_SET_ROI_LOCATION)")

        def done(r: CommandResult):
            if self._unsupported(r) and by_location:   # the profile knows it now: DO_SET_ROI next
                return self.look_at(lat, lon, alt)
            with self._store.lock:
                if r.ok:
                    self._store.set(gimbal=replace(self._gimbal(), control=GimbalControl.ROI, roi=(lat, lon, alt)))
                    self._store.publish()
                return r
        return chain(inner, done, name)

    def stop_looking(self) -> Future:
        name = "stop looking (ROI none)"
        state = self._store.state
        problem = self._problem(state)
        if problem:
            return self._answered(name, CommandStatus.REJECTED, problem)
        if not self._roi_by_location():
            inner = self._commands.long(mavlink.MAV_CMD_DO_SET_ROI, (0, 0, 0, 0, 0, 0, 0), f"{name} (DO_SET_ROI 0)")
        else:
            inner = self._commands.long(mavlink.MAV_CMD_DO_SET_ROI_NONE, (0,), f"{name} (DO_SET_ROI_NONE)")

        def done(r: CommandResult):
            with self._store.lock:
                if r.ok:      # the mount goes back to its default mode (the recording: RC targeting)
                    self._store.set(gimbal=replace(self._gimbal(), control=GimbalControl.RC, roi=None))
                    self._store.publish()
                return r
        return chain(inner, done, name)

    def _problem(self, state) -> str | None:
        return payload_problem(state, self._replaying)

    # -- the camera (driver.payload.camera) --------------------------------------------------------------------
    def take_photo(self) -> Future:
        return self.camera.take_photo()

    def record_video(self, on: bool) -> Future:
        return self.camera.record_video(on)

