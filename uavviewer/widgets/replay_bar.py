"""Play/pause, speed and the flight's clock while watching a recorded flight."""
from __future__ import annotations

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import QComboBox, QHBoxLayout, QLabel, QProgressBar, QPushButton, QWidget

__all__ = ["ReplayBar", "SPEEDS"]

SPEEDS = (1.0, 2.0, 4.0)


def _clock(seconds: float | None) -> str:
    if seconds is None or seconds != seconds:
        return "--:--"
    seconds = max(0, int(seconds))
    return f"{seconds // 60:02d}:{seconds % 60:02d}"


class ReplayBar(QWidget):
    pauseRequested = pyqtSignal(bool)       # True = pause
    speedRequested = pyqtSignal(float)

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
        self.progress = QProgressBar()
        self.progress.setRange(0, 1000)
        self.progress.setTextVisible(False)
        self.progress.setMaximumHeight(10)
        self.clock = QLabel("--:-- / --:--")
        self.clock.setObjectName("replayClock")
        row = QHBoxLayout(self)
        row.setContentsMargins(8, 4, 8, 4)
        row.addWidget(QLabel("Replay"))
        row.addWidget(self.play_button)
        row.addWidget(self.speed)
        row.addWidget(self.progress, 1)
        row.addWidget(self.clock)
        self.play_button.clicked.connect(lambda: self.pauseRequested.emit(not self._paused))
        self.speed.activated.connect(lambda i: self.speedRequested.emit(float(self.speed.itemData(i))))

    def set_progress(self, position: float | None, duration: float | None, paused: bool,
                     speed: float | None = None, finished: bool = False) -> None:
        """``finished``: the whole log has been played; nothing more will come."""
        self._paused = paused
        self.play_button.setText("Finished" if finished else ("Play" if paused else "Pause"))
        self.play_button.setEnabled(not finished)
        if duration:
            fraction = 1.0 if finished else (position or 0.0) / duration
            self.progress.setValue(int(1000 * max(0.0, min(1.0, fraction))))
        end = "  (finished)" if finished else ""
        self.clock.setText(f"{_clock(duration if finished else position)} / {_clock(duration)}{end}")
        if speed is not None and not self.speed.view().isVisible():
            i = self.speed.findData(float(speed))
            if i >= 0 and i != self.speed.currentIndex():
                self.speed.setCurrentIndex(i)
