"""Which bytes of a log are held: sorted, disjoint [start, end) ranges, and the partial file's map on disk.

A download keeps ``FILE.part`` (the bytes at their offsets) and ``FILE.part.json`` (the log's id, its
time_utc and the ranges written to the .part), so a dropped link or an app restart resumes where it was instead
of fetching the log again. The map is written only after the bytes it names are in the .part file.
"""
from __future__ import annotations

import bisect
import json
import os

__all__ = ["Ranges", "PartMap", "load_part_map", "save_part_map"]


class Ranges:
    """Held bytes as sorted, disjoint spans; adding one is a binary search (a lossy download holds thousands of
    spans and adds one per packet)."""

    def __init__(self, spans=()) -> None:
        self.spans: list[list[int]] = []
        self._starts: list[int] = []
        self._total = 0
        for a, b in spans:
            self.add(int(a), int(b))

    def add(self, start: int, end: int) -> int:
        """Hold [start, end); returns how many of those bytes are new."""
        if end <= start:
            return 0
        spans, starts = self.spans, self._starts
        i = bisect.bisect_left(starts, start)
        if i and spans[i - 1][1] >= start:
            i -= 1                              # the span before reaches this one: merge from it
        j = i
        removed = 0
        new_start, new_end = start, end
        while j < len(spans) and spans[j][0] <= end:
            new_start, new_end = min(new_start, spans[j][0]), max(new_end, spans[j][1])
            removed += spans[j][1] - spans[j][0]
            j += 1
        spans[i:j] = [[new_start, new_end]]
        starts[i:j] = [new_start]
        added = (new_end - new_start) - removed
        self._total += added
        return added

    def total(self) -> int:
        return self._total

    def held_from(self, offset: int) -> int:
        """The end of the held run that covers ``offset`` (``offset`` itself when it is not held)."""
        for a, b in self.spans:
            if a <= offset < b:
                return b
        return offset

    def missing(self, end: int) -> list[tuple[int, int]]:
        """The gaps in [0, end)."""
        out, at = [], 0
        for a, b in self.spans:
            if a >= end:
                break
            if a > at:
                out.append((at, a))
            at = max(at, b)
        if at < end:
            out.append((at, end))
        return out

    def held(self, start: int, end: int) -> int:
        """How many bytes of [start, end) are held."""
        spans, total = self.spans, 0
        for a, b in spans[max(0, bisect.bisect_right(self._starts, start) - 1):]:
            if a >= end:
                break
            total += max(0, min(b, end) - max(a, start))
        return total

    def gaps(self, start: int, end: int):
        """The gaps in [start, end), in order, lazily (a binary search finds ``start``)."""
        spans, at = self.spans, start
        i = bisect.bisect_right(self._starts, start) - 1
        if i >= 0 and spans[i][1] > at:
            at = spans[i][1]
        i += 1
        while at < end:
            if i < len(spans) and spans[i][0] < end:
                a, b = spans[i]
                if a > at:
                    yield at, a
                at = max(at, b)
                i += 1
            else:
                yield at, end
                return

    def clipped(self, end: int) -> "Ranges":
        return Ranges((a, min(b, end)) for a, b in self.spans if a < end)


class PartMap:
    def __init__(self, log_id: int, time_utc: int, ranges: Ranges, size: int | None) -> None:
        self.log_id, self.time_utc, self.ranges, self.size = log_id, time_utc, ranges, size


def load_part_map(path: str) -> PartMap | None:
    """``path``.part.json, None if absent or unreadable (then the .part is not trusted)."""
    try:
        with open(path + ".part.json") as f:
            raw = json.load(f)
        return PartMap(int(raw["id"]), int(raw["time_utc"]), Ranges(raw["ranges"]), raw.get("size"))
    except (OSError, ValueError, KeyError, TypeError):
        return None


def save_part_map(path: str, part: PartMap) -> None:
    tmp = path + ".part.json.tmp"
    with open(tmp, "w") as f:
        json.dump({"id": part.log_id, "time_utc": part.time_utc, "size": part.size, "ranges": part.ranges.spans}, f)
    os.replace(tmp, path + ".part.json")
