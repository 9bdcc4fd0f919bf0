"""The MAVLink inspector's counts: every message type from every system and component the link
carries, its rate and its newest values, for a pilot or developer to see what the vehicle really says.

The reader calls :meth:`MessageInspector.seen` once per parsed frame (its hot path: a dict lookup and two
stores); :meth:`snapshot` builds the immutable :class:`Inspection` the viewer reads, from any thread.
"""
from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass

__all__ = ["MessageInspector", "Inspection", "MessageStat", "RATE_WINDOW"]

RATE_WINDOW = 1.0            # s: the rate is the count over the last window of at least this long between snapshots


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
    """Written by the reader (count, msg); the rest by :meth:`MessageInspector.snapshot`."""
    __slots__ = ("count", "msg", "last", "seen_count", "window_start", "window_count", "rate")

    def __init__(self, msg, now: float) -> None:
        self.count, self.msg = 0, msg
        self.last = self.window_start = now          # newest arrival seen by a snapshot; the rate's window
        self.seen_count = self.window_count = 0
        self.rate = 0.0


def _value(v):
    if isinstance(v, (bytes, bytearray)):
        return bytes(v).rstrip(b"\0").decode("ascii", "replace")
    if isinstance(v, float) and not math.isfinite(v):
        return str(v)
    return v


class MessageInspector:
    """The reader's side is :meth:`seen` (no clock, no lock: a count and the message); rates and ages are worked
    out by :meth:`snapshot` from how the counts moved between snapshots, so the viewer's refresh sets their
    resolution (5 per second in the inspector's window)."""

    def __init__(self, clock=time.monotonic) -> None:
        self._clock = clock
        self._lock = threading.Lock()               # snapshots from several threads
        self._entries: dict[tuple[int, int, str], _Entry] = {}

    def seen(self, msg, system: int, component: int, name: str) -> None:
        e = self._entries.get((system, component, name))
        if e is None:
            e = self._entries[(system, component, name)] = _Entry(msg, self._clock())
        e.count += 1
        e.msg = msg

    def snapshot(self) -> Inspection:
        now = self._clock()
        out = []
        with self._lock:
            for (system, component, name), e in sorted(list(self._entries.items())):
                count, msg = e.count, e.msg
                if count != e.seen_count:            # something came since the last snapshot
                    e.last, e.seen_count = now, count
                elapsed = now - e.window_start
                if elapsed >= RATE_WINDOW:
                    e.rate = (count - e.window_count) / elapsed
                    e.window_start, e.window_count = now, count
                fields = tuple((f, _value(getattr(msg, f, None))) for f in msg.get_fieldnames())
                out.append(MessageStat(system, component, name, count, e.rate, now - e.last, fields))
        return Inspection(True, tuple(out))
