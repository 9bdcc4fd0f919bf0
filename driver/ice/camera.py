"""JdeRobot's ``Camera`` served from any video source (webcam, file, stream, the simulated camera).

Each new frame is encoded once, on first request, and the same ``ImageData`` answers
every client until the next frame arrives: work per call is bounded whatever the
number of clients. ``getImageData`` is AMD in the Slice; it answers at once here.

Configuration (``MAVLinkServer.Camera.*``, prefix removed): ``Uri`` (and ``Uri.2``,
``Uri.3``… for ArDroneExtra.toggleCam), ``Loop`` (1 = loop files), ``Name``,
``RecordDir`` (where recordOnUsb(true) writes, default :func:`~driver.core.files.default_record_dir`),
``RecordMaxMB`` (the most one recording may hold, default 4000), ``RecordDirMaxMB`` (the most our
recordings in ``RecordDir`` may hold together, default 20000), ``TimeoutMs`` (how long
opening or reading a stream may hang, default 5000), ``StallMs`` (how long without a new frame
counts as a failure, default 2000), ``Width``/``Height`` (the simulated camera's, 640×480), ``LowLatency``
(0 opens a live stream with OpenCV's defaults: several decoder threads, for a companion computer too slow to
decode it on one; default 1).

recordOnUsb is a network call anyone who reaches the port can make, so what it can write is
bounded: files only in ``RecordDir``, named by us (date and the camera's ``Name``, reduced to
a plain name), each stopped cleanly at ``RecordMaxMB``, and none started once our recordings
there hold ``RecordDirMaxMB`` (a recording gets only the room left). At that cap recording is
refused with a warning rather than deleting the oldest recordings: a client could otherwise
erase earlier flights' videos by recording again and again; what to delete is the operator's call.
"""
from __future__ import annotations

import logging
import os
import re
import threading

import cv2

from ..vehicle.api import Drone
from ..camera import CameraSet, Frame, VideoRecorder, VideoSource
from ..camera.record import MIN_CAP_BYTES, recordings_size
from ..core.files import default_record_dir
from . import load_slice

jderobot, _ = load_slice()
log = logging.getLogger(__name__)

__all__ = ["CameraI", "SUPPORTED_FORMATS", "uris_from_config", "RECORD_MAX_MB", "RECORD_DIR_MAX_MB"]

SUPPORTED_FORMATS = ("RGB8", "GRAY8")
MB = 1_000_000
# One recording: under FAT32's 4 GiB file limit (a USB stick), and over 20 min even of worst-case
# video (random noise at 640×480, about 3.2 MB/s in mp4v): a copter's whole battery.
RECORD_MAX_MB = 4000
# All of them: five full recordings, which leaves most of a 32 GB card to the rest.
RECORD_DIR_MAX_MB = 20000


def uris_from_config(config: dict[str, str]) -> list[str]:
    """``Uri``, then ``Uri.2``, ``Uri.3``… in order."""
    uris = [config["Uri"].strip()] if config.get("Uri", "").strip() else []
    extra = sorted((k for k in config if k.startswith("Uri.") and k[4:].isdigit()), key=lambda k: int(k[4:]))
    return uris + [config[k].strip() for k in extra if config[k].strip()]


