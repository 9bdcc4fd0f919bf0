"""Brings the newest video frame to the camera panel and carries out snapshot, record and switch.

Capture and decoding run on the source's own thread (driver.camera). A new frame
wakes the UI thread through a queued signal, at most one outstanding at a time, so a
slow paint never builds a queue: the UI simply takes the newest frame when it gets
there. A timer also looks every ~16 ms, for the HUD and for a source that has
stopped (the "No video" message).
"""
from __future__ import annotations

import logging
import os
import statistics
import time
from collections import deque
from concurrent.futures import Future
from typing import Callable

from PyQt5.QtCore import QObject, QStandardPaths, Qt, QTimer, pyqtSignal

import driver.ice.camera_source  # noqa: F401  (registers ice: cameras)
from driver.vehicle.api import Drone
from driver.camera import CameraSet, VideoRecorder, describe_uri, save_snapshot
from driver.vehicle.state import CommandResult, CommandStatus, VehicleState

from .panel import CameraPanel

__all__ = ["CameraController", "default_media_folder"]

log = logging.getLogger(__name__)
NO_CAMERA = "No video: no camera configured (--camera URI, or Settings > Preferences)"


def default_media_folder() -> str:
    base = QStandardPaths.writableLocation(QStandardPaths.MoviesLocation) or os.path.expanduser("~")
    return os.path.join(base, "UavViewer")


