"""A video source read on its own thread, keeping only the newest frame.

Whoever shows or serves video (the viewer's timer, an Ice servant, a recorder)
asks :meth:`VideoSource.latest` for the newest :class:`Frame`; nothing queues,
so a slow reader never makes the picture lag behind the camera. Opening, reading
and decoding (which can hang on a network) happen only on the capture thread,
and a source that fails or ends says why and tries again with a growing pause.
A source whose frames stop coming while the capture still hangs in a read (a network
stream that went quiet) reports "stalled" once no frame has come for ``stall_s``.
"""
from __future__ import annotations

import logging
import os
import sys
import threading
import time
from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

log = logging.getLogger(__name__)

__all__ = ["Frame", "SourceStatus", "VideoSource", "OpenCVSource", "SourceEnded", "SourceFailed", "STALL_S"]

FFMPEG_TIMEOUT_MS = 5000
STALL_S = 2.0                   # no new frame for this long: the video is stalled, not live
_FFMPEG_ENV = "OPENCV_FFMPEG_CAPTURE_OPTIONS"
#: FFmpeg's options for live video (OpenCV's OPENCV_FFMPEG_CAPTURE_OPTIONS, ``key;value|key;value``): hand each
#: packet on as it arrives instead of buffering input (nobuffer), no wait to reorder packets (max_delay 0), the
#: decoder's low-delay mode (low_delay), and a short look at the stream before the first picture (probesize,
#: analyzeduration). bench/bench_video_latency.py measures what they save.
LOW_LATENCY_OPTIONS = "fflags;nobuffer|flags;low_delay|max_delay;0|probesize;32768|analyzeduration;200000"


#: Decoder threads for live video. OpenCV gives FFmpeg one per core, and FFmpeg's frame threading holds a
#: picture back for each extra thread (33 ms at 30 fps on two cores, measured); one thread decodes 720p30
#: H.264 at a fraction of a core (bench/bench_video_latency.py prints the viewer's CPU).
LOW_LATENCY_THREADS = 1
#: Given no options OpenCV asks for RTSP over TCP; given ours, FFmpeg would ask for UDP first and wait 10 s for
#: a packet before trying TCP, longer than our open timeout. So a low-latency RTSP source asks for TCP (what
#: worked before), and after a failed attempt lets FFmpeg choose (UDP first: a server such as rtsp-server-perl
#: serves nothing else), alternating until one delivers.
RTSP_OVER_TCP = "rtsp_transport;tcp"


def join_options(*parts: str | None) -> str:
    """FFmpeg option strings joined for OPENCV_FFMPEG_CAPTURE_OPTIONS (empty parts left out)."""
    return "|".join(p for p in parts if p)
_ENV_LOCK = threading.Lock()


@dataclass(frozen=True)
class Frame:
    """One decoded picture: ``image`` is height×width×3, uint8, R,G,B order, read-only."""
    image: np.ndarray
    index: int                  # 1 for the first frame a source delivers, then +1 per frame
    decoded: float              # time.monotonic() right after decoding (start of decode-to-paint latency)
    wall_time: float            # time.time() at the same instant (for Ice timestamps and file names)

    @property
    def width(self) -> int:
        return int(self.image.shape[1])

    @property
    def height(self) -> int:
        return int(self.image.shape[0])


@dataclass(frozen=True)
class SourceStatus:
    state: str                  # "connecting", "live", "stalled", "retrying", "ended", "closed"
    reason: str = ""            # why there is no video (empty while live)
    frames: int = 0             # frames delivered since the source was created
    dropped: int = 0            # frames replaced by a newer one before anyone took them
    attempts: int = 0           # how many times the source was opened

    @property
    def live(self) -> bool:
        return self.state == "live"


class SourceEnded(Exception):
    """The source has no more frames (end of a file that does not loop)."""


class SourceFailed(Exception):
    """The source cannot deliver frames; the message is shown to the pilot."""


