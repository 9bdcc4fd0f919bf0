"""Saying alerts out loud without ever blocking the window.

:class:`Speaker` queues texts and says one at a time: through espeak-ng when the system has it, else Qt's own
QTextToSpeech when PyQt5 ships it with a working engine, else the desktop's beep. espeak-ng runs as a child
process started and waited for by a speech thread of its own, so the UI thread only appends to a list (starting a
process from the UI thread, as QProcess does, forks the whole viewer there: tens of milliseconds on a busy
laptop). A more urgent alert jumps the queue, and the queue never grows stale: at most a few alerts wait, the least
urgent are dropped first.
"""
from __future__ import annotations

import logging
import shutil
import subprocess
import threading

from PyQt5.QtCore import QObject, pyqtSignal
from PyQt5.QtWidgets import QApplication

from .model import Alert

__all__ = ["Speaker", "espeak_command", "espeak_args", "render_wav"]

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
    spoken = pyqtSignal(str)              # a text handed to the engine (or beeped for); from the speech thread
    engineChanged = pyqtSignal(str)

    def __init__(self, parent: QObject | None = None, engine: str | None = None) -> None:
        """``engine``: "espeak-ng", "qt", "beep" or None for the best this system has."""
        super().__init__(parent)
        self.muted = False
        self._queue: list[Alert] = []
        self._cond = threading.Condition()
        self._process: subprocess.Popen | None = None
        self._speaking = False
        self._closed = False
        self._tts = None
        self._program = espeak_command()
        self.engine = engine or self._best_engine()
        self._thread: threading.Thread | None = None
        if self.engine == "espeak-ng":
            self._thread = threading.Thread(target=self._run, name="speech", daemon=True)
            self._thread.start()
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
        """Something is being said now."""
        return self._speaking

    @property
    def waiting(self) -> tuple[Alert, ...]:
        with self._cond:
            return tuple(self._queue)

    def set_muted(self, muted: bool) -> None:
        """Mute: nothing more is said, what waits is dropped and what is being said stops."""
        self.muted = muted
        if muted:
            with self._cond:
                self._queue.clear()
                process = self._process
            if process is not None and process.poll() is None:
                process.kill()
            if self._tts is not None:
                self._tts.stop()

    def say(self, alert: Alert) -> None:
        """Queue ``alert``; returns at once."""
        if self.muted or self._closed:
            return
        if self.engine != "espeak-ng":
            if self.engine == "qt" and self._tts is not None:
                self._tts.say(alert.text)                    # QTextToSpeech queues and never blocks
            else:
                QApplication.beep()
            self.spoken.emit(alert.text)
            return
        with self._cond:
            self._queue.append(alert)
            self._queue.sort(key=lambda a: a.severity)      # stable: the same urgency keeps its order
            del self._queue[MAX_WAITING:]
            self._cond.notify()

    def _run(self) -> None:
        """The speech thread: one espeak-ng process at a time, most urgent first."""
        while True:
            with self._cond:
                while not self._queue and not self._closed:
                    self._cond.wait()
                if self._closed:
                    return
                alert = self._queue.pop(0)
                self._speaking = True
                try:
                    self._process = subprocess.Popen([self._program, *espeak_args(alert.text)],
                                                     stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                                     stderr=subprocess.DEVNULL)
                except OSError:
                    log.warning("espeak-ng failed to start; alerts beep instead", exc_info=True)
                    self.engine, self._speaking = "beep", False
                    self.engineChanged.emit(self.engine)
                    return
            self.spoken.emit(alert.text)
            self._process.wait()
            with self._cond:
                self._process = None
                self._speaking = False

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._queue.clear()
            process = self._process
            self._cond.notify_all()
        if process is not None and process.poll() is None:
            process.kill()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
