"""Reading every parameter: PARAM_REQUEST_LIST, then each missing index asked again until the set is complete.

As QGroundControl's ParameterManager: the list is asked for once; while the vehicle streams it, gaps (frames
lost on the radio) are only noted. Once the stream has gone quiet, every index still missing is asked for
with PARAM_REQUEST_READ, a few at a time (ArduPilot queues only a handful of reads), each asked again when its
answer does not come: at once when a read sent after it has been answered (the vehicle answers its queue in
order, so the earlier one or its answer was lost), else after the link's timeout (the vehicle's one round-trip
estimate, :class:`driver.core.roundtrip.RoundTrip`, which the list's first answer and every read answered once
feed). How many are out at once
adapts as TCP's window does: one more for each answered, half as many when reads go unanswered altogether (a
burst of interference, a radio's full buffer), so a link that drops frames when busy is not kept busier. Unlike QGroundControl, which gives up on an index after a few tries, this goes on while
the link is up: a radio at 30 % loss still ends with every parameter. It ends when the set is complete, or
when the link is lost (the table keeps what arrived; the next fetch asks only for what is missing).

All methods run with the driver's state lock held and return the messages to send.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core.roundtrip import RoundTrip

log = logging.getLogger(__name__)

__all__ = ["Download", "LIST_RETRY", "LIST_TRIES", "READ_WINDOW"]

LIST_RETRY = 2.0        # s without any PARAM_VALUE after PARAM_REQUEST_LIST before it is asked again
LIST_TRIES = 5          # PARAM_REQUEST_LIST sent without any answer before the download fails
QUIET_MIN = 0.4         # s: the stream counts as over after this long without a new index (or more: see quiet)
QUIET_MAX = 2.0
READ_WINDOW = 16        # most PARAM_REQUEST_READs outstanding at once (ArduPilot answers reads from a small queue)
MIN_WINDOW = 2
READ_TIMEOUT_MIN = 0.1  # s before an unanswered read is asked again (or the link's timeout, whichever is longer)


@dataclass
class Download:
    """One download in progress: which indexes have arrived and what is asked for; ``roundtrip``: the vehicle's."""
    started: float
    roundtrip: RoundTrip
    expected: int | None = None
    have: set[int] = field(default_factory=set)
    listing: bool = True                 # waiting for the list's stream; False: re-asking by index
    list_sent: float = -1.0
    list_tries: int = 0
    last_new: float = 0.0                # when the last new index arrived
    gap: float = 0.05                    # smoothed time between new indexes while the list streams
    asked: dict[int, tuple[float, int]] = field(default_factory=dict)   # index -> (when, order), oldest first
    sequence: int = 0                    # reads sent so far, to order them
    tries: dict[int, int] = field(default_factory=dict)       # index -> reads sent for it
    reads: int = 0                       # PARAM_REQUEST_READs sent
    window: float = READ_WINDOW          # reads outstanding at once now

    @property
    def missing(self) -> int:
        return 0 if self.expected is None else self.expected - len(self.have)

    @property
    def complete(self) -> bool:
        return self.expected is not None and len(self.have) >= self.expected

    def quiet(self) -> float:
        """How long without a new index before the stream counts as over: ten of its gaps, and a request's timeout
        (the next value may be a re-asked one's answer)."""
        return min(QUIET_MAX, max(QUIET_MIN, 10.0 * self.gap + self.roundtrip.timeout()))

    def arrived(self, index: int, count: int, now: float) -> bool:
        """A PARAM_VALUE with ``index`` of ``count``; True when it was new."""
        if count != self.expected:
            if self.expected is not None:
                log.info("parameter count changed from %s to %d", self.expected, count)
                self.have = {i for i in self.have if i < count}
            self.expected = count
        if index in self.have or index >= count:
            return False
        if self.listing and not self.have and self.list_tries == 1:
            self.roundtrip.sample(now - self.list_sent)   # the list asked once: its first value answers it
        asked = self.asked.pop(index, None)
        if asked is not None:
            sent, order = asked
            self.window = min(READ_WINDOW, self.window + 1.0 / self.window)
            if self.tries.get(index) == 1:           # a re-asked one cannot say which read it answers (Karn)
                self.roundtrip.sample(now - sent)
            for earlier in [i for i, (_, o) in self.asked.items() if o < order]:
                del self.asked[earlier]              # answered in order: those were lost, ask again now
        elif self.listing and self.have:
            self.gap = 0.9 * self.gap + 0.1 * max(0.0, now - self.last_new)
        self.have.add(index)
        self.last_new = now
        return True

    def service(self, now: float, target: tuple[int, int]) -> tuple[list, str | None]:
        """Messages to send now, and why the download failed (None while it goes on)."""
        system, component = target
        if self.expected is None or (self.listing and not self.list_tries):
            # nothing heard yet, or only a stray value (while MAVLink FTP was tried): (re)ask for the list
            if self.list_sent < 0 or now - self.list_sent >= LIST_RETRY:
                if self.list_tries >= LIST_TRIES:
                    return [], f"the vehicle did not answer PARAM_REQUEST_LIST ({self.list_tries} times)"
                self.list_sent, self.list_tries, self.last_new = now, self.list_tries + 1, now
                return [mavlink.MAVLink_param_request_list_message(system, component)], None
            return [], None
        if self.listing:
            if now - self.last_new < self.quiet():
                return [], None
            self.listing = False                             # the stream is over: ask for the gaps
        timeout = max(READ_TIMEOUT_MIN, self.roundtrip.timeout())
        timed_out = [index for index, (sent, _) in self.asked.items() if now - sent >= timeout]
        for index in timed_out:
            del self.asked[index]
        if timed_out:
            self.window = max(MIN_WINDOW, self.window / 2.0)
        out = []
        for index in range(self.expected):
            if len(self.asked) >= int(self.window):
                break
            if index not in self.have and index not in self.asked:
                self.sequence += 1
                self.asked[index] = (now, self.sequence)
                self.tries[index] = self.tries.get(index, 0) + 1
                out.append(mavlink.MAVLink_param_request_read_message(system, component, b"", index))
        self.reads += len(out)
        return out, None
