"""The running smart shot over the video: what it is doing and how far the camera is off its look."""
from __future__ import annotations

from PyQt5.QtWidgets import QLabel, QWidget

from driver.shots.model import ShotKind, ShotState

__all__ = ["ShotBadge"]


class ShotBadge(QLabel):
    """Shown only while a shot runs; its text is the vehicle's, from telemetry."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setStyleSheet("background: rgba(0, 0, 0, 150); color: #4ee0ff; padding: 2px 6px; font-weight: bold")
        self._shown: ShotState | None = None
        self.hide()

    def show_shot(self, shot: ShotState) -> None:
        if shot is self._shown:
            return
        self._shown = shot
        if not shot.active:
            self.hide()
            return
        text = f"{shot.kind.value.upper()} {shot.phase.value}"
        if shot.kind is ShotKind.PANO:
            text += f" · {shot.photos}/{shot.photos_total} pictures"
        elif shot.progress is not None:
            text += f" · {100 * shot.progress:.0f} %"
        elif shot.radius is not None:
            text += f" · {shot.radius:.1f} m"
        if shot.aim_error is not None:
            text += f" · camera {shot.aim_error:.1f}° off"
        self.setText(text)
        self.show()
