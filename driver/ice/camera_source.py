"""Video from a JdeRobot ``Camera`` served over Ice (ours or any JdeRobot driver's): ``ice:<proxy>``.

It lives with the Ice code and registers its scheme with :func:`driver.camera.uri.register_scheme` when
imported, so ``driver.camera`` never imports ``driver.ice`` (the dependency runs one way: ice -> camera).

``getImageData`` always answers with the newest image, so asking too often only
sends the same image again. After each new image the source waits most of the
camera's measured frame interval before asking again: a first ask that still gets
the old image makes the next wait longer, one that gets a new image makes it
shorter, so the asks settle just after the frames appear.
"""
from __future__ import annotations

import logging
import statistics
import time
from collections import deque

import numpy as np

from ..camera.source import SourceFailed, VideoSource
from ..camera.uri import register_scheme

log = logging.getLogger(__name__)

__all__ = ["IceSource"]

#: Ice properties every ``ice:`` camera of this process adds to its own: main.py puts the IceSSL ones here when
#: the viewer flies a MAVLinkServer over TLS (--ice-certs), so the server's camera is reached the same way.
client_properties: dict[str, str] = {}
LEAD = (0.5, 0.8, 0.95)         # the wait after a new image, as a fraction of the frame interval: min, start, max
WAIT_S = (0.005, 0.2)           # bounds of any wait between asks


def use_client_properties(props) -> None:
    """Reach Ice cameras as this Ice client is set up (``props``, Ice.Properties): over TLS with its certificate,
    through its registry's locator (a lab's fleet)."""
    client_properties.update({k: v for prefix in ("IceSSL.", "Ice.Plugin.IceSSL", "Ice.Default.Locator")
                              for k, v in props.getPropertiesForPrefix(prefix).items()})


class IceSource(VideoSource):
    """``ice:<proxy>``: asks ``getImageData(format)`` in a loop, keeping each new image.

    ``poll_s`` is the pause between asks until two new images have told the frame interval.
    """

    def __init__(self, proxy: str, image_format: str = "RGB8", timeout_ms: int = 3000, poll_s: float = 0.01,
                 name: str | None = None):
        super().__init__(f"ice:{proxy}", name or f"Ice camera {proxy}")
        self.proxy = proxy
        self.image_format = image_format
        self._timeout_ms = timeout_ms
        self._poll = poll_s
        self._communicator = None
        self._camera = None
        self._last_stamp = None
        self._jderobot = None
        self._arrivals: deque[float] = deque(maxlen=9)    # when the last new images came (monotonic)
        self._lead = LEAD[1]
        self._next_ask = 0.0
        self._misses = 0                                  # asks since the last new image that got it again

    @property
    def description(self) -> str:
        return f"JdeRobot camera {self.proxy}"

    def _open(self) -> None:
        import Ice
        from . import load_slice
        jderobot, _ = load_slice()
        self._jderobot = jderobot
        init = Ice.InitializationData()
        init.properties = Ice.createProperties()
        from .client import CLIENT_MESSAGE_KB          # a 1920x1080 RGB8 picture; Ice's default is 1 MB
        init.properties.setProperty("Ice.MessageSizeMax", str(CLIENT_MESSAGE_KB))
        init.properties.setProperty("Ice.Warn.Connections", "0")
        for key, value in client_properties.items():
            init.properties.setProperty(key, value)
        self._communicator = Ice.initialize(init)
        try:
            base = self._communicator.stringToProxy(self.proxy).ice_invocationTimeout(self._timeout_ms)
            camera = jderobot.CameraPrx.checkedCast(base)
        except Ice.LocalException as e:
            raise SourceFailed(f"camera server {self.proxy} unreachable ({type(e).__name__})") from None
        if camera is None:
            raise SourceFailed(f"{self.proxy} is not a jderobot::Camera")
        self._camera = camera
        self._last_stamp = None
        self._arrivals.clear()
        self._next_ask = 0.0

    def _read(self) -> np.ndarray | None:
        import Ice
        jderobot = self._jderobot
        wait = self._next_ask - time.monotonic()
        if wait > 0 and self._stop.wait(wait):
            return None
        try:
            data = self._camera.getImageData(self.image_format)
        except jderobot.DataNotExistException as e:
            raise SourceFailed(f"camera has no image yet ({e.what})") from None
        except jderobot.HardwareFailedException as e:
            raise SourceFailed(f"camera failed: {e.what}") from None
        except Ice.LocalException as e:
            raise SourceFailed(f"camera server {self.proxy} lost ({type(e).__name__})") from None
        now = time.monotonic()
        stamp = (data.timeStamp.seconds, data.timeStamp.useconds)
        interval = self._interval()
        if stamp == self._last_stamp:         # the same image again: asked too early
            if not self._misses and interval:
                self._lead = min(LEAD[2], self._lead + 0.05)
            self._misses += 1
            # ask again soon, then less and less often while the camera sends nothing new
            retry = 0.1 * interval * 2 ** (self._misses - 1) if interval else self._poll
            self._next_ask = now + _bounded(retry)
            return None
        if not self._misses and interval:     # new at the first ask: perhaps late, ask a little earlier
            self._lead = max(LEAD[0], self._lead - 0.02)
        self._misses = 0
        self._last_stamp = stamp
        self._arrivals.append(now)
        interval = self._interval()
        self._next_ask = now + _bounded(self._lead * interval) if interval else now
        d = data.description
        if d.format != "RGB8" or d.width <= 0 or d.height <= 0 or len(data.pixelData) != d.width * d.height * 3:
            raise SourceFailed(f"camera sent an unusable image ({d.format} {d.width}x{d.height}, "
                               f"{len(data.pixelData)} bytes)")
        return np.frombuffer(data.pixelData, np.uint8).reshape(d.height, d.width, 3)

    def _interval(self) -> float:
        """The camera's frame interval, from when new images came (0 until known)."""
        times = self._arrivals
        if len(times) < 2:
            return 0.0
        return statistics.median(b - a for a, b in zip(times, list(times)[1:]))

    def _release(self) -> None:
        communicator, self._communicator, self._camera = self._communicator, None, None
        if communicator is not None:
            communicator.destroy()


def _bounded(wait: float) -> float:
    return min(WAIT_S[1], max(WAIT_S[0], wait))


register_scheme("ice", lambda rest, image_format, timeout_ms: IceSource(rest.strip(), image_format, timeout_ms=timeout_ms))
