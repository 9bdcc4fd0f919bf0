"""The 3DR Solo's video: keep TCP 5502 open to the controller, read RTP H.264 on UDP 5600.

The controller forwards the Solo's H.264 as RTP to UDP 5600 of the one app that
holds a TCP connection open to 10.1.1.1:5502 (see arducopter.md, "Video on the
Solo"). :class:`SoloLink` holds that connection and reconnects when it drops;
:func:`write_sdp` describes the RTP stream so OpenCV's FFmpeg backend can open it.
The SDP file lives in our private :func:`~driver.core.files.runtime_dir` under a random name
(never a fixed name in /tmp that another user could plant a link at), and goes when the
source closes.
"""
from __future__ import annotations

import logging
import os
import secrets
import socket
import threading

from ..core.files import runtime_dir, write_private
from .source import OpenCVSource, SourceFailed

log = logging.getLogger(__name__)

__all__ = ["SoloLink", "SoloSource", "write_sdp", "SOLO_HOST", "SOLO_VIDEO_TCP_PORT", "SOLO_VIDEO_UDP_PORT",
           "RTP_FFMPEG_OPTIONS"]

SOLO_HOST = "10.1.1.1"
SOLO_VIDEO_TCP_PORT = 5502
SOLO_VIDEO_UDP_PORT = 5600
RTP_FFMPEG_OPTIONS = "protocol_whitelist;file,rtp,udp"


def write_sdp(path: str, port: int = SOLO_VIDEO_UDP_PORT, encoding: str = "H264/90000", payload: int = 96,
              address: str = "127.0.0.1") -> str:
    """Write an SDP file describing one RTP video stream arriving on UDP ``port`` (mode 0600).

    Written with :func:`~driver.core.files.write_private`: a link planted at ``path`` is replaced, not
    followed, and a reader never sees half a file."""
    text = "\n".join([
        "v=0",
        f"o=- 0 0 IN IP4 {address}",
        "s=UavViewer video",
        f"c=IN IP4 {address}",
        "t=0 0",
        f"m=video {int(port)} RTP/AVP {int(payload)}",
        f"a=rtpmap:{int(payload)} {encoding}",
        "",
    ])
    return write_private(path, text.encode("ascii"))


class SoloLink:
    """Holds the TCP connection that makes the controller send video; reconnects with backoff."""

    def __init__(self, host: str = SOLO_HOST, port: int = SOLO_VIDEO_TCP_PORT, timeout: float = 3.0):
        self.host, self.port, self.timeout = host, port, timeout
        self.connected = False
        self.connections = 0
        self.reason = "not connected yet"
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="solo video link", daemon=True)

    def start(self) -> "SoloLink":
        self._thread.start()
        return self

    def close(self) -> None:
        self._stop.set()

    def _run(self) -> None:
        delay = 0.5
        while not self._stop.is_set():
            try:
                with socket.create_connection((self.host, self.port), timeout=self.timeout) as sock:
                    self.connected, self.reason = True, ""
                    self.connections += 1
                    delay = 0.5
                    log.info("solo video link to %s:%d open", self.host, self.port)
                    sock.settimeout(0.5)
                    while not self._stop.is_set():
                        try:
                            if not sock.recv(4096):
                                self.reason = "controller closed the video link"
                                break
                        except socket.timeout:
                            continue
            except OSError as e:
                self.reason = f"controller {self.host}:{self.port} unreachable ({e.strerror or e})"
            self.connected = False
            if not self._stop.is_set():
                log.info("solo video link: %s", self.reason)
            self._stop.wait(delay)
            delay = min(delay * 2, 5.0)


class SoloSource(OpenCVSource):
    """``solo``: the Solo's RTP H.264 video, with the controller link kept open.

    Without ``sdp_path``, the SDP file is named on the first open, ``solo-PORT-RANDOM.sdp`` in
    :func:`~driver.core.files.runtime_dir` (``sdp_path`` then tells where), and removed when the capture
    thread ends; a file at a given ``sdp_path`` is the caller's and stays.
    """

    def __init__(self, host: str = SOLO_HOST, tcp_port: int = SOLO_VIDEO_TCP_PORT,
                 udp_port: int = SOLO_VIDEO_UDP_PORT, sdp_path: str | None = None, encoding: str = "H264/90000",
                 payload: int = 96, name: str = "Solo camera", timeout_ms: int = 5000, low_latency: bool = True):
        self.sdp_path = sdp_path
        self._own_sdp = sdp_path is None
        self._sdp = (udp_port, encoding, payload)
        super().__init__(sdp_path or "", name, stream=True, ffmpeg_options=RTP_FFMPEG_OPTIONS, timeout_ms=timeout_ms,
                         low_latency=low_latency)
        self.uri = "solo"
        self.link = SoloLink(host, tcp_port)

    @property
    def description(self) -> str:
        return f"3DR Solo video via {self.link.host}:{self.link.port}, RTP on UDP {self._sdp[0]}"

    def start(self) -> "SoloSource":
        if self._thread is None:
            self.link.start()
        super().start()
        return self

    def close(self, wait: float = 0.0) -> None:
        self.link.close()
        super().close(wait)

    def _open(self) -> None:
        udp_port, encoding, payload = self._sdp
        if self.sdp_path is None:                   # on the capture thread: the caller never waits for a disk
            self.sdp_path = os.path.join(runtime_dir(), f"solo-{udp_port}-{secrets.token_hex(8)}.sdp")
            log.info("Solo video described in %s", self.sdp_path)
        write_sdp(self.sdp_path, udp_port, encoding, payload)    # again each time: a cleaner may have removed it
        self._target = self.sdp_path
        try:
            super()._open()
        except SourceFailed:
            if not self.link.connected:
                raise SourceFailed(f"no Solo video: {self.link.reason}") from None
            raise SourceFailed(f"no RTP video on UDP {udp_port}") from None

    def _run(self) -> None:
        try:
            super()._run()
        finally:
            if self._own_sdp and self.sdp_path:
                try:
                    os.unlink(self.sdp_path)
                except FileNotFoundError:
                    pass
                except OSError as e:
                    log.warning("cannot remove %s: %s", self.sdp_path, e)

    def _read(self):
        try:
            return super()._read()
        except SourceFailed:
            if not self.link.connected:
                raise SourceFailed(f"Solo video stopped: {self.link.reason}") from None
            raise
