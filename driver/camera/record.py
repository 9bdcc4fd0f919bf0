"""Snapshots (PNG) and recordings (MP4, mp4v) of the video, named by date.

The recorder encodes on its own thread from a short queue, so neither the capture
thread nor the viewer waits for the encoder; if the encoder falls behind, frames
are dropped and counted rather than piling up. The file's frame rate is the source's
own, measured from the first second of frames (held back until then), so a recording
plays at the speed it was filmed.

Files are made so that another user who can write to the folder cannot turn them against
us (see :mod:`driver.core.files`): a snapshot or a recording's name is created new (O_EXCL,
never through a planted link, never over an existing file; the next free name is taken
instead). OpenCV's encoder opens its file by name, and would follow a link or truncate a
file, so it writes into a directory only we can enter (``.recording-XXXXXXXX`` in the same
folder); the finished file is then renamed over the name we reserved. A recording may be
given a size cap (``max_bytes``): it stops cleanly, with a playable file, before the cap.
"""
from __future__ import annotations

import datetime
import logging
import os
import queue
import re
import shutil
import stat
import tempfile
import threading
from typing import Callable, Iterator

import cv2
import numpy as np

from ..core.files import open_new
from .source import Frame

log = logging.getLogger(__name__)

__all__ = ["VideoRecorder", "save_snapshot", "dated_path", "recordings_size", "WORK_DIR_PREFIX", "MIN_CAP_BYTES"]

MEDIA_PERM = 0o644              # media are for copying and sharing; only our own files are 0600
WORK_DIR_PREFIX = ".recording-"
_PLAIN_PREFIX = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]*")
#: what :func:`dated_path` makes, for any prefix: ``NAME-YYYYmmdd-HHMMSS-mmm.ext`` or ``…-mmm-N.ext``
DATED_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]*-\d{8}-\d{6}-\d{3}(-\d+)?\.[a-z0-9]+")
_MAX_SAME_NAME = 100            # files with the same millisecond's name before giving up


def dated_path(folder: str, prefix: str, ext: str, when: float | None = None, n: int = 1) -> str:
    """``folder/prefix-YYYYmmdd-HHMMSS-mmm.ext`` (``…-mmm-N.ext`` for ``n`` > 1), creating the folder.

    ``prefix`` is a plain name (letters, digits, ``_``, ``-``): the file stays in ``folder``.
    """
    if not _PLAIN_PREFIX.fullmatch(prefix) or not re.fullmatch(r"[a-z0-9]+", ext):
        raise ValueError(f"not a plain file name: {prefix!r}.{ext!r}")
    os.makedirs(folder, exist_ok=True)
    t = datetime.datetime.fromtimestamp(when) if when is not None else datetime.datetime.now()
    suffix = "" if n <= 1 else f"-{n}"
    return os.path.join(folder, f"{prefix}-{t:%Y%m%d-%H%M%S}-{t.microsecond // 1000:03d}{suffix}.{ext}")


def _dated_paths(folder: str, prefix: str, ext: str, when: float | None) -> Iterator[str]:
    if when is None:
        when = datetime.datetime.now().timestamp()
    for n in range(1, _MAX_SAME_NAME + 1):
        yield dated_path(folder, prefix, ext, when, n)
    raise FileExistsError(f"{_MAX_SAME_NAME} files named {dated_path(folder, prefix, ext, when)} already")


def save_snapshot(frame: Frame, folder: str, prefix: str = "snapshot") -> str:
    """Write ``frame`` as a new PNG and return its path (raises OSError when it cannot)."""
    ok, png = cv2.imencode(".png", cv2.cvtColor(frame.image, cv2.COLOR_RGB2BGR))
    if not ok:
        raise OSError("cannot encode the snapshot as PNG")
    for path in _dated_paths(folder, prefix, "png", frame.wall_time):
        try:
            f = open_new(path, "wb", MEDIA_PERM)
        except FileExistsError:
            continue                             # taken (or a planted link): the next name
        try:
            with f:
                f.write(png.tobytes())
        except OSError:
            _remove_quietly(path)
            raise
        return path
    raise AssertionError("unreachable")          # _dated_paths raises when it runs out


