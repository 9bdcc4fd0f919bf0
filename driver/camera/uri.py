"""One option names any video source; :func:`open_source` turns it into a :class:`VideoSource`.

=========================================  =============================================
``0``, ``1``                               local camera by index
``/dev/video0``                            local camera by device path
``clip.mp4`` (``clip.mp4?loop=1``)          video file, optionally looping
``rtsp://…``, ``http://…``                  network stream (RTSP, HTTP/MJPEG)
``udp://0.0.0.0:5600``                     MPEG-TS over UDP
``stream.sdp``                             RTP described by an SDP file (e.g. H.264 on 5600)
``solo`` (``solo:HOST``)                   the 3DR Solo's video through its controller
``ice:Camera:default -h HOST -p 9999``     a JdeRobot Camera over Ice, in RGB8
``sim``                                    the simulated vehicle's camera
=========================================  =============================================
"""
from __future__ import annotations

import ipaddress
import logging
import os
import threading
from typing import Callable

from ..vehicle.state import VehicleState
from .source import FFMPEG_TIMEOUT_MS, STALL_S, OpenCVSource, SourceFailed, VideoSource

log = logging.getLogger(__name__)

__all__ = ["open_source", "describe_uri", "CameraSet", "STREAM_SCHEMES", "register_scheme"]

#: Sources other packages add without this one importing them (the Ice camera: driver.ice.camera_source).
_SCHEMES: dict = {}


def register_scheme(scheme: str, factory) -> None:
    """``scheme:REST`` URIs open as ``factory(rest, image_format, timeout_ms)``."""
    _SCHEMES[scheme] = factory

STREAM_SCHEMES = ("rtsp", "rtsps", "rtmp", "http", "https", "udp", "rtp", "tcp", "srt")


def _split_loop(uri: str) -> tuple[str, bool]:
    if not os.path.exists(uri) and "?" in uri:
        path, _, query = uri.rpartition("?")
        if query in ("loop", "loop=1", "loop=true"):
            return path, True
    return uri, False


def _shareable(uri: str) -> bool:
    """Whether another program can watch ``uri`` too: UDP/RTP input listens on a local port, which
    only one reader can have, unless the address is a multicast group."""
    scheme, _, rest = uri.partition("://")
    if scheme.lower() not in ("udp", "rtp"):
        return True
    host = rest.split("?", 1)[0].rsplit(":", 1)[0].strip("[]@")
    try:
        return ipaddress.ip_address(host).is_multicast
    except ValueError:
        return False


def describe_uri(uri: str) -> str:
    """What kind of source ``uri`` names, for menus and logs."""
    u = uri.strip()
    if u == "sim":
        return "simulated camera"
    if u == "solo" or u.startswith("solo:"):
        return "3DR Solo video"
    if u.startswith("ice:"):
        return "Ice camera"
    if u.isdigit():
        return f"camera {u}"
    if u.startswith("/dev/"):
        return f"camera {u}"
    scheme = u.split("://", 1)[0].lower() if "://" in u else ""
    if scheme in STREAM_SCHEMES:
        return f"{scheme.upper()} stream"
    if u.lower().endswith(".sdp"):
        return "RTP stream (SDP)"
    return f"file {os.path.basename(_split_loop(u)[0])}"


