"""Play/pause, restart, seek, speed and the flight's clock while watching a recorded flight."""
from __future__ import annotations

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import QComboBox, QHBoxLayout, QLabel, QPushButton, QSlider, QWidget

from ..flight.timer import clock_text
from ..widgets.seek_slider import SeekSlider
from ..widgets.text_width import width_for

__all__ = ["ReplayBar", "SPEEDS"]

SPEEDS = (0.5, 1.0, 2.0, 4.0, 8.0)
STEPS = 1000                   # the seek bar's resolution


class ReplayBar(QWidget):
    pauseRequested = pyqtSignal(bool)       # True = pause
    speedRequested = pyqtSignal(float)
    seekRequested = pyqtSignal(float)       # seconds from the start of the recording
    restartRequested = pyqtSignal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("replayBar")
        self._paused = False
        self.play_button = QPushButton("Pause")
        self.play_button.setObjectName("replayPlay")
        self.play_button.setFocusPolicy(Qt.NoFocus)
        self.speed = QComboBox()
        self.speed.setFocusPolicy(Qt.NoFocus)
        for s in SPEEDS:
            self.speed.addItem(f"{s:g}×", s)
        self.restart_button = QPushButton("Restart")
        self.restart_button.setObjectName("replayRestart")
        self.restart_button.setFocusPolicy(Qt.NoFocus)
        self.progress = SeekSlider()                  # shows where the replay is; clicked or dragged, it seeks
        self.progress.setObjectName("replaySeek")
        self.progress.setRange(0, STEPS)
        self.progress.setFocusPolicy(Qt.NoFocus)
        self.progress.setToolTip("Drag or click to jump in the recording")
        self._duration = 0.0
        self.clock = QLabel("--:-- / --:--")
        self.clock.setObjectName("replayClock")
        row = QHBoxLayout(self)
        row.setContentsMargins(8, 0, 8, 0)          # as tall as the stick line it stands in for
        row.addWidget(QLabel("Replay"))
        row.addWidget(self.play_button)
        row.addWidget(self.restart_button)
        row.addWidget(self.speed)
        row.addWidget(self.progress, 1)
        row.addWidget(self.clock)
        self._finished = False
        self.play_button.clicked.connect(self._play_clicked)
        # as wide as their longest texts from the start: Pause/Play/Restart and the clock never move the seek bar
        self.play_button.setMinimumWidth(max(width_for(self.play_button, t) for t in ("Pause", "Play")))
        self.clock.setMinimumWidth(width_for(self.clock, "8:88:88 / 8:88:88"))
        self.speed.activated.connect(lambda i: self.speedRequested.emit(float(self.speed.itemData(i))))
        self.restart_button.clicked.connect(self.restartRequested)
        self.progress.sliderReleased.connect(lambda: self._seek(self.progress.value()))
        self.progress.actionTriggered.connect(self._clicked)
        self.speed.setCurrentIndex(self.speed.findData(1.0))

    def _play_clicked(self) -> None:
        """Pause / Play (nothing once the recording has ended: Restart beside it plays it again)."""
        if not self._finished:
            self.pauseRequested.emit(not self._paused)

    def _clicked(self, action: int) -> None:
        """A click on the groove (page step) or the keys: seek to where the slider goes."""
        if action in (QSlider.SliderPageStepAdd, QSlider.SliderPageStepSub, QSlider.SliderSingleStepAdd,
                      QSlider.SliderSingleStepSub, QSlider.SliderToMinimum, QSlider.SliderToMaximum):
            self._seek(self.progress.sliderPosition())

    def _seek(self, value: int) -> None:
        if self._duration > 0:
            self.seekRequested.emit(self._duration * value / STEPS)

    def seek_to(self, seconds: float) -> None:
        """Move the bar as the pilot would and ask for that place (tests and the keyboard)."""
        if self._duration > 0:
            self.progress.setValue(int(STEPS * max(0.0, min(1.0, seconds / self._duration))))
            self._seek(self.progress.value())

    def set_progress(self, position: float | None, duration: float | None, paused: bool,
                     speed: float | None = None, finished: bool = False) -> None:
        """``finished``: the whole log has been played; nothing more will come."""
        self._paused, self._finished = paused, finished
        self.play_button.setText("Play" if paused or finished else "Pause")
        self.play_button.setEnabled(not finished)   # one Restart only: the button beside it
        self._duration = duration or 0.0
        if duration and not self.progress.isSliderDown():
            fraction = 1.0 if finished else (position or 0.0) / duration
            value = int(STEPS * max(0.0, min(1.0, fraction)))
            if value != self.progress.value():
                self.progress.blockSignals(True)
                self.progress.setValue(value)
                self.progress.blockSignals(False)
        # the end is said by the play button (Restart): a longer clock would squeeze the seek bar at the end
        self.clock.setText(f"{clock_text(duration if finished else position)} / {clock_text(duration)}")
        if speed is not None and not self.speed.view().isVisible():
            i = self.speed.findData(float(speed))
            if i >= 0 and i != self.speed.currentIndex():
                self.speed.setCurrentIndex(i)

