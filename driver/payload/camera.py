"""The camera on the vehicle: pictures and video, confirmed by the camera itself.

Pictures: IMAGE_START_CAPTURE where CAMERA_INFORMATION says a MAVLink camera exists, the Solo's GoPro through
GOPRO_SET_REQUEST (component 154, one request at a time, as its shotmanager), else DO_DIGICAM_CONTROL. An ACK
never counts as a picture: only CAMERA_FEEDBACK, CAMERA_IMAGE_CAPTURED or the GoPro's answer do; video only
on CAMERA_CAPTURE_STATUS or the GoPro heartbeat's recording flag.

All methods run with the driver's state lock held unless they say otherwise; messages are returned or posted,
never written here.
"""
from __future__ import annotations

import time
from concurrent.futures import Future
from dataclasses import dataclass, replace

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core.ports import Clock, CommandPort, Outbox, Settler, StatePort
from ..core.results import CommandResult, CommandStatus
from .model import CameraKind, VehicleCamera

__all__ = ["CameraControl", "Wait", "CAMERA_MESSAGES", "CONFIRM_TIMEOUT", "GIMBAL_COMPONENT", "payload_problem"]

CAMERA_MESSAGES = frozenset({"CAMERA_INFORMATION", "CAMERA_FEEDBACK", "CAMERA_IMAGE_CAPTURED",
                             "CAMERA_CAPTURE_STATUS", "GOPRO_HEARTBEAT", "GOPRO_SET_RESPONSE"})
CONFIRM_TIMEOUT = 3.0        # s after the vehicle's ACK for the camera's own confirmation
GOPRO_WAIT = 1.0             # s the GoPro may take to answer one request before the next goes
GIMBAL_COMPONENT = mavlink.MAV_COMP_ID_GIMBAL        # 154: the Solo's gimbal and its GoPro


@dataclass(eq=False)
class Wait:
    """An action that resolves on the vehicle's own confirmation, not its ACK."""
    name: str
    kind: str                        # "photo", "record", "mount"
    future: Future
    want: object = None              # record: True/False; mount: the pitch wanted
    deadline: float | None = None    # set once the command is out (or ACKed)
    next_send: float = 0.0
    message = None                   # mount: the MOUNT_CONTROL to re-send
    photos_before: int = 0


def payload_problem(state, replaying: bool) -> str | None:
    """Why no payload command can go now (None when one can)."""
    if replaying:
        return "replaying a recording: no vehicle to command"
    if not state.connected:
        return "no vehicle connected"
    return None


