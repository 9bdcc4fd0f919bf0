"""Which LOG_REQUEST_DATA to send for one log: the stream first, then the gaps that loss left.

Events in (a LOG_DATA heard, time passing), requests out (``(offset, count)`` pairs): no I/O, no lock and no clock
of its own, so a test drives it on any clock it likes.

How ArduPilot serves requests (AP_Logger_MAVLinkLogTransfer.cpp) and what is done about it:

* LOG_REQUEST_DATA (ofs, count) streams 90-byte LOG_DATA in order, served at once, on receipt, up to num_sends
  packets a call (SITL 40, USB 250, a flow-controlled serial port 10, a radio without flow control 1). A request
  that ends within them ends the transfer, so the next request of the same batch is served too; a longer one
  keeps the transfer running, and while it runs a new request is dropped (the Solo's 3.3 moves the transfer to
  it instead).
* The first request runs from where the held bytes end to the end of the log, open-ended: the log's true end is
  where a short packet (or one of count 0) says it is, so a log that grew since the list comes whole.
* Then the gaps are filled by pipelining: one request per missing packet (within any link's one call, so never
  dropped for a transfer still running, and never a held byte asked again), as many in flight as the link
  carries in a round trip (:meth:`GapFiller.window`), sent at a little more than the pace the vehicle answers
  (:meth:`GapFiller._paced`): a batch that overflows the vehicle's transmit buffer leaves a transfer running, and
  every request after it is dropped.
* The vehicle answers in order, so when a request's packet arrives every request sent before it that is still
  unanswered was lost (or its packet was): it is asked again on the next sweep over the gaps. Silence for the
  link's timeout clears them all. Once fewer are missing than the vehicle sends in a round trip, each goes several
  times (:meth:`GapFiller._copies`), so the tail is not a string of round trips.
* A stream silent for a round trip within a few packets of the listed size lost its end (the short packet): it is
  probed with the gaps or, a few packets short of the listed size, the packets up to it are gaps like the others.
  A long gap (a dropped link, a burst of loss) with nothing else in flight is streamed as one request. Nothing
  held is ever thrown away.
"""
from __future__ import annotations

import logging
from collections import OrderedDict

from ..core.roundtrip import RoundTrip
from .ranges import Ranges
from .wire import CHUNK, OPEN_END

__all__ = ["GapFiller"]

log = logging.getLogger(__name__)