class VideoSource:
    """Base: a capture thread calling :meth:`_open` / :meth:`_read` / :meth:`_release`.

    Subclasses implement those three; ``_read`` returns an RGB frame (or None when no
    new frame is there yet) and raises :class:`SourceEnded` or :class:`SourceFailed`.
    """

    retry_initial = 0.5
    retry_max = 5.0             # a source that has delivered frames comes back soon (a replugged camera)
    retry_max_unheard = 120.0   # one that never delivered any (unsupported, wrong address): back off further
    retry_on_end = True         # network streams come back; a file that ended may not

    def __init__(self, uri: str, name: str | None = None, stall_s: float = STALL_S):
        self.uri = uri
        self.name = name or uri
        self.stall_s = stall_s          # 0 = never report a stall
        self._min_stall = 0.0           # a subclass's slowest normal frame spacing (a slow file)
        self._steady = 0.0              # monotonic time of the last frame that came in a steady flow
        self._previous = 0.0            # monotonic time of the newest frame (0: none since opening)
        self._lock = threading.Lock()
        self._frame: Frame | None = None
        self._taken = True
        self._status = SourceStatus("connecting")
        self._stop = threading.Event()
        self._wake = threading.Event()
        self._listeners: list[Callable[[Frame], None]] = []
        self._thread: threading.Thread | None = None
        self._frames = 0
        self._dropped = 0
        self._attempts = 0

    # -- what readers use ---------------------------------------------------------------------
    def start(self) -> "VideoSource":
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name=f"video {self.name}", daemon=True)
            self._thread.start()
        return self

    def latest(self) -> Frame | None:
        """The newest frame (None before the first); marks it taken."""
        with self._lock:
            self._taken = True
            return self._frame

    def status(self) -> SourceStatus:
        """The state; "live" turns into "stalled" when no frame has come for the stall time."""
        with self._lock:
            status = self._status
            stall = max(self.stall_s, self._min_stall)
            if status.state == "live" and self.stall_s > 0:
                age = time.monotonic() - self._steady
                if age >= stall:
                    return replace(status, state="stalled", reason=f"no frame for {age:.{1 if age < 10 else 0}f} s")
            return status

    @property
    def description(self) -> str:
        """A short human description ("file clip.mp4", "RTSP stream ...")."""
        return self.name

    @property
    def streaming_uri(self) -> str:
        """Where others can watch the same video directly ("" when only we can read it)."""
        return ""

    def add_listener(self, callback: Callable[[Frame], None]) -> None:
        """Call ``callback(frame)`` on the capture thread for every new frame (keep it short)."""
        with self._lock:
            self._listeners = self._listeners + [callback]

    def remove_listener(self, callback: Callable[[Frame], None]) -> None:
        with self._lock:
            # ==, not "is": ``recorder.push`` is a new bound method each time it is named
            self._listeners = [c for c in self._listeners if c != callback]

    def restart(self) -> None:
        """Drop the current connection and open again at once."""
        self._restart = True
        self._wake.set()

    def close(self, wait: float = 0.0) -> None:
        """Stop the thread; never blocks the caller longer than ``wait`` seconds."""
        self._stop.set()
        self._wake.set()
        if wait and self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(wait)

    @property
    def closed(self) -> bool:
        return self._thread is not None and not self._thread.is_alive()

    # -- subclass hooks -----------------------------------------------------------------------
    def _open(self) -> None:
        raise NotImplementedError

    def _read(self) -> np.ndarray | None:
        raise NotImplementedError

    def _release(self) -> None:
        pass

    # -- the thread ---------------------------------------------------------------------------
    _restart = False

    def _set_status(self, state: str, reason: str = "") -> None:
        with self._lock:
            self._status = SourceStatus(state, reason, self._frames, self._dropped, self._attempts)

    def _publish(self, image: np.ndarray) -> None:
        now_m, now_w = time.monotonic(), time.time()
        image.flags.writeable = False
        with self._lock:
            # a lone frame after a silence (FFmpeg hands back a buffered one when a read times out)
            # does not end a stall: video is live again once frames follow each other
            if not self._previous or now_m - self._previous < max(self.stall_s, self._min_stall):
                self._steady = now_m
            self._previous = now_m
            self._frames += 1
            if not self._taken:
                self._dropped += 1
            self._frame = Frame(image, self._frames, now_m, now_w)
            self._taken = False
            self._status = SourceStatus("live", "", self._frames, self._dropped, self._attempts)
            frame, listeners = self._frame, self._listeners
        for callback in listeners:
            try:
                callback(frame)
            except Exception:  # a listener must never kill the capture
                log.exception("video listener failed")

    def _run(self) -> None:
        delay = self.retry_initial
        while not self._stop.is_set():
            self._restart = False
            self._attempts += 1
            self._set_status("connecting", self._status.reason or "connecting")
            reason, ended = "", False
            self._previous = 0.0
            try:
                self._open()
                log.info("video source %s open", self.name)
                while not self._stop.is_set() and not self._restart:
                    image = self._read()
                    if image is not None:
                        self._publish(image)
                        delay = self.retry_initial
            except SourceEnded as e:
                reason, ended = str(e) or "end of stream", True
            except SourceFailed as e:
                reason = str(e)
            except Exception as e:  # OpenCV, sockets, Ice: anything means "no video, try again"
                log.exception("video source %s failed", self.name)
                reason = f"{type(e).__name__}: {e}"
            finally:
                try:
                    self._release()
                except Exception:
                    log.exception("releasing video source %s", self.name)
            if self._stop.is_set():
                break
            if self._restart:
                continue
            log.info("video source %s: %s", self.name, reason)
            if ended and not self.retry_on_end:
                self._set_status("ended", reason)
                self._wake.wait()   # until restart() or close()
                self._wake.clear()
                continue
            self._set_status("retrying", f"{reason} (retrying in {delay:.1f} s)")
            self._wake.wait(delay)
            self._wake.clear()
            delay = min(delay * 2, self.retry_max if self._frames else max(self.retry_max, self.retry_max_unheard))
        self._set_status("closed", "closed")


