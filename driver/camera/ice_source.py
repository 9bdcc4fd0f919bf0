"""Video from a JdeRobot ``Camera`` served over Ice (ours or any JdeRobot driver's)."""
from __future__ import annotations

import logging

import numpy as np

from .source import SourceFailed, VideoSource

log = logging.getLogger(__name__)

__all__ = ["IceSource"]

IMAGE_MESSAGE_KB = 65536        # a 1280x720 RGB8 image is 2.7 MB; Ice's default limit is 1 MB


class IceSource(VideoSource):
    """``ice:<proxy>``: asks ``getImageData(format)`` in a loop, keeping each new image."""

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

    @property
    def description(self) -> str:
        return f"JdeRobot camera {self.proxy}"

    def _open(self) -> None:
        import Ice
        from ..ice import load_slice
        jderobot, _ = load_slice()
        self._jderobot = jderobot
        init = Ice.InitializationData()
        init.properties = Ice.createProperties()
        init.properties.setProperty("Ice.MessageSizeMax", str(IMAGE_MESSAGE_KB))
        init.properties.setProperty("Ice.Warn.Connections", "0")
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

    def _read(self) -> np.ndarray | None:
        import Ice
        jderobot = self._jderobot
        try:
            data = self._camera.getImageData(self.image_format)
        except jderobot.DataNotExistException as e:
            raise SourceFailed(f"camera has no image yet ({e.what})") from None
        except jderobot.HardwareFailedException as e:
            raise SourceFailed(f"camera failed: {e.what}") from None
        except Ice.LocalException as e:
            raise SourceFailed(f"camera server {self.proxy} lost ({type(e).__name__})") from None
        stamp = (data.timeStamp.seconds, data.timeStamp.useconds)
        if stamp == self._last_stamp:         # the same image again: wait for a new one
            self._stop.wait(self._poll)
            return None
        self._last_stamp = stamp
        d = data.description
        if d.format != "RGB8" or d.width <= 0 or d.height <= 0 or len(data.pixelData) != d.width * d.height * 3:
            raise SourceFailed(f"camera sent an unusable image ({d.format} {d.width}x{d.height}, "
                               f"{len(data.pixelData)} bytes)")
        return np.frombuffer(data.pixelData, np.uint8).reshape(d.height, d.width, 3)

    def _release(self) -> None:
        communicator, self._communicator, self._camera = self._communicator, None, None
        if communicator is not None:
            communicator.destroy()
