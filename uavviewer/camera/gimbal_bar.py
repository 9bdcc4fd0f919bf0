"""The row under the video for the camera ON THE VEHICLE: its gimbal and its own Photo and Record.

Kept apart from the window's Snapshot/Record (which save the video this window receives) by its own row, the
"Drone cam" label and names, and it shows only what the vehicle confirmed.
"""
from __future__ import annotations

from PyQt5.QtCore import pyqtSignal
from PyQt5.QtWidgets import QHBoxLayout, QLabel, QToolButton, QWidget

from driver.vehicle.state import VehicleState

from ..widgets.text_width import width_for

__all__ = ["GimbalBar"]


class GimbalBar(QWidget):
    """Buttons say what the pilot wants; the gimbal controller does it."""

    levelRequested = pyqtSignal()
    downRequested = pyqtSignal()
    photoRequested = pyqtSignal()
    recordRequested = pyqtSignal(bool)          # the vehicle's camera: start (True) or stop
    stopLookingRequested = pyqtSignal()         # end the region of interest ("Look here" on the map)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._shown: tuple | None = None         # (gimbal, camera, connected) the texts last showed
        self.pitch_label = QLabel("Drone cam ?°", self)   # short: the row fits a 1024-pixel window;
        self.pitch_label.setToolTip("The gimbal's pitch as the vehicle reports it (0 level, -90 straight down)")
        self.level_button = self._button("Level", "Point the camera level (gimbal pitch 0°)")
        self.down_button = self._button("Down", "Point the camera straight down (gimbal pitch -90°)")
        self.photo_button = self._button("Photo", "Take a picture with the vehicle's own camera; counted "
                                         "only when the vehicle confirms it")
        self.record_button = self._button("Video", "Start or stop video on the vehicle's own camera "
                                          "(not this window's recording)")
        self.record_button.setCheckable(True)
        self._recording: bool | None = None         # the camera's last word (None: it has said nothing)
        self.stop_looking_button = self._button("Stop looking", "The camera stops looking at the point chosen on "
                                                "the map (DO_SET_ROI_NONE) and goes back to the pilot")
        self.stop_looking_button.setStyleSheet("color: #ff6ad5; font-weight: bold")
        self.stop_looking_button.hide()
        self.level_button.clicked.connect(self.levelRequested)
        self.down_button.clicked.connect(self.downRequested)
        self.photo_button.clicked.connect(self.photoRequested)
        self.record_button.clicked.connect(self._record_clicked)
        self.stop_looking_button.clicked.connect(self.stopLookingRequested)
        row = QHBoxLayout(self)
        row.setContentsMargins(0, 0, 0, 0)
        row.setSpacing(4)
        for w in (self.pitch_label, self.level_button, self.down_button, self.photo_button, self.record_button):
            row.addWidget(w)
        row.addStretch(1)
        # each as wide as its longest text from the start: a dot or a pitch appearing moves nothing (Stop looking
        # is not in the row: it stands over the video, see CameraPanel.add_overlay)
        for w, longest in ((self.pitch_label, "Drone cam -90°"), (self.record_button, "Video ●")):
            w.setMinimumWidth(width_for(w, longest))

    def _button(self, text: str, tip: str) -> QToolButton:
        b = QToolButton(self)
        b.setText(text)
        b.setToolTip(tip)
        b.setAutoRaise(True)
        return b

    def _record_clicked(self) -> None:
        """Start when the camera says it is not recording, stop when it says it is: the click asks, the button's
        own toggle is undone at once and only the camera's report presses it (a toggle left to the next snapshot
        crossed it, and a second click then asked to start again)."""
        recording = bool(self._recording)
        self.record_button.setChecked(recording)
        self.recordRequested.emit(not recording)

    def show_state(self, s: VehicleState) -> None:
        """What the vehicle says about its gimbal and camera; the Record button follows the camera, not the click.
        Every snapshot: the texts are set only when what they show changed."""
        c = s.camera
        self._recording = c.recording
        if self.record_button.isChecked() != bool(c.recording):     # a click the camera did not follow is undone
            self.record_button.setChecked(bool(c.recording))
        live = s.connected and not s.link.replay       # a recording's camera cannot be asked for anything
        shown = (s.gimbal, c, live)
        if shown == self._shown:
            return
        self._shown = shown
        pitch = s.gimbal.pitch_deg
        self.pitch_label.setText("Drone cam " + ("?°" if pitch is None else f"{pitch:.0f}°"))
        self.pitch_label.setToolTip(f"The vehicle's camera: gimbal {s.gimbal.describe()}, the pitch as the vehicle reports it "
                                    "(0 level, -90 straight down)")
        self.photo_button.setText("Photo")     # the count is in its tooltip (the row fits 1024 px and never moves)
                                               # and in the mission's progress line (plan/progress.py)
        self.record_button.setText("Video ●" if c.recording else "Video")
        recording = "unknown" if c.recording is None else "yes" if c.recording else "no"
        self.photo_button.setToolTip(f"A picture with the vehicle's camera ({c.name or c.kind.value}), counted only "
                                     f"when it confirms it: {c.photos} so far")
        self.record_button.setToolTip(f"Video on the vehicle's camera (not this window's recording); recording: "
                                      f"{recording}")
        self.stop_looking_button.setVisible(s.gimbal.roi is not None)
        for b in (self.level_button, self.down_button, self.photo_button, self.record_button,
                  self.stop_looking_button):
            b.setEnabled(live)
