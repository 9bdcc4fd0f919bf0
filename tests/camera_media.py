"""Video made on the spot for the camera tests: clips with known colours and streams on loopback.

Everything is produced with OpenCV's own FFmpeg (no ffmpeg binary needed): an MP4
(mp4v) or MPEG-TS (MPEG-1 video) file, whose bytes a thread sends over UDP at a
steady pace, as a plain MPEG-TS stream or wrapped in RTP (payload 33, MP2T).
"""
from __future__ import annotations

import os
import socket
import struct
import threading
import time

import cv2
import numpy as np

# distinct colours that survive lossy compression, R, G, B
COLOURS = [(255, 0, 0), (0, 255, 0), (0, 0, 255), (255, 255, 0), (255, 0, 255), (0, 255, 255)]
TS_PACKET = 188


def write_clip(path: str, colours=COLOURS, repeat: int = 1, size=(320, 240), fps: float = 30.0,
               fourcc: str = "mp4v") -> str:
    """A clip showing each colour (R, G, B) for ``repeat`` frames, in order."""
    writer = cv2.VideoWriter(path, cv2.CAP_FFMPEG, cv2.VideoWriter_fourcc(*fourcc), fps, size)
    if not writer.isOpened():
        raise RuntimeError(f"OpenCV cannot encode {fourcc} into {os.path.basename(path)}")
    frame = np.empty((size[1], size[0], 3), np.uint8)
    for rgb in colours:
        frame[:] = rgb[::-1]                     # VideoWriter takes B, G, R
        for _ in range(repeat):
            writer.write(frame)
    writer.release()
    return path


def frames_and_rate(path: str) -> tuple[int, float]:
    """How many frames a video file holds, and the frame rate its container declares."""
    cap = cv2.VideoCapture(path)
    fps = cap.get(cv2.CAP_PROP_FPS)
    n = 0
    while cap.read()[0]:
        n += 1
    cap.release()
    return n, fps


def write_ts(path: str, colours=COLOURS, repeat: int = 10, size=(320, 240)) -> bytes:
    """An MPEG-TS file (MPEG-1 video); returns its bytes."""
    write_clip(path, colours, repeat, size, fourcc="PIM1")
    with open(path, "rb") as f:
        data = f.read()
    if not data or len(data) % TS_PACKET:
        raise RuntimeError("OpenCV wrote no usable MPEG-TS")
    return data


class UdpSender:
    """Sends MPEG-TS bytes to 127.0.0.1:port in a loop, 7 TS packets a datagram, optionally as RTP.

    :meth:`pause` stops sending with the socket left open, as a camera that goes quiet.
    """

    def __init__(self, data: bytes, port: int, rtp: bool = False, rate_bytes_s: float = 400_000):
        self.data, self.port, self.rtp = data, port, rtp
        self._period = 7 * TS_PACKET / rate_bytes_s
        self._stop = threading.Event()
        self._sending = threading.Event()
        self._sending.set()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self.sent = 0

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self.stop()

    def pause(self):
        self._sending.clear()

    def resume(self):
        self._sending.set()

    def stop(self):
        self._stop.set()
        self._sending.set()
        self._thread.join(2)

    def _run(self):
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        chunk = 7 * TS_PACKET
        seq, start = 0, time.monotonic()
        try:
            while not self._stop.is_set():
                for off in range(0, len(self.data), chunk):
                    self._sending.wait()
                    if self._stop.is_set():
                        break
                    payload = self.data[off:off + chunk]
                    if self.rtp:
                        ts = int((time.monotonic() - start) * 90000) & 0xFFFFFFFF
                        payload = struct.pack("!BBHII", 0x80, 33, seq & 0xFFFF, ts, 0x1234) + payload
                    sock.sendto(payload, ("127.0.0.1", self.port))
                    seq += 1
                    self.sent += 1
                    self._stop.wait(self._period)
        finally:
            sock.close()


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait(cond, timeout=10.0, what="condition"):
    """Poll ``cond`` until it returns something true (returned), or fail after ``timeout`` s."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = cond()
        if value:
            return value
        time.sleep(0.01)
    raise AssertionError(f"timed out waiting for {what}")