# Gap requests in flight: FILL_GAIN x the packets the link carries in a round trip, raised for the share loss takes
# (1.5 gave a clean radio 1.5 requests per packet it can carry instead of 3, and a lossy TCP link as many as
# before: aa49dc0) ...
FILL_GAIN = 1.5
# ... counting a round trip of at least 50 ms: one measured while the vehicle's transmit buffer runs dry is short,
# and fewer requests would keep it dry (on the radio the window had shrunk to 4 with answers in 2 ms: bff0406) ...
FILL_RTT_MIN = 0.05
# ... never fewer than 4 (a radio port's 1 kB transmit buffer holds 9 LOG_DATA: 4 keep it from running dry
# between answers) ...
FILL_MIN = 4
# ... nor more than 8,192: the simulator's 30,000 LOG_DATA/s over TCP in a 0.1 s round trip, with the gain and
# loss, is ~9,000; a smoothed round trip swollen by the link's own queues would ask for tens of thousands at once.
FILL_MAX = 8192
# Requests in flight and their pace are raised by 1 / (the share that arrives), at most 2.5x: frames that a reader
# starved of CPU drops look like loss too, and more requests would only have more dropped (2e50b8e).
LOSS_FACTOR_MAX = 2.5
# Gap requests go at 1.25x the rate the vehicle answers them, at most 20 ms of that pace at once, and the sender
# looks again within 5 ms: in bursts of up to 2,048, 20-45 % of the requests that reached ArduPilot were dropped
# for a transfer its full transmit buffer left running; paced, 2 MB through 30 % loss went from 2.9x to 1.8x the
# clean floor (bff0406).
PACE_GAIN = 1.25
PACE_BURST = 0.02
PACE_TICK = 0.005
# The least silence (s) that says a stream or the gap requests went unanswered: the ticker's own beat (50 ms), so a
# wait never ends just before answers already queued are read (a timer exactly on it asked them again: 5390b2b).
SILENCE_MIN = 0.05
# The rate at which gap requests are answered is measured over at least 0.1 s (and two round trips), enough
# answers to count on a radio (53 LOG_DATA/s at 57,600 baud: five).
FILL_RATE_PERIOD = 0.1
# The share a stream lost is counted over at least 50 of its packets (fewer say nothing at 10 % loss).
LOSS_SAMPLE = 50
# The last few packets of the log: each asked twice, even with no loss seen (a lost one costs a round trip with
# nothing else in flight: 4759ff1; 32 at most, under load it doubled hundreds: aa49dc0); a lost end this close to
# the listed size is asked as gaps, further off probed and streamed (74ceab4). (The last 8 three times made no
# difference in 80 seeded runs at 2, 10 and 30 % loss, on TCP and a radio: the copies below cover a lossy tail.)
LAST_FEW = 32
# Each gap request goes at most 6 times, the vehicle's room in the link's own round trip allowing: the last thousand
# packets at 30 % loss were ten round trips, now three or four (cff542e).
COPIES_MAX = 6
# A gap longer than the window, bounded to 32..256 packets, is streamed when nothing else is in flight: asked a
# packet each, the rest of a log after a burst of loss took a frame a packet, and in the fault matrix's bursts cell
# the frames are what the link loses (34.5 s with the pacing alone, 30.6-32.2 s streamed: 74ceab4).
STREAM_GAP_MIN = 32
STREAM_GAP_MAX = 256
# A stream whose packets came within 8 of the listed size and then stopped for a round trip (20 ms at least) lost
# its end: the end follows them in the same call. 0.06-0.13 s saved whenever the last packet was lost (cff542e).
END_NEAR = 8
END_WAIT = 0.02


def _for_loss(arriving: float) -> float:
    """How many times more to send so that as many arrive: 1 / the share that arrives, at most LOSS_FACTOR_MAX."""
    return LOSS_FACTOR_MAX if arriving * LOSS_FACTOR_MAX <= 1.0 else 1.0 / arriving


