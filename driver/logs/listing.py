"""The vehicle's list of logs, complete under loss: LOG_REQUEST_LIST out, LOG_ENTRY in.

What ArduCopter 4.6.3 does (tests/data/recordings/arducopter-4.6-sitl-logs.*) and what is done about it:

* LOG_REQUEST_LIST 0..0xffff gives one LOG_ENTRY per log; a list of ids past the last one floods LOG_ENTRY (size
  0) for ~40 s. So only 0..0xffff is asked, ids that went missing are asked again as a range inside last_log_num,
  and entries outside 1..last_log_num are ignored.
* The vehicle sends the first entry on receipt (handle_log_request_list calls handle_log_send_listing), so a list
  of one log is over at once; while a listing or a transfer runs, a new LOG_REQUEST_LIST is refused ("Log download
  in progress"). So each try asks twice, LOG_REQUEST_END before each LOG_REQUEST_LIST: the second never finds the
  first listing running, a transfer left running (a cancelled download whose END was lost) cannot refuse it, and
  one lost request or entry costs no try.

Pure: no lock, no clock of its own (``now`` comes with each call), no I/O.
"""
from __future__ import annotations

import logging

from ..core.roundtrip import RoundTrip
from .model import LogEntry
from .wire import ALL_IDS, LogRequests

__all__ = ["LogListing", "LIST_TRIES"]

log = logging.getLogger(__name__)

# Each try asks twice; a request and its first answer get through 30 % loss each way with 0.7 x 0.7 = 0.49, so a
# try fails with about 0.51 x 0.51 = 0.26, and twelve in a row with 10^-7: a list that fails this often is a link
# that does not carry LOG_ENTRY at all.
LIST_TRIES = 12
# The least wait (s) before the list is asked again: 40 ms took the list at 30 % loss each way from 0.2-0.44 s to
# 0.02-0.12 s in half of the bench's runs (cff542e). With the link's round trip measured, its timeout; each try
# waits half as long again as the first: at 30 % loss half the round trips fail, and a listing asked again is only
# ended and begun anew.
LIST_RETRY = 0.04


class LogListing:
    """One list in progress. ``roundtrip``: the vehicle's estimate of the link's round trip
    (driver.core.roundtrip); a list asked once times it, from its LOG_REQUEST_LIST to the first LOG_ENTRY after it."""

    def __init__(self, requests: LogRequests, roundtrip: RoundTrip) -> None:
        self._requests = requests
        self.roundtrip = roundtrip
        self.entries: dict[int, LogEntry] = {}
        self.last: int | None = None            # the vehicle's last_log_num, once an entry told it
        self.tries = 0
        self.quiet_until = 0.0                  # no new try before this (the clock's time)
        self._asked_at: float | None = None     # the last LOG_REQUEST_LIST, until its first answer times it
        self.failure = ""                       # why the list was given up

    @property
    def complete(self) -> bool:
        return self.last is not None and not self.missing()

    def result(self) -> tuple[LogEntry, ...]:
        return tuple(sorted(self.entries.values(), key=lambda e: e.id))

    def missing(self) -> list[int]:
        """Ids inside last_log_num with no entry yet."""
        if self.last is None:
            return []
        return [i for i in range(1, self.last + 1) if i not in self.entries]

    def requests(self, now: float) -> list:
        """What to send now: a try (END, LIST, END, LIST) when the last one went unanswered long enough; [END]
        when the list is given up (``failure`` says why)."""
        if now < self.quiet_until or self.complete or self.failure:
            return []
        wanted = self.missing()
        if self.tries >= LIST_TRIES:
            shown = ", ".join(str(i) for i in wanted[:10]) if wanted else "all"
            self.failure = f"the log list is incomplete after {LIST_TRIES} tries (missing: {shown})"
            return [self._requests.end()]
        self.tries += 1
        self.quiet_until = now + self._wait()
        self._asked_at = now
        first, last = (wanted[0], wanted[-1]) if self.last is not None else ALL_IDS
        log.debug("log list: try %d, ids %d-%d", self.tries, first, last)
        ask = [self._requests.end(), self._requests.list(first, last)]
        return ask + ask

    def _wait(self) -> float:
        base = max(LIST_RETRY, self.roundtrip.timeout()) if self.roundtrip.measured else LIST_RETRY
        return base * (1 + (self.tries - 1) / 2)

    def on_entry(self, m, now: float) -> bool:
        """A LOG_ENTRY; True once the list is complete."""
        if self._asked_at is not None:
            if self.tries == 1:                 # asked once: its first answer times the link (Karn's rule)
                self.roundtrip.sample(now - self._asked_at)
            self._asked_at = None
        if m.num_logs == 0 or m.last_log_num == 0:
            self.last = 0
        else:
            self.last = m.last_log_num if self.last is None else max(self.last, m.last_log_num)
        if 1 <= m.id <= m.last_log_num:
            self.entries[m.id] = LogEntry(m.id, m.size, m.time_utc)
            # a listing under way: the rest of it is given a try's wait to come before the ids still missing are
            # asked again (asking ends the listing and begins another). A fixed 0.3 s here made six logs through
            # 30 % loss each way take 0.36 s (median of 60 seeded runs against the simulator on a 4 ms round trip,
            # tests/test_logs_filler.py's link), the try's wait 0.12 s; on a 0.1 s round trip both 0.35-0.38 s
            self.quiet_until = now + self._wait()
        if self.complete:
            self.quiet_until = 0.0
            return True
        return False
