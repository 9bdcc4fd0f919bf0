"""The window's display clock: each view redraws at the rate the eye needs, and nothing while it is minimised.

Telemetry arrives at 20–50 snapshots a second, but a number that changes faster than a few times a second
cannot be read, a plot a minute wide moves less than a pixel between two snapshots, and a minimised
window shows nothing at all. Views therefore do not redraw on every snapshot: each registers a
:class:`Channel` with the window's :class:`Refresh` at its own rate, says ``mark()`` when it has something
new, and its callback runs at most that often, never while the window is minimised, and at once when the
window comes back. Logic that acts on the vehicle's state (buttons that must follow it, dialogs to withdraw,
the sticks) does not go through here: it follows every snapshot.

Any view can plug in: ``channel = window.refresh.add(hz, callback)``, then ``channel.mark()``. Anything that
must know whether the pilot can see the window at all (the video) listens to ``Refresh.shownChanged``.
"""
from __future__ import annotations

import time
from typing import Callable

from PyQt5.QtCore import QEvent, QObject, QTimer, pyqtSignal
from PyQt5.QtWidgets import QWidget

__all__ = ["Refresh", "Channel", "INSTRUMENTS_HZ", "TEXT_HZ", "PLOTS_HZ"]

INSTRUMENTS_HZ = 30.0        # the attitude indicator: smooth motion
TEXT_HZ = 5.0                # numbers and status lines: as fast as anyone can read them
PLOTS_HZ = 5.0               # a 60 s strip: a fifth of a second is a pixel or two


class Channel(QObject):
    """One view's refresh: ``callback()`` at most ``hz`` times a second, only after :meth:`mark`."""

    def __init__(self, refresh: "Refresh", hz: float, callback: Callable[[], None]) -> None:
        super().__init__(refresh)
        self._refresh = refresh
        self._callback = callback
        self.period = 1.0 / hz
        self._marked = False
        self._ran_at = float("-inf")
        self.runs = 0                            # how often the callback ran (for tests and benches)
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.timeout.connect(self._run)

    @property
    def pending(self) -> bool:
        """Marked and not yet redrawn."""
        return self._marked

    def mark(self) -> None:
        """There is something new to show: redraw within one period (or when the window comes back)."""
        self._marked = True
        self._schedule()

    def _schedule(self) -> None:
        if self._marked and self._refresh.shown and not self._timer.isActive():
            wait = self._ran_at + self.period - time.monotonic()
            self._timer.start(int(max(0.0, wait) * 1000))

    def _stop(self) -> None:
        self._timer.stop()

    def _run(self) -> None:
        if not self._marked or not self._refresh.shown:
            return
        self._marked = False
        self._ran_at = time.monotonic()
        self.runs += 1
        self._callback()


class Refresh(QObject):
    """Watches one top-level window; its channels run only while the window is not minimised."""

    shownChanged = pyqtSignal(bool)          # False when the window is minimised, True when it is back

    def __init__(self, window: QWidget) -> None:
        super().__init__(window)
        self._window = window
        self._channels: list[Channel] = []
        self._shown = not window.isMinimized()
        window.installEventFilter(self)

    @property
    def shown(self) -> bool:
        """Whether the pilot can see the window (it is not minimised)."""
        return self._shown

    def add(self, hz: float, callback: Callable[[], None]) -> Channel:
        channel = Channel(self, hz, callback)
        self._channels.append(channel)
        return channel

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:  # noqa: N802
        if watched is self._window and event.type() == QEvent.WindowStateChange:
            self._set_shown(not self._window.isMinimized())
        return False

    def _set_shown(self, shown: bool) -> None:
        if shown == self._shown:
            return
        self._shown = shown
        for channel in self._channels:
            channel._schedule() if shown else channel._stop()
        self.shownChanged.emit(shown)