class CameraController(QObject):
    sourceChanged = pyqtSignal(str)            # the URI now shown
    snapshotSaved = pyqtSignal(str)            # PNG path
    recordingChanged = pyqtSignal(bool, str)   # recording?, file
    failed = pyqtSignal(str)                   # a snapshot or recording that could not happen, and why
    switchAnswered = pyqtSignal(object)        # the vehicle's CommandResult for a camera switch, on the UI thread
    _frameArrived = pyqtSignal()               # emitted on the capture thread, delivered queued
    _switchDone = pyqtSignal(object)           # a toggle_camera Future, emitted on a driver thread, delivered queued

    def __init__(self, panel: CameraPanel, uris: list[str], *, state_fn: Callable[[], VehicleState] | None = None,
                 drone: Callable[[], Drone] | None = None, folder: str | None = None, rate_hz: float = 30.0,
                 parent: QObject | None = None,
                 **source_options) -> None:
        """``source_options`` go to :func:`driver.camera.open_source` (loop, timeout_ms, image_format); ``drone``
        says which vehicle to ask for its next camera (the one flown now: in a fleet it changes)."""
        super().__init__(parent)
        self.panel = panel
        self.view = panel.view
        self.folder = folder or default_media_folder()
        self._state_fn = state_fn
        self._drone = drone
        self._open_options = dict(source_options, state_fn=state_fn)
        self._cameras = CameraSet(uris, **self._open_options) if uris else None
        self._wake_pending = False
        self._shown = True                      # whether the pilot can see the window (not minimised)
        self._frameArrived.connect(self._on_frame_arrived, Qt.QueuedConnection)
        self._switchDone.connect(self._on_switch_done, Qt.QueuedConnection)
        if self._cameras is not None:
            self._cameras.add_listener(self._wake)
        self._shown_index = 0
        self._shown_source = None
        self._recorder: VideoRecorder | None = None
        self._record_started = 0.0
        self._painted: deque[float] = deque(maxlen=240)       # paint times, for frames/s
        self._latency: deque[float] = deque(maxlen=240)       # decode-to-paint, seconds
        self._timer = QTimer(self)
        self._timer.setInterval(max(1, int(1000 / rate_hz)))
        self._timer.timeout.connect(self.poll)
        self._stats_timer = QTimer(self)
        self._stats_timer.setInterval(500)
        self._stats_timer.timeout.connect(self._update_stats)
        self.view.framePainted.connect(self._on_painted)
        panel.hudToggled.connect(self.view.set_hud_visible)
        panel.snapshotRequested.connect(self.snapshot)
        panel.recordToggled.connect(self.set_recording)
        panel.switchRequested.connect(self.switch)
        panel.set_switch_enabled(self._can_switch())
        if self._cameras is None:
            self.view.set_message(NO_CAMERA)
        self._timer.start()
        self._stats_timer.start()

    # -- reading -----------------------------------------------------------------------------
    @property
    def source(self):
        return self._cameras.source if self._cameras else None

    def set_shown(self, shown: bool) -> None:
        """Whether the pilot can see the video (the window is not minimised). While not, nothing is painted and
        the source is closed, so nothing is decoded either, unless it is recording (then it keeps capturing).
        Back, the source opens again and its newest picture is shown."""
        self._shown = shown
        if self._cameras is not None:
            if not shown and self._recorder is None:
                self._cameras.suspend()
            elif shown and self._cameras.suspended:
                self._cameras.resume()
                self._shown_index, self._shown_source = 0, None
        if shown:
            self.poll()

    def poll(self) -> None:
        """Show the newest frame if it is new, or why there is none; refresh the HUD."""
        if not self._shown:
            return
        if self._state_fn is not None:
            try:
                self.view.set_state(self._state_fn())
            except Exception:                 # noqa: BLE001 - a remote drone may fail; the video goes on
                log.debug("no vehicle state for the HUD", exc_info=True)
        source = self.source
        if source is None:
            return
        status = source.status()
        frame = source.latest()
        if (status.state == "connecting" and status.attempts <= 1) or (status.live and frame is None):
            self.view.set_message(f"Connecting to {source.description}…")
        elif not status.live:
            self.view.set_message(f"No video: {status.reason or status.state}")
        elif frame.index != self._shown_index or source is not self._shown_source:
            self._shown_index, self._shown_source = frame.index, source
            self.view.set_frame(frame)

    def _wake(self, frame) -> None:
        """Capture thread: ask the UI thread to look, unless it has not looked since the last ask (or nobody sees)."""
        if self._shown and not self._wake_pending:
            self._wake_pending = True
            self._frameArrived.emit()

    def _on_frame_arrived(self) -> None:
        self._wake_pending = False
        self.poll()

    def _on_painted(self, index: int, latency: float) -> None:
        self._painted.append(time.monotonic())
        self._latency.append(latency)

    def stats(self) -> dict:
        """Frames painted per second over the last second, resolution, latency median/p95 (s), dropped."""
        now = time.monotonic()
        recent = [t for t in self._painted if now - t <= 1.0]
        lat = sorted(self._latency)
        frame = self.view.frame()
        status = self.source.status() if self.source else None
        return {
            "fps": float(len(recent)),
            "resolution": (frame.width, frame.height) if frame else None,
            "latency_median": statistics.median(lat) if lat else None,
            "latency_p95": lat[min(len(lat) - 1, int(0.95 * len(lat)))] if lat else None,
            "dropped": status.dropped if status else 0,
            "frames": status.frames if status else 0,
        }

    def _update_stats(self) -> None:
        if self._recorder is not None and self._recorder.error:     # the encoder gave up on its thread
            self.set_recording(False)
        if not self._shown:
            return
        s = self.stats()
        if s["resolution"] is None:
            self.view.set_stats("")
        else:
            w, h = s["resolution"]
            latency = "--" if s["latency_median"] is None else f"{s['latency_median'] * 1000:.0f}"
            self.view.set_stats(f"{s['fps']:.0f} fps · {w}×{h} · {latency} ms · {s['dropped']} dropped")
        if self._recorder is not None:
            seconds = int(time.monotonic() - self._record_started)
            self.view.set_recording(f"REC {seconds // 60:02d}:{seconds % 60:02d}")

    # -- pilot's intents -----------------------------------------------------------------------
    def snapshot(self) -> str | None:
        """Save the picture on screen as PNG; returns the path (None, with ``failed``, if none)."""
        frame = self.view.frame() or (self.source.latest() if self.source else None)
        if frame is None:
            return self._fail("No snapshot: no video")
        try:
            path = save_snapshot(frame, self.folder)
        except OSError as e:
            return self._fail(f"No snapshot: {e}")
        self.panel.set_note(f"Saved {path}")
        self.snapshotSaved.emit(path)
        return path

    @property
    def recording(self) -> bool:
        return self._recorder is not None

    def set_recording(self, on: bool) -> str | None:
        """Start or stop recording every captured frame to a dated MP4 in the folder."""
        if on and self._recorder is None:
            if self._cameras is None:
                self.panel.set_recording(False)
                return self._fail("Cannot record: no camera")
            try:
                recorder = VideoRecorder.in_folder(self.folder, "video")     # at the source's own frame rate
            except OSError as e:
                self.panel.set_recording(False)
                return self._fail(f"Cannot record: {e}")
            self._recorder, self._record_started = recorder, time.monotonic()
            self._cameras.add_listener(recorder.push)
            if self._cameras.suspended:                 # recording needs the frames, seen or not
                self._cameras.resume()
            self.panel.set_note(f"Recording {recorder.path}")
        elif not on and self._recorder is not None:
            recorder, self._recorder = self._recorder, None
            self._cameras.remove_listener(recorder.push)
            recorder.stop()
            if not self._shown:
                self._cameras.suspend()                 # nobody watches and nothing records any more
            self.view.set_recording("")
            if recorder.error:
                self._fail(f"Cannot record: {recorder.error}")
            elif not recorder.frames_written or not os.path.isfile(recorder.path):
                status = self._cameras.source.status() if self._cameras is not None else None
                why = status.reason if status is not None and status.reason else "the camera gave no frames"
                self._fail(f"Nothing recorded: {why}")          # no file was left behind
            else:
                self.panel.set_note(f"Recorded {recorder.path} ({recorder.frames_written} frames)")
        else:
            return self._recorder.path if self._recorder else None
        self.panel.set_recording(on)
        self.recordingChanged.emit(on, recorder.path)
        return recorder.path

    def switch(self) -> None:
        """The next camera: the remote vehicle's own toggle when video comes from its server,
        else the next configured source."""
        if self._remote_source():
            if self._drone is None:
                self.panel.set_note("Cannot switch camera: no vehicle to ask")
                return
            try:
                future = self._drone().toggle_camera()
            except Exception as exc:          # noqa: BLE001 - a remote drone may fail; the video goes on
                log.exception("toggle_camera failed to start")
                future = Future()
                future.set_result(CommandResult("switch camera", CommandStatus.REJECTED, str(exc)))
            self.panel.set_note("Asking the vehicle to switch camera…")
            future.add_done_callback(self._switchDone.emit)
            return
        if self._cameras is None or len(self._cameras.uris) < 2:
            return
        source = self._cameras.toggle()
        self._shown_index, self._shown_source = 0, None
        self.view.set_message(f"Connecting to {source.description}…")
        self.panel.set_note(f"Camera: {describe_uri(source.uri)}")
        self.sourceChanged.emit(source.uri)

    def _on_switch_done(self, future: Future) -> None:
        try:
            result = future.result(timeout=0)
        except Exception as exc:              # noqa: BLE001
            result = CommandResult("switch camera", CommandStatus.REJECTED, f"{type(exc).__name__}: {exc}")
        if result.ok:
            self.panel.set_note("Camera: the vehicle switched to its next camera")
        else:
            self.panel.set_note(f"Cannot switch camera: {result.reason or result.status.value}")
        self.switchAnswered.emit(result)

    def _remote_source(self) -> bool:
        """The video comes from the vehicle's own server, which switches it (JdeRobot's Extra.toggleCam)."""
        source = self.source
        return source is not None and source.uri.startswith("ice:")

    def _can_switch(self) -> bool:
        return bool(self._cameras and (len(self._cameras.uris) > 1 or self._remote_source()))

    @property
    def uris(self) -> list[str]:
        return list(self._cameras.uris) if self._cameras else []

    def set_sources(self, uris: list[str]) -> None:
        """Close the camera shown and open these sources instead (Preferences); recording stops."""
        if self._recorder is not None:
            self.set_recording(False)
        if self._cameras is not None:
            self._cameras.remove_listener(self._wake)
            self._cameras.close()
        self._cameras = CameraSet(list(uris), **self._open_options) if uris else None
        self._shown_index, self._shown_source = 0, None
        if self._cameras is not None and not self._shown:
            self._cameras.suspend()
        self.panel.set_switch_enabled(self._can_switch())
        if self._cameras is None:
            self.view.set_message(NO_CAMERA)
            return
        self._cameras.add_listener(self._wake)
        self.view.set_message(f"Connecting to {self._cameras.source.description}…")
        self.sourceChanged.emit(self._cameras.source.uri)

    def _fail(self, reason: str) -> None:
        self.panel.set_note(reason)
        self.failed.emit(reason)
        return None

    def close(self, wait: float = 0.0) -> None:
        """Stop polling, finish any recording, release the source (waiting at most ``wait`` s for it)."""
        self._timer.stop()
        self._stats_timer.stop()
        if self._recorder is not None:
            self.set_recording(False)
        if self._cameras is not None:
            self._cameras.remove_listener(self._wake)
            self._cameras.close(wait)
