"""The MAVLink inspector's counts (issue 31): every message type from every system and component the link
carries, its rate and its newest values, for a pilot or developer to see what the vehicle really says.

The reader calls :meth:`MessageInspector.seen` once per parsed frame (its hot path: a dict lookup and three
stores); :meth:`snapshot` builds the immutable :class:`Inspection` the viewer reads, from any thread.
"""
from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass

__all__ = ["MessageInspector", "Inspection", "MessageStat", "RATE_WINDOW"]

RATE_WINDOW = 1.0            # s: the rate is the count over the last whole window (or the current one, if longer)


@dataclass(frozen=True)
class MessageStat:
    system: int
    component: int
    name: str                                   # HEARTBEAT, ATTITUDE, ...
    count: int
    rate_hz: float
    age_s: float                                # since the newest one
    fields: tuple[tuple[str, object], ...]      # the newest one's fields, in the message's order


@dataclass(frozen=True)
class Inspection:
    available: bool
    messages: tuple[MessageStat, ...] = ()
    why: str = ""                               # when not available: why, in words

    @staticmethod
    def unavailable(why: str) -> "Inspection":
        return Inspection(False, (), why)


class _Entry:
    __slots__ = ("count", "msg", "last", "window_start", "window_count", "rate")

    def __init__(self, now: float) -> None:
        self.count = 0
        self.msg = None
        self.last = now
        self.window_start = now
        self.window_count = 0
        self.rate = 0.0


def _value(v):
    if isinstance(v, (bytes, bytearray)):
        return bytes(v).rstrip(b"\0").decode("ascii", "replace")
    if isinstance(v, float) and not math.isfinite(v):
        return str(v)
    return v


class MessageInspector:
    def __init__(self, clock=time.monotonic) -> None:
        self._clock = clock
        self._lock = threading.Lock()
        self._entries: dict[tuple[int, int, str], _Entry] = {}

    def seen(self, msg, system: int, component: int) -> None:
        now = self._clock()
        key = (system, component, msg.get_type())
        with self._lock:
            e = self._entries.get(key)
            if e is None:
                e = self._entries[key] = _Entry(now)
            e.count += 1
            e.window_count += 1
            e.msg, e.last = msg, now
            if now - e.window_start >= RATE_WINDOW:
                e.rate = e.window_count / (now - e.window_start)
                e.window_start, e.window_count = now, 0

    def snapshot(self) -> Inspection:
        now = self._clock()
        with self._lock:
            items = [(k, e.count, e.msg, e.last, e.window_start, e.window_count, e.rate)
                     for k, e in self._entries.items()]
        out = []
        for (system, component, name), count, msg, last, start, window_count, rate in sorted(items):
            elapsed = now - start
            if elapsed >= RATE_WINDOW:                       # nothing closed the window: the rate is falling
                rate = window_count / elapsed
            elif rate == 0.0 and window_count >= 2 and last > start:    # the first second: what came so far
                rate = (window_count - 1) / (last - start)
            fields = tuple((f, _value(getattr(msg, f, None))) for f in msg.get_fieldnames())
            out.append(MessageStat(system, component, name, count, rate, now - last, fields))
        return Inspection(True, tuple(out))
