"""One log as the Flight logs window shows it: an immutable row, and the words its cells read.

Rows are made by the controller from the vehicle's list, the files already in the logs folder and the driver's
progress snapshot; the table only draws them, so nothing on screen is a guess of the widget's own.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, replace
from enum import Enum

__all__ = ["LogRow", "RowState", "size_text", "date_text", "rate_text", "time_left_text"]


class RowState(Enum):
    ON_VEHICLE = "on the vehicle"
    PARTIAL = "partly downloaded"          # a .part is kept: Download resumes it
    QUEUED = "waiting"
    DOWNLOADING = "downloading"
    CHECKING = "checking"                  # the file is complete; DFReader reads it to its end
    SAVED = "saved"
    FAILED = "failed"


@dataclass(frozen=True)
class LogRow:
    log_id: int
    size: int                              # bytes, as the vehicle listed it (or as its stream ended)
    time_utc: int                          # s since 1970; 0: the vehicle had no clock
    path: str                              # where it is (or will be) saved
    state: RowState = RowState.ON_VEHICLE
    held: int = 0                          # bytes on disk (in the .part while downloading)
    rate: float = 0.0                      # bytes/s over the last second
    seconds_left: float | None = None
    reason: str = ""                       # why it failed or stopped, in the vehicle's or the driver's words

    @property
    def fraction(self) -> float:
        if self.state is RowState.SAVED:
            return 1.0
        return min(1.0, self.held / self.size) if self.size > 0 else 0.0

    @property
    def running(self) -> bool:
        """Waiting or under way: Cancel is what the pilot can do to it."""
        return self.state in (RowState.QUEUED, RowState.DOWNLOADING, RowState.CHECKING)

    @property
    def openable(self) -> bool:
        return self.state is RowState.SAVED

    def but(self, **changes) -> "LogRow":
        return replace(self, **changes)


def size_text(size: int) -> str:
    """Bytes in decimal units, as docs/flight-logs.md's kB/s and MB figures."""
    if size >= 1_000_000:
        return f"{size / 1e6:.2f} MB"
    if size >= 1_000:
        return f"{size / 1e3:.1f} kB"
    return f"{size} B"


def date_text(time_utc: int) -> str:
    return time.strftime("%Y-%m-%d %H:%M", time.gmtime(time_utc)) if time_utc > 0 else "no date"


def rate_text(row: LogRow) -> str:
    return f"{size_text(int(row.rate))}/s" if row.state is RowState.DOWNLOADING and row.rate > 0 else ""


def time_left_text(row: LogRow) -> str:
    if row.state is not RowState.DOWNLOADING or row.seconds_left is None:
        return ""
    seconds = int(round(row.seconds_left))
    return f"{seconds // 60}:{seconds % 60:02d}" if seconds >= 60 else f"{seconds} s"