def recordings_size(folder: str) -> int:
    """Bytes held in ``folder`` by recordings and snapshots named as ours (:data:`DATED_NAME`), counting
    recordings still in progress (or left by a crash) in ``.recording-*`` directories. Links are not followed;
    other files are not counted."""
    total = 0
    try:
        entries = list(os.scandir(folder))
    except FileNotFoundError:
        return 0
    for entry in entries:
        try:
            if entry.is_file(follow_symlinks=False) and DATED_NAME.fullmatch(entry.name):
                total += entry.stat(follow_symlinks=False).st_size
            elif entry.name.startswith(WORK_DIR_PREFIX) and entry.is_dir(follow_symlinks=False):
                with os.scandir(entry.path) as inner:
                    total += sum(e.stat(follow_symlinks=False).st_size for e in inner
                                 if e.is_file(follow_symlinks=False))
        except OSError:                          # gone while we looked
            continue
    return total


def _remove_quietly(path: str) -> None:
    try:
        os.unlink(path)
    except OSError:
        pass


FALLBACK_FPS = 30.0             # a recording too short to measure its rate
MEASURE_S = 1.0                 # how much video tells the frame rate
MEASURE_FRAMES = 32             # ... or how many frames, whichever comes first (bounds the memory held)
# The encoder's file lags behind what it was given: FFmpeg writes it in blocks (256 KiB here) and adds
# its index (the moov box) when the file is closed. A capped recording stops while the file on disk plus
# this much room stays under the cap: the unwritten block (at most the largest jump of the file seen,
# or 1 MiB before any), the next frame (at most that jump again), and the index (under 64 B a frame).
CAP_ROOM_BYTES = 1 << 20
INDEX_BYTES_PER_FRAME = 64
MIN_CAP_BYTES = 2 * CAP_ROOM_BYTES  # a smaller cap would stop before the first frame


class RecordingFull(Exception):
    """The next frame would take the recording over its size cap."""