class OpenCVSource(VideoSource):
    """Anything OpenCV opens: a camera index or device, a file, RTSP/HTTP/UDP, an SDP file."""

    def __init__(self, target: str | int, name: str | None = None, *, loop: bool = False,
                 api: int | None = None, stream: bool | None = None, ffmpeg_options: str | None = None,
                 streaming_uri: str = "", timeout_ms: int = FFMPEG_TIMEOUT_MS, low_latency: bool = False):
        """``low_latency`` (a live stream through FFmpeg): open it with :data:`LOW_LATENCY_OPTIONS`."""
        import cv2
        uri = str(target)
        super().__init__(uri, name)
        self._target = target
        self._loop = loop
        self._api = cv2.CAP_ANY if api is None else api
        if stream is None:
            stream = not (isinstance(target, str) and os.path.isfile(target))
        # a file is paced at its own frame rate, as a camera would deliver it, and may loop;
        # a stream (camera, network, SDP) is read as fast as it comes and reopened when it ends
        self._is_file = not stream
        self.low_latency = bool(low_latency and stream)
        if self.low_latency:
            ffmpeg_options = join_options(LOW_LATENCY_OPTIONS, ffmpeg_options)
        self._ffmpeg_options = ffmpeg_options
        self._streaming_uri = streaming_uri
        self._timeout_ms = int(timeout_ms)
        self.retry_on_end = not self._is_file
        self._cap = None
        self._period = 0.0
        self._next = 0.0

    @property
    def streaming_uri(self) -> str:
        return self._streaming_uri

    @property
    def ffmpeg_options(self) -> str | None:
        """What OPENCV_FFMPEG_CAPTURE_OPTIONS holds while this source opens (None: OpenCV's defaults); a
        low-latency RTSP source adds :data:`RTSP_OVER_TCP` on every other attempt, the first included."""
        return self._ffmpeg_options

    def _options_now(self) -> str | None:
        """The options for this attempt: an RTSP source alternates between TCP and FFmpeg's own choice."""
        if self.low_latency and self.uri.lower().startswith(("rtsp://", "rtsps://")) and self._attempts % 2 == 1:
            return join_options(self._ffmpeg_options, RTSP_OVER_TCP)
        return self._ffmpeg_options

    def _open(self) -> None:
        import cv2
        if isinstance(self._target, str) and self._looks_local_file() and not os.path.exists(self._target):
            raise SourceFailed(f"no such file: {self._target}")
        device = self._device_path()
        if device and not os.path.exists(device):      # checked here: OpenCV would only log its own complaint
            raise SourceFailed(f"no such device: {device}")
        params = [cv2.CAP_PROP_OPEN_TIMEOUT_MSEC, self._timeout_ms, cv2.CAP_PROP_READ_TIMEOUT_MSEC, self._timeout_ms]
        if self.low_latency:
            params += [cv2.CAP_PROP_N_THREADS, LOW_LATENCY_THREADS]
        options = self._options_now()
        if options is None:
            cap = cv2.VideoCapture(self._target, self._api, params)
        else:
            # OpenCV's FFmpeg backend reads this variable when a capture opens; it is process-wide,
            # so it is set only for this open
            with _ENV_LOCK:
                old = os.environ.get(_FFMPEG_ENV)
                os.environ[_FFMPEG_ENV] = options
                try:
                    cap = cv2.VideoCapture(self._target, self._api, params)
                finally:
                    if old is None:
                        os.environ.pop(_FFMPEG_ENV, None)
                    else:
                        os.environ[_FFMPEG_ENV] = old
        if not cap.isOpened():
            cap.release()
            raise SourceFailed(f"cannot open {self.uri}")
        self._cap = cap
        fps = cap.get(cv2.CAP_PROP_FPS)
        self._period = 1.0 / fps if self._is_file and 1.0 <= fps <= 240.0 else 0.0
        self._min_stall = 3 * self._period
        self._next = time.monotonic()

    def _device_path(self) -> str:
        """The video device file a camera source needs ("" when it is not one, or not on Linux)."""
        t = self._target
        if isinstance(t, str) and t.startswith("/dev/"):
            return t
        if isinstance(t, int) and sys.platform.startswith("linux"):
            return f"/dev/video{t}"
        return ""

    def _looks_local_file(self) -> bool:
        t = self._target
        return "://" not in t and not t.startswith("/dev/") and not t.isdigit()

    def _read(self) -> np.ndarray | None:
        import cv2
        if self._period:
            wait = self._next - time.monotonic()
            if wait > 0 and self._stop.wait(wait):
                return None
            self._next = max(self._next + self._period, time.monotonic() - self._period)
        ok, bgr = self._cap.read()
        if not ok or bgr is None:
            if self._is_file and self._loop and self._frames:
                self._cap.set(cv2.CAP_PROP_POS_FRAMES, 0)
                ok, bgr = self._cap.read()
            if not ok or bgr is None:
                if self._is_file:
                    raise SourceEnded(f"end of file {os.path.basename(self.uri)}")
                raise SourceFailed(f"stream stopped: {self.uri}")
        if bgr.ndim == 2:
            return cv2.cvtColor(bgr, cv2.COLOR_GRAY2RGB)
        return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)   # the one copy: OpenCV decodes to B,G,R

    def _release(self) -> None:
        cap, self._cap = self._cap, None
        if cap is not None:
            cap.release()