class CameraControl:
    """The camera of one vehicle (part of :class:`~driver.payload.control.Payload`)."""

    def __init__(self, state: StatePort, outbox: Outbox, commands: CommandPort, settler: Settler, clock: Clock,
                 replaying: bool = False) -> None:
        self._store, self._outbox, self._commands, self._settler = state, outbox, commands, settler
        self._clock, self._replaying = clock, replaying
        self._waits: list[Wait] = []
        self._gopro_queue: list[tuple[int, int]] = []
        self._gopro_sent_at = -1e9
        self._gopro_busy: int | None = None
        self._gopro_mode: int | None = None      # the GoPro's capture mode (its heartbeat, or what we set)

    # -- what the camera says (reader thread) ------------------------------------------------------------------
    def on_message(self, m, component: int) -> None:
        getattr(self, "_on_" + m.get_type().lower())(m, component)

    def _camera(self) -> VehicleCamera:
        return self._store.view()["camera"]

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

    def _settle(self, w: Wait, status: CommandStatus, reason: str) -> None:
        if w in self._waits:
            self._waits.remove(w)
        self._settler.settle(w.future, self._store.record_locked(w.name, status, reason))

    # -- the ticker ------------------------------------------------------------------------------------------
    def service(self, now: float, system: int) -> list:
        """The GoPro's next request and the confirmations that did not come."""
        out = self._gopro_next(now, system)
        for w in list(self._waits):
            if w.deadline is not None and now >= w.deadline:
                self._settle(w, CommandStatus.TIMED_OUT, self._unconfirmed(w))
        return out

    @staticmethod
    def _unconfirmed(w: Wait) -> str:
        if w.kind == "photo":
            return ("the vehicle took the command but no camera confirmed a picture (no CAMERA_FEEDBACK or "
                    "CAMERA_IMAGE_CAPTURED): is a camera configured on it (CAM1_TYPE)?")
        return f"the camera did not say it {'started' if w.want else 'stopped'} recording"

    # -- the pilot's calls (any thread) ------------------------------------------------------------------------
    def take_photo(self) -> Future:
        state = self._store.state
        problem = payload_problem(state, self._replaying)
        if problem:
            return self._commands.answer("photo", CommandStatus.REJECTED, problem)
        cam = state.camera
        future: Future = Future()
        with self._store.lock:
            if any(w.kind == "photo" for w in self._waits):
                return self._commands.answer("photo", CommandStatus.REJECTED, "the last picture is not confirmed yet")
            w = Wait("photo", "photo", future, photos_before=cam.photos)
            self._waits.append(w)
            if cam.kind is CameraKind.GOPRO:
                if self._gopro_mode != mavlink.GOPRO_CAPTURE_MODE_PHOTO:
                    self._gopro_queue.append((mavlink.GOPRO_COMMAND_CAPTURE_MODE, mavlink.GOPRO_CAPTURE_MODE_PHOTO))
                self._gopro_queue.append((mavlink.GOPRO_COMMAND_SHUTTER, 1))
                w.deadline = self._clock() + CONFIRM_TIMEOUT + GOPRO_WAIT * len(self._gopro_queue)
                self._outbox.wake()
                return future
        if cam.kind is CameraKind.MAVLINK:
            inner = self._commands.long(mavlink.MAV_CMD_IMAGE_START_CAPTURE, (0, 0, 1, 0), "IMAGE_START_CAPTURE")
        else:
            inner = self._commands.long(mavlink.MAV_CMD_DO_DIGICAM_CONTROL, (0, 0, 0, 0, 1, 0, 0),
                                        "DO_DIGICAM_CONTROL shoot")
        inner.add_done_callback(lambda f: self._acked(w, f.result()))
        return future

    def _acked(self, w: Wait, result: CommandResult) -> None:
        """The vehicle answered the trigger: a refusal ends it, an acceptance waits for the camera (any thread)."""
        with self._store.lock:
            if w not in self._waits:
                return
            if not result.ok:
                self._settle(w, result.status, result.reason)
            else:
                w.deadline = self._clock() + CONFIRM_TIMEOUT

    def record_video(self, on: bool) -> Future:
        name = f"record {'on' if on else 'off'}"
        state = self._store.state
        problem = payload_problem(state, self._replaying)
        if problem:
            return self._commands.answer(name, CommandStatus.REJECTED, problem)
        cam = state.camera
        if cam.kind is CameraKind.UNKNOWN or (cam.kind is CameraKind.MAVLINK and not cam.can_record):
            return self._commands.answer(name, CommandStatus.REJECTED,
                                  "no camera on the vehicle says it records video (no CAMERA_INFORMATION with video, "
                                  "no GoPro); DO_DIGICAM_CONTROL only takes pictures")
        future: Future = Future()
        with self._store.lock:
            for old in [x for x in self._waits if x.kind == "record"]:
                self._settle(old, CommandStatus.ABORTED, f"superseded by {name}")
            w = Wait(name, "record", future, want=on)
            self._waits.append(w)
            if cam.kind is CameraKind.GOPRO:
                if on and self._gopro_mode != mavlink.GOPRO_CAPTURE_MODE_VIDEO:
                    self._gopro_queue.append((mavlink.GOPRO_COMMAND_CAPTURE_MODE, mavlink.GOPRO_CAPTURE_MODE_VIDEO))
                self._gopro_queue.append((mavlink.GOPRO_COMMAND_SHUTTER, 1 if on else 0))
                w.deadline = self._clock() + CONFIRM_TIMEOUT + GOPRO_WAIT * len(self._gopro_queue)
                self._outbox.wake()
                return future
        command = mavlink.MAV_CMD_VIDEO_START_CAPTURE if on else mavlink.MAV_CMD_VIDEO_STOP_CAPTURE
        inner = self._commands.long(command, (0, 0), "VIDEO_START_CAPTURE" if on else "VIDEO_STOP_CAPTURE")
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


def _text(value) -> str:
    if isinstance(value, (bytes, bytearray)):
        value = bytes(value).split(b"\0", 1)[0].decode("ascii", "replace")
    elif isinstance(value, (list, tuple)):
        value = bytes(int(v) & 0xFF for v in value).split(b"\0", 1)[0].decode("ascii", "replace")
    return str(value).rstrip("\0").strip()