class GapFiller:
    """The requests for one log by LOG_DATA. ``size``: the listed size (a lower bound until the stream's end is
    seen); ``held``: the bytes held already (a resumed .part's, else none); ``end``: where the vehicle's stream said
    the log ends, if a resumed .part knows it; ``roundtrip``: the vehicle's one estimate of the link's round trip
    (driver.core.roundtrip), which the stream's first packet and every gap request answered once feed.

    :meth:`on_data` for each LOG_DATA of the log, :meth:`requests` when the sender may send (each tick, and by
    :attr:`due`); :attr:`done` once every byte to the end is held."""

    def __init__(self, size: int, held: Ranges, end: int | None, roundtrip: RoundTrip) -> None:
        self.size, self.held, self.end = size, held, end
        self.roundtrip = roundtrip
        self.rate = 0.0                         # packets/s the vehicle sends (a stream's, or the answers')
        self.loss = 0.0                         # share of a stream's packets lost on the way
        self.last_heard = 0.0                   # the last LOG_DATA of the log
        self.due: float | None = None           # call requests() again by then, news or not (None: on news only)
        self.bytes_requested = self.bytes_rerequested = 0
        # the stream under way: (start, end) of the request, when sent, its first and last packets heard
        self._window: tuple[int, int] | None = None
        self._sent_at = 0.0
        self._first_heard: float | None = None
        self._first_ofs = self._last_ofs = 0
        self._stream_heard = 0                  # packets of the window that arrived
        self._streamed = False                  # the open-ended pass was asked
        # the gap requests: offset -> (count, sent at), in the order sent; how often each offset was asked
        self._asks: OrderedDict[int, tuple[int, float]] = OrderedDict()
        self._times_asked: dict[int, int] = {}
        self._asked_at = 0.0
        self._cursor = 0                        # where the sweep over the gaps goes on
        self._partial_asks: dict[int, int] = {}  # offset -> count of gap requests for less than a packet: their
                                                 # short answers are not the log's end
        self._goes_on_at: set[int] = set()      # offsets where a probe of the unknown end found a full packet
        self._answered = 0                      # gap requests answered since _answered_since
        self._answered_since: float | None = None
        self._pace_credit = 0.0                 # gap requests that may go now (paced at the answer rate)
        self._pace_at: float | None = None

    @property
    def done(self) -> bool:
        return self.end is not None and self.held.whole(self.end)

    def restart(self, held: Ranges) -> None:
        """What was held is another log's: ``held`` (what this session got since) instead, the end unknown."""
        self.held, self.end = held, None

    def link_lost(self) -> None:
        """Nothing in flight will be answered: the stream and the gap requests are forgotten."""
        self._window = None
        self._asks.clear()

    # -- events in ---------------------------------------------------------------------------------------------
    def on_data(self, offset: int, count: int, now: float) -> int:
        """A LOG_DATA of this log (whichever request it answers); returns how many of its bytes are new."""
        count = min(count, CHUNK)
        self.last_heard = now
        added = self.held.add(offset, offset + count) if count else 0
        expected = self._partial_asks.get(offset, CHUNK)
        ask = self._asks.get(offset)
        if ask is not None:                     # a gap request's answer: the ones sent before it went unanswered
            while self._asks.popitem(last=False)[0] != offset:
                pass
            expected = ask[0]
            if self._times_asked.get(offset) == 1:      # asked once: the answer is its own (Karn's rule)
                self.roundtrip.sample(now - ask[1])
            self._answered += 1
            top = offset + count
            if self.end is None and count == CHUNK and top == self.held.spans[-1][1] and \
                    not top < self.size <= top + LAST_FEW * CHUNK:
                self._goes_on_at.add(top)       # the log goes on past the probe: stream the rest (not the last few)
            if len(self._asks) <= self.window() // 2 or now - self._asked_at >= PACE_TICK:
                self.due = now                  # room for more
        if count < expected and (self.end is None or offset + count < self.end):
            self.end = offset + count           # a short packet: the log ends here (the vehicle's word)
        window = self._window
        if window is None or not window[0] <= offset < window[1]:
            return added                        # queued from an earlier request: kept, but it times nothing
        if self._first_heard is None:
            self._first_heard, self._first_ofs = now, offset
            self.roundtrip.sample(now - self._sent_at)
        self._last_ofs = offset
        self._stream_heard += 1
        if offset + count >= window[1] or count < CHUNK:
            self._measure_stream()
            self._window = None
            self.due = now
        return added

    # -- requests out ------------------------------------------------------------------------------------------
    def requests(self, now: float) -> list[tuple[int, int]]:
        """The LOG_REQUEST_DATA (offset, count) to send now, in order, a request repeated where it goes twice."""
        self.due = None
        if self._window is not None:
            silent_until = max(self._sent_at, self.last_heard) + self._stream_wait()
            if now < silent_until:
                self.due = silent_until         # looked at again when the silence would end it
                return []
            self._measure_stream()
            self._window = None                 # silence: the rest of that window was lost
        held_to = self.held.spans[-1][1] if self.held.spans else 0
        if self.end is None and (not self._streamed or not held_to or held_to in self._goes_on_at):
            # from where the held bytes end to the log's own end: the first pass, or a log still going on; twice
            # for the first pass (a second request is dropped while the first one streams, and 3.3 only begins
            # again at the same place) and for the last few packets (served within one call): a lost one would
            # cost a round trip with nothing else in flight
            first = not self._streamed and not held_to
            tail = self._streamed and held_to and self.size - held_to <= LAST_FEW * CHUNK
            ask = self._stream(held_to, OPEN_END - held_to, now)
            return [ask, ask] if first or tail else [ask]
        return self._fill(now)

    @property
    def rtt(self) -> float:
        """The link's smoothed round trip (its first guess until an answer times it)."""
        return self.roundtrip.estimate

    def window(self) -> int:
        """Gap requests in flight: what the link carries in a round trip (its packet rate times the round trip),
        with a margin, and more for the requests and answers a loss takes (the stream's loss share, taken for both
        ways): enough to keep the vehicle sending, not more, so a radio is not flooded."""
        more = _for_loss((1.0 - self.loss) ** 2)
        return int(min(FILL_MAX, max(FILL_MIN, FILL_GAIN * self.rate * max(self.rtt, FILL_RTT_MIN) * more)))

    def _fill(self, now: float) -> list[tuple[int, int]]:
        """Ask for the missing packets one request each, sweeping the gaps from the cursor, while fewer than the
        window are in flight; a gap longer than the window, with nothing in flight, is streamed instead."""
        if self._asks and now - max(self._asked_at, self.last_heard) >= max(SILENCE_MIN, self.roundtrip.timeout()):
            self._asks.clear()                  # silence: all of them (or their answers) were lost
        self._measure_answers(now)
        window = self.window()
        room = allowed = min(window - len(self._asks), self._paced(now))    # requests that may go now
        if room <= 0:
            return []
        out: list[tuple[int, int]] = []
        end = self.end
        copies = self._copies((end - self.held.total()) // CHUNK if end is not None else None, window)
        if end is None:                         # the stream's last packet was lost: probe the end with the gaps
            end = self.held.spans[-1][1]
            listed = -(-self.size // CHUNK) * CHUNK
            if end < listed <= end + LAST_FEW * CHUNK:
                # a few packets short of the listed size, where the log goes on at least: those packets are gaps
                # like the others, each asked for a whole packet, so the last one's answer comes short where the
                # log ends (or full if it grew); further short, the probe below, then a stream (a lost run)
                end = listed
            elif end not in self._asks:
                self._asks[end] = (CHUNK, now)
                self._times_asked[end] = self._times_asked.get(end, 0) + 1
                out += [(end, CHUNK)] * 2       # twice: one packet, whose loss costs a whole round
                room -= 1
        gaps, wrapped = self.held.gaps(self._cursor, end), self._cursor == 0
        longest = max(min(window, STREAM_GAP_MAX), STREAM_GAP_MIN) * CHUNK
        while room > 0:
            gap = next(gaps, None)
            if gap is None:
                if wrapped:
                    break
                self._cursor, wrapped = 0, True     # the next sweep: what went unanswered is asked again
                gaps = self.held.gaps(0, end)
                continue
            a, b = gap
            if b - a > longest and not self._asks and not out:
                self._cursor = b
                return [self._stream(a, -(-(b - a) // CHUNK) * CHUNK, now)]
            for offset in range(a, b, CHUNK):
                if offset in self._asks:
                    continue
                count = min(CHUNK, b - offset)
                self._asks[offset] = (count, now)
                self._times_asked[offset] = self._times_asked.get(offset, 0) + 1
                if count < CHUNK:
                    self._partial_asks[offset] = count  # its answer is short too, and not the log's end
                self.bytes_requested += count
                out += [(offset, count)] * copies
                self._cursor = offset + count
                room -= 1
                if not room:
                    break
        if self.rate > 0:                       # paced: what went is spent, more may go once the pace allows
            self._pace_credit -= allowed - room
            if self._pace_credit < 1.0 and len(self._asks) < window:
                self.due = now + PACE_TICK
        if out:
            self._asked_at = now
            log.debug("%d gap requests (%d in flight, window %d, rtt %.3f s, %.0f packets/s, loss %.2f)",
                      len(out), len(self._asks), window, self.rtt, self.rate, self.loss)
        return out

    def _stream(self, start: int, count: int, now: float) -> tuple[int, int]:
        """One request streamed as a window: the log's tail (open-ended) or a long gap."""
        if self.end is not None:
            count = min(count, self.end - start)
        self._window = (start, start + count)
        self._streamed = True
        self._sent_at = now
        self._first_heard = None
        self._stream_heard = 0
        upto = min(start + count, self.end if self.end is not None else max(self.size, start))
        self.bytes_requested += max(0, upto - start)
        self.bytes_rerequested += self.held.held(start, upto)
        log.debug("stream %d+%d (rtt %.3f s, %.0f packets/s)", start, count, self.rtt, self.rate)
        return start, count

    def _stream_wait(self) -> float:
        """Silence that ends a stream's window: the link's timeout; once its packets came within a few of the listed
        size, one round trip (the end follows them at once, in the same call, so silence there means the end was
        lost; a log that grew since the list keeps coming, and each packet restarts the wait)."""
        if self.end is None and self._first_heard is not None and self._last_ofs + END_NEAR * CHUNK > self.size:
            return max(END_WAIT, self.rtt)
        return max(SILENCE_MIN, self.roundtrip.timeout())

    def _copies(self, left: int | None, window: int) -> int:
        """How many times each gap request goes, ``left`` packets still missing (None: the end is not known).

        While the missing packets outnumber what the vehicle sends in a round trip, once: the vehicle is the
        bottleneck, and a copy's answer would take a missing packet's place. Fewer, and the download waits on
        round trips instead (at 30 % loss each way half the requests come to nothing, so the last thousand packets
        take ten of them): the vehicle's spare room in a round trip is spent on copies, each of which lowers the
        odds that a packet is still missing after the next one. The last few go twice even when no loss was seen:
        a lost one costs a whole round trip with nothing else in flight."""
        if left is None:
            return 1
        copies = 1 if left >= min(window // 4, LAST_FEW) else 2
        quickest = self.roundtrip.lowest
        if self.loss > 0 and self.rate > 0 and quickest is not None:
            # requests answered in one of the link's own round trips, its quickest (the smoothed one grows with the
            # queues of a busy link, where copies only queue longer: through a relay to SITL that rule received up
            # to 40 % more)
            room = self.rate * quickest * _for_loss(1.0 - self.loss)
            copies = max(copies, min(COPIES_MAX, int(room // max(1, left))))
        return copies

    # -- what the link does, measured --------------------------------------------------------------------------
    def _measure_stream(self) -> None:
        """The stream's rate (packets/s, lost ones counted) from this window's first and last packets, averaged
        with the last one, and the share of its packets the link lost."""
        first = self._first_heard
        if first is not None and self.last_heard > first and self._last_ofs > self._first_ofs:
            span = (self._last_ofs - self._first_ofs) / CHUNK
            rate = span / (self.last_heard - first)
            self.rate = rate if self.rate == 0 else 0.5 * self.rate + 0.5 * rate
            if span >= LOSS_SAMPLE:
                self.loss = max(0.0, 1.0 - self._stream_heard / (span + 1))

    def _paced(self, now: float) -> int:
        """Gap requests that may go now: a token bucket filled at PACE_GAIN times the rate the vehicle sends (over
        the share of requests that reach it), holding PACE_BURST of it, so the requests come at the pace the
        vehicle answers them rather than in bursts it drops. Unpaced while the rate is unknown."""
        if self.rate <= 0:
            return FILL_MAX
        pace = PACE_GAIN * self.rate * _for_loss(1.0 - self.loss)
        elapsed = PACE_BURST if self._pace_at is None else now - self._pace_at
        self._pace_credit = min(max(1.0, pace * PACE_BURST), self._pace_credit + pace * elapsed)
        self._pace_at = now
        return int(self._pace_credit)

    def _measure_answers(self, now: float) -> None:
        """The rate the gap requests are answered at, lost answers counted, raises the stream's: a stream cut
        short (a link that dropped, a log already mostly held) measures nothing, and a window left at FILL_MIN
        would then crawl through the whole log. Requests paced PACE_GAIN faster than answered are answered faster
        until the link is full, so the pace grows by up to PACE_GAIN each period until it stops paying."""
        if self._answered_since is None or not self._asks:
            self._answered_since, self._answered = now, 0
            return
        elapsed = now - self._answered_since
        if elapsed < max(FILL_RATE_PERIOD, 2 * self.rtt):
            return
        sample = self._answered / elapsed * _for_loss(1.0 - self.loss)
        if sample > self.rate:
            self.rate = sample
        self._answered_since, self._answered = now, 0
