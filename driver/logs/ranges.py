"""Which bytes of a log are held: sorted, disjoint [start, end) ranges, and the partial file's map on disk.

A download keeps ``FILE.part`` (the bytes at their offsets) and ``FILE.part.json`` (the log's id, its
time_utc and the ranges written to the .part), so a dropped link or an app restart resumes where it was instead
of fetching the log again. The map is written only after the bytes it names are in the .part file: the .part is
fsynced before the map, the map's tmp file before it replaces the map, so after a power loss the map never claims
bytes the disk does not hold; and a map read back is clipped to the .part's size all the same.
"""
from __future__ import annotations

import bisect
import copy
import json
import os

__all__ = ["Ranges", "PartMap", "load_part_map", "save_part_map"]


class Ranges:
    """Held bytes as sorted, disjoint spans; adding one is a binary search (a lossy download holds thousands of
    spans and adds one per packet). A span, once made, is never changed in place (adding replaces it), so
    :meth:`copy` shares them."""

    def __init__(self, spans=()) -> None:
        self.spans: list[list[int]] = []
        self.starts: list[int] = []             # each span's start, for the binary search
        self._total = 0
        for a, b in spans:
            self.add(int(a), int(b))

    def add(self, start: int, end: int) -> int:
        """Hold [start, end); returns how many of those bytes are new."""
        if end <= start:
            return 0
        spans, starts = self.spans, self.starts
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

    def copy(self) -> "Ranges":
        """These ranges as they are now, untouched by later adds: two list copies, no walk over the spans (the
        download hands one to the .part's writer four times a second)."""
        new = copy.copy(self)                   # the total with it; the lists its own
        new.spans, new.starts = list(self.spans), list(self.starts)
        return new

    def held_from(self, offset: int) -> int:
        """The end of the held run that covers ``offset`` (``offset`` itself when it is not held)."""
        i = bisect.bisect_right(self.starts, offset) - 1
        if i >= 0 and self.spans[i][1] > offset:
            return self.spans[i][1]
        return offset

    def whole(self, end: int) -> bool:
        """Every byte of [0, end) held: one span from 0 (a check each tick, so not a walk over the gaps)."""
        return end <= 0 or bool(self.spans) and self.spans[0][0] == 0 and self.spans[0][1] >= end

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
        for a, b in spans[max(0, bisect.bisect_right(self.starts, start) - 1):]:
            if a >= end:
                break
            total += max(0, min(b, end) - max(a, start))
        return total

    def gaps(self, start: int, end: int):
        """The gaps in [start, end), in order, lazily (a binary search finds ``start``)."""
        spans, at = self.spans, start
        i = bisect.bisect_right(self.starts, start) - 1
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
    """``size``: where the vehicle's stream said the log ends; ``listed``: its size in the list it was fetched by."""

    def __init__(self, log_id: int, time_utc: int, ranges: Ranges, size: int | None, listed: int = 0) -> None:
        self.log_id, self.time_utc, self.ranges, self.size, self.listed = log_id, time_utc, ranges, size, listed


def load_part_map(path: str) -> PartMap | None:
    """``path``.part.json, None if absent or unreadable (then the .part is not trusted)."""
    try:
        with open(path + ".part.json") as f:
            raw = json.load(f)
        ranges = Ranges(raw["ranges"]).clipped(os.path.getsize(path + ".part"))
        return PartMap(int(raw["id"]), int(raw["time_utc"]), ranges, raw.get("size"), int(raw.get("listed", 0)))
    except (OSError, ValueError, KeyError, TypeError):
        return None


def save_part_map(path: str, part: PartMap) -> None:
    """The map of what ``path``.part holds (its writes flushed by the caller), once the .part is on the disk:
    written whole to a temporary file, then renamed, so a full disk leaves the previous map as it was."""
    try:
        with open(path + ".part", "rb") as data:
            os.fsync(data.fileno())             # fsync is per file: it writes what any handle of it wrote
    except FileNotFoundError:
        pass
    tmp = path + ".part.json.tmp"
    try:
        # dumps, not dump: json.dump encodes in Python, and a lossy download's map holds tens of thousands of
        # spans, written four times a second on the thread that reads the link
        text = json.dumps({"id": part.log_id, "time_utc": part.time_utc, "size": part.size, "listed": part.listed,
                           "ranges": part.ranges.spans}, separators=(",", ":"))
        with open(tmp, "w") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path + ".part.json")
    except OSError:
        try:
            os.remove(tmp)
        except OSError:
            pass
        raise
