"""An on-screen thumb stick that springs back to the centre.

Emits the knob's normalised position (x right, y up, each in [-1, 1]) on every
change. Releasing the mouse, leaving the pad or being disabled centres it, so a
lost gesture never leaves the drone moving.
"""
from __future__ import annotations

import math

from PyQt5.QtCore import QPointF, QRectF, Qt, pyqtSignal
from PyQt5.QtGui import QColor, QFont, QPainter, QPen, QRadialGradient
from PyQt5.QtWidgets import QSizePolicy, QWidget

__all__ = ["JoystickPad"]


class JoystickPad(QWidget):
    """Mouse/touch thumb stick; knows nothing of what its axes fly."""

    moved = pyqtSignal(float, float)        # normalised x, y (y up)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._x = 0.0
        self._y = 0.0
        self._dragging = False
        self._echo = (0.0, 0.0)                 # another input's demand on this pad's axes (keys, gamepad)
        self._caption = ""
        self._hint = ""
        self.setMinimumSize(120, 120)          # room for both at 1024×600
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Expanding)
        self.setFocusPolicy(Qt.NoFocus)
        self.setMouseTracking(False)

    # -- values in/out ---------------------------------------------------------------------------
    @property
    def position(self) -> tuple[float, float]:
        return (self._x, self._y)

    @property
    def dragging(self) -> bool:
        return self._dragging

    def set_caption(self, text: str) -> None:
        """What the pad flies, shown under the ring (e.g. "Climb · Yaw"); the pad is never narrower than it."""
        self._caption = text
        self.ensurePolished()                   # the style sheet's font, not the default one
        self.setMinimumWidth(max(120, self.fontMetrics().horizontalAdvance(text) + 8))
        self.update()

    def set_hint(self, text: str) -> None:
        """Why the pad is inert, shown over it while disabled."""
        if text != self._hint:
            self._hint = text
            self.update()

    def centre(self) -> None:
        """Spring back: knob to the middle, one (0, 0) emitted if it was off-centre."""
        self._dragging = False
        self._set(0.0, 0.0)

    def hold(self, x: float, y: float) -> None:
        """Put the knob at a normalised position as if a finger held it there (scripted demos)."""
        if self.isEnabled():
            norm = math.hypot(x, y)
            if norm > 1.0:
                x, y = x / norm, y / norm
            self._set(x, y)

    def set_echo(self, x: float, y: float) -> None:
        """Show where the keyboard or gamepad holds this pad's axes: the knob moves, nothing is emitted (the
        pilot sees the demand that flies, whatever gives it)."""
        if (x, y) != self._echo:
            self._echo = (x, y)
            self.update()

    @property
    def shown_position(self) -> tuple[float, float]:
        """Where the knob is drawn: the finger's position plus the other inputs' echo, inside the ring."""
        x = max(-1.0, min(1.0, self._x + self._echo[0]))
        y = max(-1.0, min(1.0, self._y + self._echo[1]))
        norm = math.hypot(x, y)
        return (x / norm, y / norm) if norm > 1.0 else (x, y)

    # -- geometry ------------------------------------------------------------------------------
    def _ring(self) -> tuple[QPointF, float]:
        caption_h = 22.0
        side = min(self.width(), self.height() - caption_h)
        radius = max(10.0, side / 2.0 - 6.0)
        return QPointF(self.width() / 2.0, (self.height() - caption_h) / 2.0), radius

    def knob_centre(self) -> QPointF:
        """Where the knob is drawn, in widget pixels (tests press here)."""
        return self.point_for(self._x, self._y)

    def point_for(self, x: float, y: float) -> QPointF:
        """Widget pixel of a normalised position (for tests and keyboard echo)."""
        c, r = self._ring()
        return QPointF(c.x() + x * r * 0.72, c.y() - y * r * 0.72)

    def _normalised(self, pos: QPointF) -> tuple[float, float]:
        c, r = self._ring()
        x = (pos.x() - c.x()) / (r * 0.72)
        y = -(pos.y() - c.y()) / (r * 0.72)
        norm = math.hypot(x, y)
        if norm > 1.0:              # keep the knob inside the ring, direction kept
            x, y = x / norm, y / norm
        return (max(-1.0, min(1.0, x)), max(-1.0, min(1.0, y)))

    def _set(self, x: float, y: float) -> None:
        if (x, y) != (self._x, self._y):
            self._x, self._y = x, y
            self.update()
            self.moved.emit(x, y)

    # -- events ----------------------------------------------------------------------------------
    def mousePressEvent(self, event) -> None:  # noqa: N802
        if event.button() == Qt.LeftButton and self.isEnabled():
            self._dragging = True
            self._set(*self._normalised(event.localPos()))
        event.accept()

    def mouseMoveEvent(self, event) -> None:  # noqa: N802
        if not self._dragging:
            return
        if not self.rect().contains(event.pos()):
            self.centre()           # the finger slid off the pad: let go
            return
        self._set(*self._normalised(event.localPos()))

    def mouseReleaseEvent(self, event) -> None:  # noqa: N802
        if event.button() == Qt.LeftButton:
            self.centre()

    def leaveEvent(self, event) -> None:  # noqa: N802
        self.centre()
        super().leaveEvent(event)

    def hideEvent(self, event) -> None:  # noqa: N802
        self.centre()
        super().hideEvent(event)

    def changeEvent(self, event) -> None:  # noqa: N802
        if event.type() == event.EnabledChange and not self.isEnabled():
            self.centre()
        super().changeEvent(event)

    # -- drawing ---------------------------------------------------------------------------------
    def paintEvent(self, event) -> None:  # noqa: N802
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        c, r = self._ring()
        enabled = self.isEnabled()
        ring_col = QColor(70, 130, 200) if enabled else QColor(70, 75, 82)
        p.setPen(QPen(ring_col, 2))
        p.setBrush(QColor(28, 34, 42) if enabled else QColor(30, 32, 36))
        p.drawEllipse(c, r, r)
        p.setPen(QPen(QColor(255, 255, 255, 40 if enabled else 20), 1, Qt.DashLine))
        p.drawLine(QPointF(c.x() - r, c.y()), QPointF(c.x() + r, c.y()))
        p.drawLine(QPointF(c.x(), c.y() - r), QPointF(c.x(), c.y() + r))
        k = self.point_for(*self.shown_position)
        kr = r * 0.28
        grad = QRadialGradient(k, kr)
        if enabled:
            grad.setColorAt(0, QColor(120, 180, 255))
            grad.setColorAt(1, QColor(40, 100, 180))
        else:
            grad.setColorAt(0, QColor(95, 98, 104))
            grad.setColorAt(1, QColor(60, 62, 66))
        p.setPen(Qt.NoPen)
        p.setBrush(grad)
        p.drawEllipse(k, kr, kr)
        font = QFont(self.font())
        font.setPixelSize(13)
        p.setFont(font)
        p.setPen(QColor(190, 200, 210) if enabled else QColor(110, 115, 120))
        p.drawText(QRectF(0, self.height() - 22, self.width(), 22), Qt.AlignCenter, self._caption)
        if not enabled and self._hint:
            p.setPen(QColor(220, 220, 220))
            box = QRectF(c.x() - r * 0.9, c.y() - 20, r * 1.8, 40)
            p.drawText(box, Qt.AlignCenter | Qt.TextWordWrap, self._hint)
        p.end()
