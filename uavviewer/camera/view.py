"""The video picture: the newest frame scaled to fit, the HUD over it, or why there is no video.

The QImage is built straight on the frame's RGB buffer (Format_RGB888 with the
array's row stride), so painting neither copies nor swaps colour channels; the
frame is kept alive while the QImage points into it.
"""
from __future__ import annotations

import time

import numpy as np
from PyQt5 import sip
from PyQt5.QtCore import QRectF, Qt, pyqtSignal
from PyQt5.QtGui import QColor, QFont, QImage, QPainter
from PyQt5.QtWidgets import QSizePolicy, QWidget

from driver.camera import Frame
from driver.vehicle.state import VehicleState

from .hud import paint_hud

__all__ = ["CameraView", "fit_rect"]

BACKGROUND = QColor(12, 14, 18)
MESSAGE = QColor(200, 205, 212)
STATS = QColor(235, 240, 245)
RECORDING = QColor(230, 40, 40)


def fit_rect(width: int, height: int, area: QRectF) -> QRectF:
    """The largest rectangle of ``width``:``height`` centred in ``area``."""
    if width <= 0 or height <= 0 or area.width() <= 0 or area.height() <= 0:
        return QRectF()
    scale = min(area.width() / width, area.height() / height)
    w, h = width * scale, height * scale
    return QRectF(area.center().x() - w / 2, area.center().y() - h / 2, w, h)


class CameraView(QWidget):
    """Paints what it is given; the camera controller decides what that is."""

    framePainted = pyqtSignal(int, float)     # frame index, decode-to-paint latency in seconds

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._frame: Frame | None = None
        self._image: QImage | None = None
        self._painted_index = 0
        self._message = "No video"
        self._stats = ""
        self._recording = ""
        self._state: VehicleState | None = None
        self._hud = True
        self.setAttribute(Qt.WA_OpaquePaintEvent)
        self.setMinimumSize(240, 96)           # the window fits 1024×600, title bar included
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Expanding)

    # -- what to show ------------------------------------------------------------------------
    def set_frame(self, frame: Frame) -> None:
        """Show ``frame`` (RGB, height×width×3); the message goes away."""
        img = frame.image
        if img.strides[1:] != (3, 1):            # QImage needs packed R,G,B pixels in each row
            frame = Frame(np.ascontiguousarray(img), frame.index, frame.decoded, frame.wall_time)
            img = frame.image
        self._frame = frame          # keeps the buffer alive under the QImage
        self._image = QImage(sip.voidptr(img.ctypes.data), frame.width, frame.height, int(img.strides[0]),
                             QImage.Format_RGB888)
        self._message = ""
        self.update()

    def set_message(self, text: str) -> None:
        """Show ``text`` instead of video (the last frame is dropped)."""
        if text != self._message or self._frame is not None:
            self._message = text
            self._frame, self._image = None, None
            self.update()

    def message(self) -> str:
        return self._message

    def frame(self) -> Frame | None:
        return self._frame

    def set_stats(self, text: str) -> None:
        if text != self._stats:
            self._stats = text
            self.update()

    def set_recording(self, text: str) -> None:
        """A red "REC …" mark while recording ("" hides it)."""
        if text != self._recording:
            self._recording = text
            self.update()

    def set_state(self, state: VehicleState | None) -> None:
        if state is not self._state:
            self._state = state
            if self._hud and self._frame is not None:      # the HUD is drawn over a picture only
                self.update()

    def set_hud_visible(self, visible: bool) -> None:
        if visible != self._hud:
            self._hud = visible
            self.update()

    def hud_visible(self) -> bool:
        return self._hud

    def video_rect(self) -> QRectF:
        """Where the picture is drawn (empty when there is none)."""
        if self._frame is None:
            return QRectF()
        return fit_rect(self._frame.width, self._frame.height, QRectF(self.rect()))

    # -- painting ----------------------------------------------------------------------------
    def paintEvent(self, event) -> None:  # noqa: N802
        p = QPainter(self)
        p.fillRect(self.rect(), BACKGROUND)
        frame, image = self._frame, self._image
        target = self.video_rect()
        if image is not None and not target.isEmpty():
            p.setRenderHint(QPainter.SmoothPixmapTransform)
            p.drawImage(target, image)
        if self._hud and self._state is not None and not target.isEmpty():
            paint_hud(p, target, self._state)        # over the picture only: "No video" stays readable
        font = QFont(self.font())
        font.setPixelSize(max(11, min(16, self.height() // 30)))
        p.setFont(font)
        if self._message:
            p.setPen(MESSAGE)
            p.drawText(QRectF(self.rect()).adjusted(10, 10, -10, -10), Qt.AlignCenter | Qt.TextWordWrap,
                       self._message)
        if self._stats:
            r = QRectF(self.rect()).adjusted(6, 0, -6, -4)
            p.setPen(QColor(0, 0, 0, 170))
            p.drawText(r.translated(1, 1), Qt.AlignLeft | Qt.AlignBottom, self._stats)
            p.setPen(STATS)
            p.drawText(r, Qt.AlignLeft | Qt.AlignBottom, self._stats)
        if self._recording:
            r = QRectF(self.rect()).adjusted(6, 0, -6, -4)
            p.setPen(RECORDING)
            p.drawText(r, Qt.AlignRight | Qt.AlignBottom, "● " + self._recording)
        p.end()
        if frame is not None and frame.index != self._painted_index:
            self._painted_index = frame.index
            self.framePainted.emit(frame.index, time.monotonic() - frame.decoded)
