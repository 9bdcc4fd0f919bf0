"""One direction of one peer's radio link: what :class:`~driver.sim.faults.LinkFaults` does to its frames.

A frame goes in with :meth:`Pipe.send`; what may go on the wire now comes back,
in order; frames held for latency or reordering come out of :meth:`Pipe.due`
later (the sim's clock thread asks every step). Times are real seconds from the
faults' clock. Latency keeps the order (each frame leaves no earlier than the one
before it, as on a serial radio); only ``reorder`` swaps frames.
"""
from __future__ import annotations

import math
import random
import threading
from collections import deque
from typing import Callable

from .faults import Faults, LinkCounters, LinkFaults

__all__ = ["Pipe"]

HOLD_MAX = 0.5      # real s: a frame held back for reordering leaves by then even if no later frame came


class Pipe:
    def __init__(self, faults: Faults, settings: Callable[[], LinkFaults], counters: LinkCounters,
                 rng: random.Random, lock: threading.Lock | None = None) -> None:
        self.faults = faults
        self.settings = settings
        self.counters = counters
        self.rng = rng
        self.lock = lock if lock is not None else threading.Lock()   # shared by the pipes sharing counters
        self.burst_until = -math.inf
        self.held = None                     # (frame, since) held back for reordering
        self.queue: deque = deque()          # (due, frame) in due order
        self.last_due = -math.inf

    def send(self, frame, now: float, extra_loss: float = 0.0) -> list:
        """Frames to deliver now, in order (``frame`` itself, a copy, a frame held back before it, or none)."""
        with self.lock:
            c = self.counters
            c.frames += 1
            if self.faults.dead(now):
                c.outage_lost += 1
                return self._flush_locked(now)
            s = self.settings()
            rng = self.rng
            if now < self.burst_until:
                c.burst_lost += 1
                return self._flush_locked(now)
            if s.burst_rate > 0 and rng.random() < s.burst_rate:
                self.burst_until = now + s.burst_seconds
                c.bursts += 1
                c.burst_lost += 1
                return self._flush_locked(now)
            if (extra_loss > 0 and rng.random() < extra_loss) or (s.loss > 0 and rng.random() < s.loss):
                c.lost += 1
                return self._flush_locked(now)
            copies = [frame]
            if s.duplicate > 0 and rng.random() < s.duplicate:
                copies.append(frame)
                c.duplicated += 1
            if self.held is None and s.reorder > 0 and rng.random() < s.reorder:
                self.held = (copies.pop(), now)
                c.reordered += 1
            elif self.held is not None:
                copies.append(self.held[0])          # the held frame goes right behind this one
                self.held = None
            for item in copies:
                self._schedule(item, now, s)
            return self._flush_locked(now)

    def due(self, now: float) -> list:
        """Frames whose time has come (dropped instead while the link is dead)."""
        with self.lock:
            if self.held is not None and now - self.held[1] >= HOLD_MAX:
                frame, _ = self.held
                self.held = None
                self._schedule(frame, now, self.settings())
            return self._flush_locked(now)

    @property
    def pending(self) -> int:
        return len(self.queue) + (self.held is not None)

    # -- internals (lock held) ----------------------------------------------------------------------
    def _schedule(self, frame, now: float, s: LinkFaults) -> None:
        delay = s.latency
        if s.jitter > 0:
            delay += self.rng.uniform(-s.jitter, s.jitter)
        delay = max(0.0, delay)
        due = max(now + delay, self.last_due)
        self.last_due = due
        if due > now:
            self.counters.delayed += 1
        self.queue.append((due, frame))

    def _flush_locked(self, now: float) -> list:
        out = []
        queue = self.queue
        dead = None
        while queue and queue[0][0] <= now:
            _, frame = queue.popleft()
            if dead is None:
                dead = self.faults.dead(now)
            if dead:
                self.counters.outage_lost += 1
                continue
            self.counters.delivered += 1
            out.append(frame)
        return out
