"""Saying alerts out loud without ever blocking the window.

:class:`Speaker` queues texts and says one at a time: through espeak-ng (a child process run by
:class:`~PyQt5.QtCore.QProcess`, so the UI thread only starts it) when the system has it, else Qt's own
QTextToSpeech when PyQt5 ships it with an engine, else the desktop's beep. A more urgent alert jumps the queue,
and the queue never grows stale: at most a few alerts wait, the least urgent are dropped first.
"""
from __future__ import annotations

import logging
import shutil
import subprocess

from PyQt5.QtCore import QObject, QProcess, pyqtSignal
from PyQt5.QtWidgets import QApplication

from .model import Alert

__all__ = ["Speaker", "espeak_command", "render_wav"]

log = logging.getLogger(__name__)

MAX_WAITING = 4
WORDS_PER_MINUTE = 175


def espeak_command() -> str | None:
    """The espeak-ng (or espeak) program on this system, or None."""
    return shutil.which("espeak-ng") or shutil.which("espeak")


def espeak_args(text: str, wav: str | None = None) -> list[str]:
    """The arguments :class:`Speaker` runs espeak-ng with; ``wav``: write the audio there instead of playing it."""
    return ["-s", str(WORDS_PER_MINUTE)] + (["-w", wav] if wav else []) + ["--", text]


def render_wav(text: str, path: str, timeout: float = 20.0) -> bool:
    """Write ``text`` as spoken by the same engine and voice to a WAV file (tests, and a check that speech works
    on a machine without a sound card). False when there is no engine."""
    program = espeak_command()
    if program is None:
        return False
    return subprocess.run([program, *espeak_args(text, path)], capture_output=True, timeout=timeout).returncode == 0


class Speaker(QObject):
    spoken = pyqtSignal(str)              # a text handed to the engine (or beeped for)
    engineChanged = pyqtSignal(str)

    def __init__(self, parent: QObject | None = None, engine: str | None = None) -> None:
        """``engine``: "espeak-ng", "qt", "beep" or None for the best this system has."""
        super().__init__(parent)
        self.muted = False
        self._queue: list[Alert] = []
        self._process: QProcess | None = None
        self._tts = None
        self._program = espeak_command()
        self.engine = engine or self._best_engine()
        log.info("spoken alerts through %s", self.engine)

    def _best_engine(self) -> str:
        if self._program:
            return "espeak-ng"
        try:
            from PyQt5.QtTextToSpeech import QTextToSpeech
            if QTextToSpeech.availableEngines():
                tts = QTextToSpeech(self)
                if tts.state() != QTextToSpeech.BackendError:     # speechd listed, but no daemon: no voice
                    self._tts = tts
                    return "qt"
                tts.deleteLater()
        except ImportError:
            pass
        return "beep"

    @property
    def busy(self) -> bool:
        return self._process is not None and self._process.state() != QProcess.NotRunning

    @property
    def waiting(self) -> tuple[Alert, ...]:
        return tuple(self._queue)

    def set_muted(self, muted: bool) -> None:
        """Mute: nothing more is said, what waits is dropped and what is being said stops."""
        self.muted = muted
        if muted:
            self._queue.clear()
            if self.busy:
                self._process.kill()
            if self._tts is not None:
                self._tts.stop()

    def say(self, alert: Alert) -> None:
        if self.muted:
            return
        self._queue.append(alert)
        self._queue.sort(key=lambda a: a.severity)          # stable: the same urgency keeps its order
        del self._queue[MAX_WAITING:]
        self._next()

    def _next(self) -> None:
        if self.busy or not self._queue:
            return
        alert = self._queue.pop(0)
        if self.engine == "espeak-ng":
            process = QProcess(self)
            process.finished.connect(lambda *_: self._done(process))
            process.errorOccurred.connect(lambda error: self._failed(process, error))
            self._process = process
            process.start(self._program, espeak_args(alert.text))
        elif self.engine == "qt" and self._tts is not None:
            self._tts.say(alert.text)                        # QTextToSpeech queues and never blocks
        else:
            QApplication.beep()
        self.spoken.emit(alert.text)
        if self.engine != "espeak-ng":
            self._next()

    def _done(self, process: QProcess) -> None:
        if self._process is process:
            self._process = None
        process.deleteLater()
        self._next()

    def _failed(self, process: QProcess, error) -> None:
        if error == QProcess.FailedToStart:                  # gone since we looked: beep from now on
            log.warning("espeak-ng failed to start; alerts beep instead")
            self.engine = "beep"
            self.engineChanged.emit(self.engine)
            self._done(process)

    def close(self) -> None:
        self._queue.clear()
        if self.busy:
            self._process.kill()
            self._process.waitForFinished(500)
