"""File › Connect, Disconnect, Replay a flight: switch the window's vehicle without a restart.

The new drone is opened on a worker thread (an Ice server answers when it answers; a .tlog is read whole) BESIDE
the one flown now, and handed to the window on the UI thread only once a heartbeat came in on it; only then is the
one left behind closed, also off the UI thread. The window keeps flying the old vehicle until the new one has
answered, and never waits. A new link that stays silent for :data:`ANSWER_TIMEOUT` s is closed with a clear
error; the old vehicle was never let go of (a dead address used to drop a flying vehicle at once). Why the new link
does not open (the system's own words: "Connection refused", "Name or service not known") is said the moment the
driver meets it, and again in the final error: it used to wait out the 15 s and then blame the heartbeat. The last
few connections that reached a vehicle are kept in the settings, newest first.
"""
from __future__ import annotations

import logging
import re
import threading
import time

from PyQt5.QtCore import QObject, QSettings, pyqtSignal

from driver.vehicle import VehicleConfig

from .choice import Choice, parse_key
from .opener import Disconnected, Opened, close_quietly, open_choice

__all__ = ["ConnectionController", "RECENT_KEY", "MAX_RECENT", "ANSWER_TIMEOUT", "open_error"]

log = logging.getLogger(__name__)

RECENT_KEY = "connect/recent"
MAX_RECENT = 8
#: s a new connection has to hear its first heartbeat (ArduPilot sends one a second; a radio link may take a few)
#: before it is given up, the vehicle flown now still flown. A lab registry's own wait for a vehicle comes first.
ANSWER_TIMEOUT = 15.0
POLL = 0.05                              # s between looks at the new link's state, on the worker thread


