"""The flight trail behind the drone on the map: the last ten minutes, fading with age (no Qt here).

Points are kept as latitude/longitude when the vehicle has one (so a moved home, which arming sets,
does not drag the trail along), else as metres from home; :meth:`Trail.bands` places them in view
metres, split into bands from the oldest (faintest) to the newest. A replay's whole track is a trail
whose ages run over the recording instead of ten minutes.
"""
from __future__ import annotations

import collections
import math
from typing import Callable

__all__ = ["Trail", "TRAIL_SECONDS", "TRAIL_STEP", "TRAIL_IDLE"]

TRAIL_SECONDS = 600.0        # the live trail: the last ten minutes
TRAIL_STEP = 0.5             # m: a new point once the vehicle moved this far ...
TRAIL_IDLE = 2.0             # s: ... or this long passed


class Trail:
    def __init__(self, seconds: float | None = TRAIL_SECONDS) -> None:
        """``seconds``: how long points are kept; None keeps them all (a replay's track)."""
        self.seconds = seconds
        # (time, east, north, (lat, lon) or None): east/north as first seen, lat/lon when there was one
        self._points: collections.deque[tuple[float, float, float, tuple[float, float] | None]] = collections.deque()
        # each point in view metres, placed once for the view's frame (None: not placed yet)
        self._placed: collections.deque[tuple[float, float] | None] = collections.deque()
        self._placed_for: Callable | None = None

    def __len__(self) -> int:
        return len(self._points)

    @property
    def span(self) -> float:
        """Seconds from the oldest point kept to the newest."""
        return self._points[-1][0] - self._points[0][0] if self._points else 0.0

    def add(self, now: float, east: float, north: float, latlon: tuple[float, float] | None = None,
            force: bool = False) -> bool:
        """A new position; kept if it moved or time passed (or ``force``). Returns whether it was kept."""
        if self._points and not force:
            t, e, n, _ = self._points[-1]
            if math.hypot(east - e, north - n) < TRAIL_STEP and now - t < TRAIL_IDLE:
                return False
        self._points.append((now, east, north, latlon))
        self._placed.append(None)
        if self.seconds is not None:
            while self._points and now - self._points[0][0] > self.seconds:
                self._points.popleft()
                self._placed.popleft()
        return True

    def bands(self, count: int, now: float, to_view: Callable[[float, float], tuple[float, float]] | None
              ) -> list[list[tuple[float, float]]]:
        """``count`` polylines in view metres, oldest first; consecutive bands share their joining point.

        ``to_view(lat, lon)`` places points that have a latitude/longitude (None: use their metres)."""
        span = self.seconds if self.seconds is not None else max(self.span, 1e-6)
        end = now if self.seconds is not None else (self._points[-1][0] if self._points else 0.0)
        out: list[list[tuple[float, float]]] = [[] for _ in range(count)]
        if to_view != self._placed_for:            # another frame (home moved, another vehicle): place again
            self._placed = collections.deque([None] * len(self._points))
            self._placed_for = to_view
        placed: list[tuple[float, float]] = []
        last = None
        for (t, e, n, latlon), where in zip(self._points, self._placed):
            if where is None:                        # only the points added since the last call
                where = to_view(*latlon) if latlon is not None and to_view is not None else (e, n)
            placed.append(where)
            band = min(count - 1, max(0, int((1.0 - (end - t) / span) * count)))
            if last is not None and last[0] != band:
                out[band].append(last[1])
            out[band].append(where)
            last = (band, where)
        self._placed = collections.deque(placed)
        return out
