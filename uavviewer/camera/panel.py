"""The camera area of the window: the video view and a row of camera buttons."""
from __future__ import annotations

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import QHBoxLayout, QLabel, QSizePolicy, QToolButton, QVBoxLayout, QWidget

from .view import CameraView

__all__ = ["CameraPanel"]


class CameraPanel(QWidget):
    """Buttons say what the pilot wants; the camera controller does it."""

    hudToggled = pyqtSignal(bool)
    snapshotRequested = pyqtSignal()
    recordToggled = pyqtSignal(bool)
    switchRequested = pyqtSignal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.view = CameraView(self)
        self.hud_button = self._button("HUD", "Show the flight HUD over the video", checkable=True)
        self.hud_button.setChecked(True)
        self.snapshot_button = self._button("Snapshot", "Save the current picture as PNG")
        self.record_button = self._button("Record", "Record the video to a file", checkable=True)
        self.switch_button = self._button("Switch camera", "Show the next camera")
        self.note = QLabel(self)
        self.note.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Preferred)
        self.hud_button.toggled.connect(self.hudToggled)
        self.snapshot_button.clicked.connect(self.snapshotRequested)
        self.record_button.toggled.connect(self.recordToggled)
        self.switch_button.clicked.connect(self.switchRequested)
        row = QHBoxLayout()
        row.setContentsMargins(0, 0, 0, 0)
        for b in (self.hud_button, self.snapshot_button, self.record_button, self.switch_button):
            row.addWidget(b)
        row.addWidget(self.note, 1)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.setSpacing(2)
        layout.addWidget(self.view, 1)
        layout.addLayout(row)

    def add_overlay(self, widget: QWidget) -> None:
        """A control that comes and goes (Stop looking) stands over the video's top right corner, where showing it
        moves nothing: the rows below keep their width, the attitude beside keeps its size."""
        corner = self.view.layout()
        if corner is None:
            corner = QHBoxLayout(self.view)
            corner.setContentsMargins(4, 4, 4, 4)
            corner.addStretch(1)
        corner.addWidget(widget, 0, Qt.AlignTop)

    def _button(self, text: str, tip: str, checkable: bool = False) -> QToolButton:
        b = QToolButton(self)
        b.setText(text)
        b.setToolTip(tip)
        b.setCheckable(checkable)
        b.setAutoRaise(True)
        return b

    def set_note(self, text: str) -> None:
        """A one-line outcome ("Saved …", "Cannot record: …")."""
        self.note.setText(text)
        self.note.setToolTip(text)

    def set_recording(self, on: bool) -> None:
        """Reflect the recorder's real state without re-emitting."""
        if self.record_button.isChecked() != on:
            self.record_button.blockSignals(True)
            self.record_button.setChecked(on)
            self.record_button.blockSignals(False)

    def set_switch_enabled(self, enabled: bool) -> None:
        self.switch_button.setEnabled(enabled)