class ConnectionController(QObject):
    opened = pyqtSignal(object)              # Opened: the window flies it from now on
    failed = pyqtSignal(str)                 # why a connection could not be opened
    busyChanged = pyqtSignal(bool)           # opening one now
    recentChanged = pyqtSignal()
    answered = pyqtSignal(object)            # Choice: a vehicle answered on it (it joined the recent ones)
    trouble = pyqtSignal(str)                # why the link being tried does not open, as soon as the driver knows
    _arrived = pyqtSignal(object, object)    # (Opened or None, error text): from the worker to the UI thread
    _troubled = pyqtSignal(object, str)      # (Choice, the system's words): from the worker to the UI thread

    def __init__(self, qsettings: QSettings, base: VehicleConfig | None = None, log_dir: str | None = None,
                 certs: str | None = None, speedup: float = 1.0, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._qsettings = qsettings
        self.base = base or VehicleConfig()
        self.log_dir = log_dir
        self.certs = certs
        self.speedup = speedup
        self.current: Opened | None = None
        self._opening: Choice | None = None
        self._unconfirmed: Choice | None = None
        self._closers: list[threading.Thread] = []
        self.answer_timeout = ANSWER_TIMEOUT
        self.clock = time.monotonic          # what answer_timeout is counted on (a test hands in its own)
        self._arrived.connect(self._on_arrived)
        self._troubled.connect(self._on_trouble)

    # -- what is flown now ------------------------------------------------------------------------------
    def adopt(self, drone, choice: Choice | None = None, sim=None, fleet=None, first: str = "") -> None:
        """The drone (or fleet) the window was started with (the command line's): closed like any other when left,
        and ``choice`` joins the recent connections once a vehicle answers on it."""
        self.current = Opened(drone, choice, sim, fleet, first)
        self._unconfirmed = choice

    @property
    def busy(self) -> bool:
        return self._opening is not None

    @property
    def connected(self) -> bool:
        return self.current is not None and not isinstance(self.current.drone, Disconnected)

    # -- recent connections -----------------------------------------------------------------------------
    def recent(self) -> list[Choice]:
        keys = self._qsettings.value(RECENT_KEY, [], type=list) or []
        return [c for c in (parse_key(str(k)) for k in keys) if c is not None]

    def remember(self, choice: Choice) -> None:
        keys = [choice.key] + [c.key for c in self.recent() if c.key != choice.key]
        self._qsettings.setValue(RECENT_KEY, keys[:MAX_RECENT])
        self._qsettings.sync()
        self.recentChanged.emit()

    # -- switching ----------------------------------------------------------------------------------------
    def connect_to(self, choice: Choice) -> bool:
        """Open ``choice`` in the background; False (and ``failed``) at once if it cannot be one."""
        problem = choice.problem()
        if problem:
            self.failed.emit(problem)
            return False
        if self._opening is not None:
            self.failed.emit(f"still opening {self._opening.label}")
            return False
        self._opening = choice
        self.busyChanged.emit(True)
        config, wait, clock = self.base, self.answer_timeout, self.clock
        still = (f"; still connected to {self.current.drone.description}" if self.connected else "")

        def work() -> None:
            try:
                opened = open_choice(choice, config, self.log_dir, self.certs, self.speedup)
            except Exception as exc:                 # noqa: BLE001 - said to the pilot, the old link flies on
                log.info("cannot open %s", choice.label, exc_info=True)
                self._hand_over(None, f"{choice.label}: {' '.join(str(exc).split()) or type(exc).__name__}{still}")
                return
            answered, why = _answers(opened, wait, lambda reason: self._say_trouble(choice, reason), clock)
            if not answered:
                close_quietly(opened)
                because = f" ({why})" if why else ""
                self._hand_over(None, f"{choice.label}: no heartbeat in {wait:g} s{because}, link closed{still}")
            elif not self._hand_over(opened, ""):
                close_quietly(opened)               # the window closed meanwhile: nobody flies it
        threading.Thread(target=work, name="connect", daemon=True).start()
        return True

    def _hand_over(self, opened: Opened | None, error: str) -> bool:
        """From the worker to the UI thread; False when the window (and this controller) went meanwhile."""
        try:
            self._arrived.emit(opened, error)
        except RuntimeError:                         # the wrapped QObject was deleted
            return False
        return True

    def _say_trouble(self, choice: Choice, reason: str) -> None:
        try:
            self._troubled.emit(choice, reason)
        except RuntimeError:                         # the window closed meanwhile
            pass

    def _on_trouble(self, choice: Choice, reason: str) -> None:
        if choice == self._opening:                  # not a link given up since
            self.trouble.emit(f"{choice.label}: {reason}; trying again for up to {self.answer_timeout:g} s")

    def _on_arrived(self, opened: Opened | None, error: str) -> None:
        """On the UI thread: the new link answered (switch to it) or did not (say why; nothing else changes)."""
        choice, self._opening = self._opening, None
        self.busyChanged.emit(False)
        if opened is None:
            self.failed.emit(error)
            return
        self._switch(opened)
        self._unconfirmed = choice

    def confirm(self, s) -> None:
        """Every snapshot: the connection joins the recent ones once a vehicle answers on it (a typo never does)."""
        if self._unconfirmed is not None and s.connected:
            choice, self._unconfirmed = self._unconfirmed, None
            self.remember(choice)
            self.answered.emit(choice)

    def disconnect(self) -> None:
        """Leave the vehicle (it is sent zero velocity and hovers, as on quitting) and show no vehicle."""
        if self.connected:
            self._unconfirmed = None
            self._switch(Opened(Disconnected(), None))

    def _switch(self, opened: Opened) -> None:
        old, self.current = self.current, opened
        self.opened.emit(opened)                      # the window flies the new one first...
        if old is not None:                           # ...then the old one is closed, off the UI thread
            t = threading.Thread(target=close_quietly, args=(old,), name="disconnect", daemon=True)
            t.start()
            self._closers.append(t)

    def close(self, wait: float = 5.0) -> None:
        """Quitting: close what is flown now, and wait for those being closed."""
        if self.current is not None:
            close_quietly(self.current)
            self.current = None
        for t in self._closers:
            t.join(timeout=wait)
        self._closers.clear()


_OPEN_ERROR = re.compile(r"^cannot open .*?: (?:\[Errno -?\d+\] )?(?P<why>.+?)(?:; retrying)?$")


def open_error(text: str, connection: str = "") -> str:
    """The system's reason in a driver line about a link that does not open ("cannot open tcp:h:1: [Errno 111]
    Connection refused; retrying" -> "Connection refused"); "" for any other line."""
    if connection and text.startswith(f"cannot open {connection}: "):
        text = "cannot open x: " + text[len(f"cannot open {connection}: "):]
    found = _OPEN_ERROR.match(text)
    return found.group("why") if found else ""


def _answers(opened: Opened, wait: float, trouble, clock=time.monotonic) -> tuple[bool, str]:
    """On the worker thread: whether a heartbeat comes in on the new link within ``wait`` s of ``clock``, and the
    latest reason the driver gave for not opening it (``trouble(reason)`` is called at once for each new one)."""
    deadline = clock() + wait
    seen, why = 0, ""
    connection = opened.choice.target if opened.choice is not None else ""
    while True:
        s = opened.drone.state()
        if s.connected:
            return True, why
        for m in s.messages_since(seen):
            seen = m.index
            reason = open_error(m.text, connection) if m.source == "driver" else ""
            if reason and reason != why:
                why = reason
                trouble(reason)
        if clock() > deadline:
            return False, why
        time.sleep(POLL)