class VideoRecorder:
    """Records frames handed to :meth:`push` into ``path`` (MP4, mp4v).

    ``fps`` fixes the file's frame rate; None (the default) measures it from the frames.
    ``path`` must not exist yet (FileExistsError otherwise); it is reserved at once, and the
    finished recording takes its place when the recording ends. ``max_bytes`` caps the file's
    size: at the cap the recorder stops by itself (``full`` is then True) and the file is
    finished and playable. ``on_done(recorder)`` is called on the encoder's thread when it ends,
    whatever the reason (stopped, full, failed).
    """

    def __init__(self, path: str, fps: float | None = None, fourcc: str = "mp4v", max_queue: int = 8, *,
                 max_bytes: int | None = None, on_done: Callable[["VideoRecorder"], None] | None = None):
        if max_bytes is not None and max_bytes < MIN_CAP_BYTES:
            raise ValueError(f"a recording's cap must be at least {MIN_CAP_BYTES} bytes, not {max_bytes}")
        self.path = os.path.abspath(path)
        self.fps = fps
        self.max_bytes = max_bytes
        self.frames_written = 0
        self.frames_dropped = 0
        self.full = False
        self.error = ""
        self._fourcc = fourcc
        self._on_done = on_done
        self._queue: queue.Queue[Frame | None] = queue.Queue(max_queue)
        self._writer: cv2.VideoWriter | None = None
        self._size: tuple[int, int] | None = None
        self._last_index = 0
        self._largest_step = 0                  # the largest growth of the file on disk from one frame
        self._done = threading.Event()
        folder = os.path.dirname(self.path)
        with open_new(self.path, "wb", MEDIA_PERM) as reserved:    # ours, new: no link, nothing clobbered
            self._reserved = os.fstat(reserved.fileno())
        try:
            # 0700, random name, made exclusively: nobody else can put anything where the encoder writes
            self._work_dir = tempfile.mkdtemp(prefix=WORK_DIR_PREFIX, dir=folder)
        except OSError:
            self._remove_reservation()
            raise
        self._work = os.path.join(self._work_dir, os.path.basename(self.path))   # FFmpeg picks MP4 by the name
        self._thread = threading.Thread(target=self._run, name="video recorder", daemon=True)
        self._thread.start()

    @classmethod
    def in_folder(cls, folder: str, prefix: str = "video", fps: float | None = None, **options) -> "VideoRecorder":
        """A recorder to a new dated file in ``folder`` (the next free name if one is taken)."""
        for path in _dated_paths(folder, prefix, "mp4", None):
            try:
                return cls(path, fps, **options)
            except FileExistsError:
                continue
        raise AssertionError("unreachable")     # _dated_paths raises when it runs out

    @property
    def recording(self) -> bool:
        return self._thread.is_alive() and not self.error and not self.full

    def wait(self, timeout: float | None = None) -> bool:
        """Wait until the recording has ended (stopped, full or failed) and its file is in place."""
        return self._done.wait(timeout)

    def push(self, frame: Frame) -> None:
        """Queue a frame (any thread); never blocks. The same frame twice is written once."""
        if frame.index == self._last_index or self._done.is_set():
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
        except RecordingFull:
            self.full = True
            log.warning("recording %s stopped at its size cap (%.1f MB) after %d frames", self.path,
                        self.max_bytes / 1e6, self.frames_written)
        except Exception as e:
            log.exception("recording %s failed", self.path)
            self.error = str(e)
        finally:
            try:
                if self._writer is not None:
                    self._writer.release()
                self._finish()
            finally:
                if self._on_done is not None:
                    try:
                        self._on_done(self)
                    except Exception:
                        log.exception("after recording %s", self.path)
                self._done.set()

    def _finish(self) -> None:
        """Put the finished file in place of the reserved name (or give the name back), drop the work dir."""
        try:
            if self.frames_written and os.path.isfile(self._work):
                try:
                    os.chmod(self._work, MEDIA_PERM)
                except OSError:
                    pass                        # a file system without modes (FAT on a USB stick)
                os.replace(self._work, self.path)   # a rename: it never writes through a link at path
            else:
                self._remove_reservation()
        except OSError as e:
            log.error("recording %s cannot be finished: %s", self.path, e)
            self.error = self.error or f"cannot finish {self.path}: {e.strerror or e}"
        finally:
            shutil.rmtree(self._work_dir, ignore_errors=True)

    def _remove_reservation(self) -> None:
        """Remove the empty file we reserved, if it is still that file."""
        try:
            st = os.lstat(self.path)
        except OSError:
            return
        if stat.S_ISREG(st.st_mode) and (st.st_dev, st.st_ino) == (self._reserved.st_dev, self._reserved.st_ino) \
                and st.st_size == 0:
            _remove_quietly(self.path)

    def _write_all(self, held: list[Frame]) -> None:
        if held and self.fps is None:
            self.fps = measured_fps(held)
            log.info("recording %s at %.2f frames/s", self.path, self.fps)
        try:
            for frame in held:
                self._write(frame)
        finally:
            held.clear()

    def _write(self, frame: Frame) -> None:
        size = (frame.width, frame.height)
        if self._writer is None:
            self._writer = cv2.VideoWriter(self._work, cv2.CAP_FFMPEG, cv2.VideoWriter_fourcc(*self._fourcc),
                                           self.fps, size)
            if not self._writer.isOpened():
                raise OSError(f"cannot record to {self.path}")
            self._size = size
        before = self._check_cap()
        image = frame.image
        if size != self._size:      # the source changed resolution: keep the file's
            image = cv2.resize(image, self._size, interpolation=cv2.INTER_AREA)
        self._writer.write(cv2.cvtColor(np.ascontiguousarray(image), cv2.COLOR_RGB2BGR))
        self.frames_written += 1
        if before is not None:
            self._largest_step = max(self._largest_step, os.stat(self._work).st_size - before)

    def _check_cap(self) -> int | None:
        """The file's size on disk now (None without a cap); raises RecordingFull if one more frame
        could take the finished file over the cap."""
        if self.max_bytes is None:
            return None
        on_disk = os.stat(self._work).st_size            # in our private work dir: no link to follow
        room = max(CAP_ROOM_BYTES, 2 * self._largest_step) + INDEX_BYTES_PER_FRAME * (self.frames_written + 1)
        if on_disk + room > self.max_bytes:
            raise RecordingFull
        return on_disk


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