def open_source(uri: str, *, state_fn: Callable[[], VehicleState] | None = None, loop: bool = False,
                image_format: str = "RGB8", timeout_ms: int = FFMPEG_TIMEOUT_MS,
                sim_size: tuple[int, int] = (640, 480), stall_s: float = STALL_S, start: bool = True,
                low_latency: bool = True) -> VideoSource:
    """The source ``uri`` names (see the module table), started unless ``start`` is False.

    ``state_fn`` returns the latest vehicle state; the simulated camera needs it. ``timeout_ms``
    bounds how long opening or reading a stream may hang before it counts as failed; ``stall_s`` is
    how long without a new frame makes a live source "stalled" (0: never); ``sim_size``
    is the simulated camera's width and height; ``low_latency`` opens live FFmpeg streams (network, SDP,
    the Solo) with :data:`~driver.camera.source.LOW_LATENCY_OPTIONS`.
    Opening happens on the source's own thread, so this never blocks.
    """
    import cv2
    from .solo import RTP_FFMPEG_OPTIONS, SOLO_HOST, SoloSource
    u = uri.strip()
    if not u:
        raise ValueError("empty camera source")
    if u == "sim":
        if state_fn is None:
            raise ValueError("the simulated camera needs the vehicle's state")
        from .sim import SimSource
        source: VideoSource = SimSource(state_fn, width=sim_size[0], height=sim_size[1])
    elif u == "solo" or u.startswith("solo:"):
        host = u.partition(":")[2]
        source = SoloSource(host or SOLO_HOST, timeout_ms=timeout_ms, low_latency=low_latency)
    elif u.split(":", 1)[0] in _SCHEMES:               # ice: (driver.ice.camera_source registers it)
        scheme, rest = u.split(":", 1)
        source = _SCHEMES[scheme](rest, image_format, timeout_ms)
    elif u.startswith("ice:"):
        source = UnsupportedSource(u)          # nothing registered ice: (import driver.ice.camera_source)
    elif u.isdigit():
        source = OpenCVSource(int(u), f"camera {u}", stream=True, timeout_ms=timeout_ms)
    elif u.startswith("/dev/"):
        source = OpenCVSource(u, f"camera {u}", stream=True, timeout_ms=timeout_ms)
    elif "://" in u and u.split("://", 1)[0].lower() in STREAM_SCHEMES:
        source = OpenCVSource(u, describe_uri(u), api=cv2.CAP_FFMPEG, stream=True,
                              streaming_uri=u if _shareable(u) else "", timeout_ms=timeout_ms,
                              low_latency=low_latency)
    elif "://" in u:
        source = UnsupportedSource(u)
    elif u.lower().endswith(".sdp"):
        source = OpenCVSource(os.path.abspath(u), describe_uri(u), api=cv2.CAP_FFMPEG, stream=True,
                              ffmpeg_options=RTP_FFMPEG_OPTIONS, timeout_ms=timeout_ms, low_latency=low_latency)
    else:
        path, looped = _split_loop(u)
        source = OpenCVSource(os.path.abspath(path), describe_uri(u), api=cv2.CAP_FFMPEG, stream=False,
                              loop=loop or looped)
    source.uri = u
    source.stall_s = stall_s
    return source.start() if start else source


class UnsupportedSource(VideoSource):
    """A URI with a scheme no source reads: it fails, saying so (and what would work), like any dead source."""

    def _open(self) -> None:
        scheme = self.uri.split("://", 1)[0]
        raise SourceFailed(f"unsupported camera source {scheme}://; use " +
                           ", ".join(f"{s}://" for s in STREAM_SCHEMES) +
                           ", a file, an .sdp file, a device, solo, ice:PROXY or sim")


class CameraSet:
    """The configured sources, one open at a time; :meth:`toggle` moves to the next.

    Listeners (a recorder) follow the active source across switches.
    """

    def __init__(self, uris: list[str], *, on_switch: Callable[[VideoSource], None] | None = None, **options):
        """``options`` go to :func:`open_source` (state_fn, loop, image_format, timeout_ms, stall_s, low_latency)."""
        if not uris:
            raise ValueError("no camera source configured")
        self.uris = list(uris)
        self._opts = options
        self._lock = threading.Lock()
        self._index = 0
        self._listeners: list[Callable] = []
        self._on_switch = on_switch
        self._suspended = False
        self._source = open_source(self.uris[0], **self._opts)

    @property
    def source(self) -> VideoSource:
        return self._source

    @property
    def index(self) -> int:
        return self._index

    def add_listener(self, callback) -> None:
        with self._lock:
            self._listeners.append(callback)
            self._source.add_listener(callback)

    def remove_listener(self, callback) -> None:
        with self._lock:
            self._listeners = [c for c in self._listeners if c != callback]     # bound methods: ==, not is
            self._source.remove_listener(callback)

    def toggle(self) -> VideoSource:
        """Close the current source and open the next configured one (never blocks)."""
        return self.select((self._index + 1) % len(self.uris))

    def select(self, index: int) -> VideoSource:
        with self._lock:
            if len(self.uris) > 1 or index != self._index:
                old = self._source
                self._index = index % len(self.uris)
                self._source = open_source(self.uris[self._index], start=False, **self._opts)
                for callback in self._listeners:
                    self._source.add_listener(callback)
                self._source.start()
                self._suspended = False
                old.close()
                log.info("camera switched to %s", self._source.uri)
            source = self._source
        if self._on_switch is not None:
            self._on_switch(source)
        return source

    @property
    def suspended(self) -> bool:
        return self._suspended

    def suspend(self) -> None:
        """Stop capturing and decoding (nobody watches and nothing records): the source is closed, never blocking."""
        with self._lock:
            if not self._suspended:
                self._suspended = True
                self._source.close()
                log.info("camera %s suspended", self._source.uri)

    def resume(self) -> VideoSource:
        """Open the current source again after :meth:`suspend` (a fresh capture: the newest picture, no backlog)."""
        with self._lock:
            if self._suspended:
                self._suspended = False
                self._source = open_source(self.uris[self._index], start=False, **self._opts)
                for callback in self._listeners:
                    self._source.add_listener(callback)
                self._source.start()
                log.info("camera %s resumed", self._source.uri)
            return self._source

    def close(self, wait: float = 0.0) -> None:
        self._source.close(wait)
