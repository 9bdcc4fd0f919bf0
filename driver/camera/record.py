"""Snapshots (PNG) and recordings (MP4, mp4v) of the video, named by date.

The recorder encodes on its own thread from a short queue, so neither the capture
thread nor the viewer waits for the encoder; if the encoder falls behind, frames
are dropped and counted rather than piling up. The file's frame rate is the source's
own, measured from the first second of frames (held back until then), so a recording
plays at the speed it was filmed.
"""
from __future__ import annotations

import datetime
import logging
import os
import queue
import threading

import cv2
import numpy as np

from .source import Frame

log = logging.getLogger(__name__)

__all__ = ["VideoRecorder", "save_snapshot", "dated_path"]


def dated_path(folder: str, prefix: str, ext: str, when: float | None = None) -> str:
    """``folder/prefix-YYYYmmdd-HHMMSS-mmm.ext``, creating the folder."""
    os.makedirs(folder, exist_ok=True)
    t = datetime.datetime.fromtimestamp(when) if when is not None else datetime.datetime.now()
    return os.path.join(folder, f"{prefix}-{t:%Y%m%d-%H%M%S}-{t.microsecond // 1000:03d}.{ext}")


def save_snapshot(frame: Frame, folder: str, prefix: str = "snapshot") -> str:
    """Write ``frame`` as PNG and return its path (raises OSError when it cannot)."""
    path = dated_path(folder, prefix, "png", frame.wall_time)
    if not cv2.imwrite(path, cv2.cvtColor(frame.image, cv2.COLOR_RGB2BGR)):
        raise OSError(f"cannot write {path}")
    return path


FALLBACK_FPS = 30.0             # a recording too short to measure its rate
MEASURE_S = 1.0                 # how much video tells the frame rate
MEASURE_FRAMES = 32             # ... or how many frames, whichever comes first (bounds the memory held)


class VideoRecorder:
    """Records frames handed to :meth:`push` into ``path`` (MP4, mp4v).

    ``fps`` fixes the file's frame rate; None (the default) measures it from the frames.
    """

    def __init__(self, path: str, fps: float | None = None, fourcc: str = "mp4v", max_queue: int = 8):
        self.path = path
        self.fps = fps
        self.frames_written = 0
        self.frames_dropped = 0
        self.error = ""
        self._fourcc = fourcc
        self._queue: queue.Queue[Frame | None] = queue.Queue(max_queue)
        self._writer: cv2.VideoWriter | None = None
        self._size: tuple[int, int] | None = None
        self._last_index = 0
        self._thread = threading.Thread(target=self._run, name="video recorder", daemon=True)
        self._thread.start()

    @classmethod
    def in_folder(cls, folder: str, prefix: str = "video", fps: float | None = None) -> "VideoRecorder":
        return cls(dated_path(folder, prefix, "mp4"), fps)

    @property
    def recording(self) -> bool:
        return self._thread.is_alive() and not self.error

    def push(self, frame: Frame) -> None:
        """Queue a frame (any thread); never blocks. The same frame twice is written once."""
        if frame.index == self._last_index:
            return
        self._last_index = frame.index
        try:
            self._queue.put_nowait(frame)
        except queue.Full:
            self.frames_dropped += 1

    def stop(self, wait: float = 5.0) -> str:
        """Finish the file and return its path; waits for the encoder up to ``wait`` s."""
        while True:
            try:
                self._queue.put(None, timeout=0.05)
                break
            except queue.Full:
                if not self._thread.is_alive():
                    break
        self._thread.join(wait)
        return self.path

    def _run(self) -> None:
        held: list[Frame] = []            # the first frames, until they tell the frame rate
        try:
            while True:
                frame = self._queue.get()
                if frame is None:
                    break
                if self._writer is None:
                    held.append(frame)
                    if self.fps is None and not _enough_to_measure(held):
                        continue
                    self._write_all(held)
                else:
                    self._write(frame)
            self._write_all(held)
        except Exception as e:
            log.exception("recording %s failed", self.path)
            self.error = str(e)
        finally:
            if self._writer is not None:
                self._writer.release()

    def _write_all(self, held: list[Frame]) -> None:
        if held and self.fps is None:
            self.fps = measured_fps(held)
            log.info("recording %s at %.2f frames/s", self.path, self.fps)
        for frame in held:
            self._write(frame)
        held.clear()

    def _write(self, frame: Frame) -> None:
        size = (frame.width, frame.height)
        if self._writer is None:
            self._writer = cv2.VideoWriter(self.path, cv2.CAP_FFMPEG, cv2.VideoWriter_fourcc(*self._fourcc),
                                           self.fps, size)
            if not self._writer.isOpened():
                raise OSError(f"cannot record to {self.path}")
            self._size = size
        image = frame.image
        if size != self._size:      # the source changed resolution: keep the file's
            image = cv2.resize(image, self._size, interpolation=cv2.INTER_AREA)
        self._writer.write(cv2.cvtColor(np.ascontiguousarray(image), cv2.COLOR_RGB2BGR))
        self.frames_written += 1


def _enough_to_measure(frames: list[Frame]) -> bool:
    return len(frames) >= MEASURE_FRAMES or frames[-1].decoded - frames[0].decoded >= MEASURE_S


def measured_fps(frames: list[Frame]) -> float:
    """The source's frame rate from decode times; source frame numbers count the ones not recorded.

    A rate within 2 % of a whole number is taken as that number (29.97 → 30).
    """
    span = frames[-1].decoded - frames[0].decoded
    count = frames[-1].index - frames[0].index
    if count <= 0:                       # the source changed (its numbering restarted)
        count = len(frames) - 1
    if count <= 0 or span <= 0:
        return FALLBACK_FPS
    fps = count / span
    if not 1.0 <= fps <= 240.0:
        return FALLBACK_FPS
    whole = round(fps)
    return float(whole) if abs(fps - whole) <= 0.02 * whole else round(fps, 2)
