"""A recording played in the window: the replay bar (pause, speed, seek, restart, its clock) in place of the
stick line, and the flight controls greyed out (a recording cannot be flown)."""
from __future__ import annotations

import logging

from PyQt5.QtCore import QObject

from ..refresh import TEXT_HZ

__all__ = ["ReplayControls"]

log = logging.getLogger(__name__)


class ReplayControls(QObject):
    """``window``: the main window (its adapter, replay bar and the slot under the controls it shares)."""

    def __init__(self, window) -> None:
        super().__init__(window)
        self.window = w = window
        bar = w.replayBar
        bar.pauseRequested.connect(lambda pause: self._act(lambda r: r.pause() if pause else r.resume()))
        bar.speedRequested.connect(lambda speed: self._act(lambda r: setattr(r, "speed", speed)))
        bar.seekRequested.connect(lambda t: self._act(lambda r: r.seek(t)))
        bar.restartRequested.connect(lambda: self._act(lambda r: r.restart()))
        channel = w.refresh.add(TEXT_HZ, self.show_progress)
        w.adapter.stateChanged.connect(lambda _s: channel.mark())
        self.use()

    def _act(self, act) -> None:
        if self.window.adapter.replay is not None:
            act(self.window.adapter.replay)

    def use(self) -> None:
        """The connection flown now: the bar and greyed controls for a recording, the sticks' line otherwise."""
        w = self.window
        replay = w.adapter.replay is not None
        w.bottomSlot.setCurrentWidget(w.replayBar if replay else w.stickLine)   # nothing else moves
        w.controlsRow.setEnabled(not replay)

    def show_progress(self) -> None:
        """The replay's clock (TEXT_HZ)."""
        replay = self.window.adapter.replay
        if replay is None:
            return
        try:
            self.window.replayBar.set_progress(replay.position, replay.duration, replay.paused, replay.speed,
                                               replay.finished)
        except Exception:               # noqa: BLE001 - a finished replay may drop its file
            log.debug("replay progress unavailable", exc_info=True)
