"""Real time for the simulated vehicle, or a hand-driven stand-in so tests never race the wall clock.

The sim's clock thread paces its steps on ``now()`` and sleeps with ``wait()``;
link latency and outages are dated with ``now()`` too. :class:`ManualClock` only
moves when a test calls :meth:`ManualClock.advance`, so a test can check the
speed-up or a latency exactly, on a loaded machine as on an idle one.
"""
from __future__ import annotations

import threading
import time

__all__ = ["RealClock", "ManualClock"]


class RealClock:
    @staticmethod
    def now() -> float:
        return time.monotonic()

    @staticmethod
    def wait(stop: threading.Event, seconds: float) -> bool:
        """Sleep ``seconds`` unless ``stop`` is set first; True when stopped."""
        return stop.wait(seconds)


class ManualClock:
    """Time that stands still until :meth:`advance`; the sim's thread sleeps on it like on real time."""

    POLL = 0.05        # real s between looks at the stop event while asleep

    def __init__(self, start: float = 1000.0) -> None:
        self._now = start
        self._cond = threading.Condition()
        self._deadlines: list[float] = []       # of the threads asleep in wait() right now

    def now(self) -> float:
        with self._cond:
            return self._now

    def advance(self, seconds: float) -> None:
        with self._cond:
            self._now += seconds
            self._cond.notify_all()

    def wait(self, stop: threading.Event, seconds: float) -> bool:
        with self._cond:
            deadline = self._now + seconds
            self._deadlines.append(deadline)
            self._cond.notify_all()
            try:
                while self._now < deadline:
                    if stop.is_set():
                        return True
                    self._cond.wait(self.POLL)
            finally:
                self._deadlines.remove(deadline)
                self._cond.notify_all()
        return stop.is_set()

    def settle(self, timeout: float = 10.0) -> bool:
        """Block until a thread sleeps on this clock waiting for time still to come: the sim has done all
        that the time so far asked of it. False if that did not happen within ``timeout`` real seconds."""
        with self._cond:
            return self._cond.wait_for(lambda: any(d > self._now for d in self._deadlines), timeout)