class CameraI(jderobot.Camera):
    """The ``Camera`` servant; ``toggle()`` and ``record(on)`` serve ArDroneExtra."""

    def __init__(self, config: dict[str, str], vehicle: Drone | None = None):
        uris = uris_from_config(config)
        if not uris:
            raise ValueError("no camera source configured (MAVLinkServer.Camera.Uri)")
        state_fn = vehicle.state if vehicle is not None else None
        self._name = config.get("Name", "") or "camera"
        # the file names are ours: the name reduced to letters, digits, _ and - (never a path)
        self._prefix = re.sub(r"[^A-Za-z0-9_-]+", "-", self._name).strip("-_") or "camera"
        record_dir = config.get("RecordDir", "").strip()     # "": the server's default, found when recording
        self._record_dir = os.path.abspath(record_dir) if record_dir else ""
        self._record_max = _cap_bytes(config, "RecordMaxMB", RECORD_MAX_MB)
        self._record_dir_max = _cap_bytes(config, "RecordDirMaxMB", RECORD_DIR_MAX_MB)
        options = dict(state_fn=state_fn, loop=config.get("Loop", "0").lower() in ("1", "true", "yes"))
        if config.get("TimeoutMs", "").strip().isdigit():
            options["timeout_ms"] = int(config["TimeoutMs"])
        if config.get("LowLatency", "").strip().lower() in ("0", "false", "no"):
            options["low_latency"] = False
        if config.get("StallMs", "").strip().isdigit():
            options["stall_s"] = int(config["StallMs"]) / 1000.0
        if config.get("Width", "").strip().isdigit() and config.get("Height", "").strip().isdigit():
            options["sim_size"] = (int(config["Width"]), int(config["Height"]))
        self._cameras = CameraSet(uris, **options)
        self._lock = threading.Lock()
        self._encoded: dict[str, tuple[int, VideoSource, object]] = {}   # format -> (frame index, source, ImageData)
        self._recorder: VideoRecorder | None = None

    @property
    def source(self) -> VideoSource:
        return self._cameras.source

    # -- ImageProvider ------------------------------------------------------------------------
    def getImageDescription(self, current=None):
        frame = self.source.latest()
        if frame is None:
            return jderobot.ImageDescription(0, 0, 0, "RGB8", "")
        return jderobot.ImageDescription(frame.width, frame.height, frame.width * frame.height * 3, "RGB8", "")

    def getImageFormat(self, current=None):
        return list(SUPPORTED_FORMATS)

    def getImageData(self, format, current=None):
        fmt = format or "RGB8"
        if fmt not in SUPPORTED_FORMATS:
            raise jderobot.DataNotExistException(
                f"image format {format!r} not supported; supported: {', '.join(SUPPORTED_FORMATS)}")
        source = self.source
        status = source.status()
        frame = source.latest()
        # still opening for the first time: no image yet; stalled, failed, ended or reopening after a failure: gone
        if status.state in ("stalled", "retrying", "ended", "closed") or \
                (status.state == "connecting" and status.attempts > 1):
            raise jderobot.HardwareFailedException(f"{source.description}: {status.reason or status.state}")
        if frame is None:
            raise jderobot.DataNotExistException(f"{source.description}: no image yet ({status.reason or status.state})")
        with self._lock:
            cached = self._encoded.get(fmt)
            if cached is not None and cached[0] == frame.index and cached[1] is source:
                return cached[2]
            data = self._encode(frame, fmt)
            self._encoded[fmt] = (frame.index, source, data)
            return data

    @staticmethod
    def _encode(frame: Frame, fmt: str):
        image = frame.image if fmt == "RGB8" else cv2.cvtColor(frame.image, cv2.COLOR_RGB2GRAY)
        pixels = image.tobytes()
        seconds = int(frame.wall_time)
        stamp = jderobot.Time(seconds, int((frame.wall_time - seconds) * 1e6))
        desc = jderobot.ImageDescription(frame.width, frame.height, len(pixels), fmt, "")
        return jderobot.ImageData(stamp, desc, pixels)

    # -- Camera -------------------------------------------------------------------------------
    def getCameraDescription(self, current=None):
        source = self.source
        frame = source.latest()
        short = source.description if frame is None else f"{source.description}, {frame.width}×{frame.height}"
        d = jderobot.CameraDescription(name=self._name, shortDescription=short, streamingUri=source.streaming_uri)
        camera = getattr(source, "camera", None)            # the simulated camera knows its optics
        if camera is not None:
            d.fdistx = d.fdisty = float(camera.focal)
            d.u0, d.v0 = float(camera.cx), float(camera.cy)
        return d

    def setCameraDescription(self, description, current=None):
        return -1                                           # the optics are not ours to change

    def startCameraStreaming(self, current=None):
        return self.source.streaming_uri

    def stopCameraStreaming(self, current=None):
        pass

    def reset(self, current=None):
        self.source.restart()

    # -- ArDroneExtra hooks -------------------------------------------------------------------
    def toggle(self) -> None:
        """Switch to the next configured source (ArDroneExtra.toggleCam)."""
        self._cameras.toggle()

    def record(self, on: bool) -> str:
        """Start or stop recording on the server (ArDroneExtra.recordOnUsb); returns the file
        ("" when none, or when refused because the directory's cap is reached)."""
        with self._lock:
            recorder = self._recorder
            if on and recorder is None:
                recorder = self._start_recording()
                if recorder is None:
                    return ""
                self._recorder = recorder
                self._cameras.add_listener(recorder.push)
                log.info("recording the camera to %s (at most %.0f MB)", recorder.path, recorder.max_bytes / MB)
                return recorder.path
            if not on and recorder is not None:
                self._recorder = None
            else:
                return recorder.path if recorder else ""
        self._cameras.remove_listener(recorder.push)
        path = recorder.stop()
        log.info("recording %s finished: %d frames", path, recorder.frames_written)
        return path

    def _start_recording(self) -> VideoRecorder | None:
        """A recorder with the room left under both caps, or None (with a warning) if too little is left."""
        if not self._record_dir:                            # make_camera_servant always sets it; a bare servant
            self._record_dir = os.path.abspath(default_record_dir())
        os.makedirs(self._record_dir, exist_ok=True)
        used = recordings_size(self._record_dir)
        room = min(self._record_max, self._record_dir_max - used)
        if room < MIN_CAP_BYTES:
            log.warning("recordOnUsb refused: our recordings in %s hold %.0f MB, and RecordDirMaxMB allows %.0f MB; "
                        "move or delete some to record again", self._record_dir, used / MB, self._record_dir_max / MB)
            return None
        if room < self._record_max:
            log.warning("recordOnUsb: %.0f MB left for recordings in %s (RecordDirMaxMB %.0f MB); "
                        "this recording stops there", room / MB, self._record_dir, self._record_dir_max / MB)
        return VideoRecorder.in_folder(self._record_dir, self._prefix, max_bytes=room, on_done=self._recording_ended)

    def _recording_ended(self, recorder: VideoRecorder) -> None:
        """On the recorder's thread, when it ends: if it stopped by itself (full, failed), let go of it."""
        with self._lock:
            if self._recorder is not recorder:
                return                                      # record(False) took it
            self._recorder = None
        self._cameras.remove_listener(recorder.push)
        why = "size cap reached" if recorder.full else recorder.error or "ended"
        log.warning("recording %s stopped (%s): %d frames; recordOnUsb(true) starts a new one",
                    recorder.path, why, recorder.frames_written)

    def close(self) -> None:
        self.record(False)
        self._cameras.close(wait=2.0)


def _cap_bytes(config: dict[str, str], key: str, default_mb: float) -> int:
    """``config[key]`` MB as bytes: the default when unset or not a positive number, at least MIN_CAP_BYTES."""
    text = config.get(key, "").strip()
    mb = default_mb
    if text:
        try:
            mb = float(text)
        except ValueError:
            mb = -1.0
        if not 0 < mb < float("inf"):
            log.warning("MAVLinkServer.Camera.%s=%s is not a positive number of MB; using %g", key, text, default_mb)
            mb = default_mb
    if mb * MB < MIN_CAP_BYTES:
        log.warning("MAVLinkServer.Camera.%s=%s is too small for a recording; using %.1f", key, text, MIN_CAP_BYTES / MB)
    return max(int(mb * MB), MIN_CAP_BYTES)
