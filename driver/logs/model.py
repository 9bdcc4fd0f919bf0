"""What the logs part tells its callers: the vehicle's logs as listed, a download's progress, and what an operation
came to. Immutable values, safe to hand to any thread."""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["LogEntry", "LogOutcome", "LogProgress"]


@dataclass(frozen=True)
class LogEntry:
    id: int
    size: int
    time_utc: int               # s since 1970 (0: the vehicle had no clock)


@dataclass(frozen=True)
class LogOutcome:
    """What a list, download or erase came to; ``ok`` False with ``reason`` in the vehicle's or our words."""
    name: str
    ok: bool
    reason: str = ""
    entries: tuple = ()         # LogEntry, by id (list and erase)
    log_id: int = 0
    path: str = ""
    size: int = 0
    seconds: float = 0.0
    bytes_received: int = 0     # LOG_DATA bytes that arrived (duplicates too)
    bytes_requested: int = 0    # bytes asked for, first asks and gap re-asks together (of the size known then)
    bytes_rerequested: int = 0  # of those, bytes already held when asked (merged into a gap's window)
    resumed_from: int = 0       # bytes already held in the .part when this download began
    messages: int = 0           # DataFlash messages DFReader read
    ending: str = ""            # what the log ends with after its last whole message (an unfinished record,
                                # padding), as check.py tells it; "" when it ends on a whole message

    @property
    def rate(self) -> float:
        """Bytes a second fetched by this download."""
        return (self.size - self.resumed_from) / self.seconds if self.seconds > 0 else 0.0


@dataclass(frozen=True)
class LogProgress:
    """The download under way, for a progress bar: bytes held of size (the size may still grow), rate, time left."""
    log_id: int
    path: str
    size: int
    held: int
    rate: float                 # bytes/s over the last second
    phase: str                  # "listing", "downloading", "checking", "erasing"

    @property
    def seconds_left(self) -> float | None:
        return (self.size - self.held) / self.rate if self.rate > 0 else None
