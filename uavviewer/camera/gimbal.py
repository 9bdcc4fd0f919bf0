"""Tilting the vehicle's camera from the window: wheel and drag on the video, keys, Level/Down, its own Photo and
Record, and Stop looking (docs/camera.md). Owns no widget logic beyond wiring; the drone does the work."""
from __future__ import annotations

import time

from PyQt5.QtCore import QEvent, QObject, Qt

from driver.payload.model import GIMBAL_PITCH_RANGE
from driver.vehicle.state import VehicleState

__all__ = ["GimbalController", "WHEEL_STEP", "KEY_STEP", "DRAG_DEG_PER_PX"]

WHEEL_STEP = 5.0            # deg a wheel notch tilts
KEY_STEP = 5.0              # deg a key press tilts
DRAG_DEG_PER_PX = 0.25      # deg per pixel of vertical drag (dragging up tilts up)
SEND_INTERVAL = 0.1         # s: a drag sends at most this often, and its last angle on release
REACHED = 1.0               # deg: the reported pitch this close to the angle asked has reached it


def _clamped(pitch: float) -> float:
    """Within the gimbal's travel: down to its lowest, up to level."""
    return min(max(pitch, GIMBAL_PITCH_RANGE[0]), 0.0)


class GimbalController(QObject):
    def __init__(self, adapter, view, bar, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._adapter = adapter
        self._view = view
        self._bar = bar
        self._target: float | None = None       # the angle last asked, until the vehicle reports it
        self._drag_y: float | None = None
        self._drag_start = 0.0
        self._sent_at = 0.0
        self._before_roi: float | None = None   # the pitch while no point is looked at
        self._restore: float | None = None      # ... as it was when a point began to be looked at: Stop looking
        view.installEventFilter(self)
        bar.levelRequested.connect(lambda: self.point(0.0))
        bar.downRequested.connect(lambda: self.point(-90.0))
        bar.photoRequested.connect(lambda: adapter.send(adapter.drone.take_photo))
        bar.recordRequested.connect(lambda on: adapter.send(adapter.drone.record_video, on))
        bar.stopLookingRequested.connect(self.stop_looking)
        adapter.droneChanged.connect(self._vehicle_changed)

    def show_state(self, s: VehicleState) -> None:
        reported = s.gimbal.pitch_deg
        if self._target is not None and reported is not None and abs(reported - self._target) <= REACHED:
            self._target = None                 # the vehicle points there: tilt from what it reports again
        if s.gimbal.roi is None:
            if reported is not None and self._target is None:
                self._before_roi = reported
        elif self._restore is None:
            self._restore = self._before_roi    # looking at a point moves it: this is where it was
        self._bar.show_state(s)

    def _vehicle_changed(self, _drone) -> None:
        """Another vehicle is flown: the angle asked of the previous one is not this one's."""
        self._target = self._before_roi = self._restore = None

    def stop_looking(self) -> None:
        """End the region of interest (the bar's button, the map's menu)."""
        self._adapter.send(self._adapter.drone.stop_looking, then=self._stopped_looking)

    def _stopped_looking(self, result) -> None:
        """The mount fell back to its default (straight down on ArduCopter's RC targeting): the camera goes back to
        the pitch it had before it looked at the point."""
        if result.ok and self._restore is not None:
            pitch, self._restore = self._restore, None
            self.point(pitch)

    def _base(self) -> float:
        if self._target is not None:
            return self._target
        pitch = self._adapter.state.gimbal.pitch_deg if self._adapter.state is not None else None
        return pitch if pitch is not None else 0.0

    def point(self, pitch: float) -> None:
        pitch = _clamped(pitch)
        self._target = pitch
        self._sent_at = time.monotonic()
        self._adapter.send(self._adapter.drone.point_gimbal, pitch)

    def tilt_by(self, degrees: float) -> None:
        """Up (positive) or down from where it points (or was last asked to)."""
        self.point(self._base() + degrees)

    def eventFilter(self, watched, event) -> bool:       # noqa: N802 (Qt's name)
        kind = event.type()
        if kind == QEvent.Wheel:
            notches = event.angleDelta().y() / 120.0
            if notches:
                self.tilt_by(notches * WHEEL_STEP)
            return True
        if kind == QEvent.MouseButtonPress and event.button() == Qt.LeftButton:
            self._drag_y, self._drag_start = event.pos().y(), self._base()
            return True
        if kind == QEvent.MouseMove and self._drag_y is not None:
            pitch = self._drag_start + (self._drag_y - event.pos().y()) * DRAG_DEG_PER_PX
            if time.monotonic() - self._sent_at >= SEND_INTERVAL:
                self.point(pitch)
            else:
                self._target = _clamped(pitch)
            return True
        if kind == QEvent.MouseButtonRelease and self._drag_y is not None:
            self.point(self._drag_start + (self._drag_y - event.pos().y()) * DRAG_DEG_PER_PX)
            self._drag_y = None
            return True
        return False
