"""The log download's request logic on a clock the test moves: the gap filler (driver/logs/filler.py) and the list
(driver/logs/listing.py), with no thread, no socket and no real second.

The vehicle is the simulated ArduCopter's own log serving (driver.sim's Autopilot, in this process): it serves a
LOG_REQUEST_DATA at once on receipt, up to its packets per call and its transmit buffer, and drops a request that
comes while a longer transfer runs, as ArduPilot does. Between the two, a link that delays each frame and loses a
seeded share of them each way. The driver's side is ticked as the ticker ticks it: every 50 ms, and sooner when
the filler says it is ``due``.
"""
from __future__ import annotations

import heapq
import itertools
import random

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.core.roundtrip import RoundTrip
from driver.logs.filler import GapFiller
from driver.logs.listing import LogListing
from driver.logs.ranges import Ranges
from driver.logs.wire import CHUNK, OPEN_END, LogRequests
from driver.sim import Autopilot, SimConfig
from driver.sim.dataflash import LogFolder, write_flight_log

BEAT = 0.05                    # the ticker's own wait between passes


def timed(seconds: float) -> RoundTrip:
    """The vehicle's round trip, timed once by an answer ``seconds`` after its request (as the list times it)."""
    rt = RoundTrip()
    rt.sample(seconds)
    return rt


class LossyVehicle:
    """The simulated vehicle's log serving behind a link of ``latency`` s each way that loses ``loss`` of the frames
    each way (seeded: the same run every time)."""

    def __init__(self, folder: LogFolder, loss: float = 0.0, latency: float = 0.005, seed: int = 1, **config):
        self.emitted: list = []
        self.ap = Autopilot(SimConfig(log_dir=folder.folder, seed=seed, ready_after=0.0, **config),
                            emit=self.emitted.append)
        self.rng = random.Random(seed)
        self.loss, self.latency = loss, latency
        self.factory = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
        self.order = itertools.count()
        self.uplink: list = []                  # (arrives at, order, request)
        self.downlink: list = []                # (arrives at, order, LOG_DATA)
        self.step = 1.0 / self.ap.config.rate_hz

    def send(self, log_id: int, asks: list[tuple[int, int]], now: float) -> None:
        for offset, count in asks:
            if self.rng.random() >= self.loss:
                request = self.factory.log_request_data_encode(1, 1, log_id, offset, count)
                heapq.heappush(self.uplink, (now + self.latency, next(self.order), request))

    def until(self, now: float) -> list:
        """The vehicle runs to ``now``: requests reach it, it steps; the LOG_DATA that reach the driver by then,
        with the time each arrives."""
        while True:
            next_step = self.ap.t + self.step
            if self.uplink and self.uplink[0][0] <= min(now, next_step):
                at, _, request = heapq.heappop(self.uplink)
                self.ap.handle(request)         # served on receipt
                self._leave(at)
            elif next_step <= now:
                self.ap.step(self.step)
                self._leave(next_step)
            else:
                break
        out = []
        while self.downlink and self.downlink[0][0] <= now:
            at, _, m = heapq.heappop(self.downlink)
            out.append((at, m))
        return out

    def _leave(self, at: float) -> None:
        for m in self.emitted:
            if m.get_type() == "LOG_DATA" and self.rng.random() >= self.loss:
                heapq.heappush(self.downlink, (at + self.latency, next(self.order), m))
        self.emitted.clear()


def download(vehicle: LossyVehicle, filler: GapFiller, log_id: int = 1, limit: float = 120.0):
    """Tick the filler as the driver's ticker does until the log is whole: (the bytes got by offset, every
    request sent with the bytes held when it went)."""
    got: dict[int, bytes] = {}
    sent: list[tuple[float, tuple[int, int], int]] = []
    now, beat = 0.0, 0.0
    while not filler.done:
        assert now < limit, f"not whole after {limit} s: {filler.held.total()} bytes held"
        woken = False
        for at, m in vehicle.until(now):
            if filler.on_data(m.ofs, m.count, at):
                got[m.ofs] = bytes(m.data[:m.count])
            woken = woken or (filler.due is not None and filler.due <= at)
        if woken or now >= beat or (filler.due is not None and filler.due <= now):
            asks = filler.requests(now)
            sent += [(now, ask, filler.held.held(ask[0], ask[0] + min(ask[1], CHUNK))) for ask in asks]
            vehicle.send(log_id, asks, now)
            beat = now + BEAT
        now = round(now + 0.001, 6)
    return got, sent


@pytest.fixture
def folder(tmp_path) -> LogFolder:
    logs = LogFolder(str(tmp_path / "logs"))
    write_flight_log(logs, 200_000)
    return logs


def vehicle_bytes(folder: LogFolder) -> bytes:
    with open(folder.path(1), "rb") as f:
        return f.read()


def test_the_first_request_streams_from_where_the_held_bytes_end():
    fresh = GapFiller(size=50_000, held=Ranges(), end=None, roundtrip=timed(0.01))
    assert fresh.requests(0.0) == [(0, OPEN_END)] * 2       # twice: a lost first request costs no round trip
    resumed = GapFiller(size=50_000, held=Ranges([(0, 9_000)]), end=None, roundtrip=timed(0.01))
    assert resumed.requests(0.0) == [(9_000, OPEN_END - 9_000)]   # held bytes are never asked again


@pytest.mark.parametrize("loss, config", [(0.3, {}), (0.3, {"radio_baud": 400_000}), (0.3, {"profile": "solo"}),
                                          (0.1, {})])
def test_a_log_comes_whole_through_loss_without_a_held_byte_asked_again(folder, loss, config):
    vehicle = LossyVehicle(folder, loss=loss, **config)
    own = vehicle_bytes(folder)
    filler = GapFiller(size=len(own), held=Ranges(), end=None, roundtrip=timed(0.01))
    got, sent = download(vehicle, filler)
    assert filler.end == len(own)
    assert b"".join(got[o] for o in sorted(got)) == own
    gap_asks = [(at, ask, held) for at, ask, held in sent if ask[1] <= CHUNK]
    assert gap_asks, "the loss left no gap to fill"
    assert not [a for a in gap_asks if a[2]], "a gap request asked for bytes already held"
    assert filler.bytes_rerequested <= 0.01 * len(own)


def test_the_last_missing_packets_are_asked_more_than_once_on_a_lossy_link(folder):
    vehicle = LossyVehicle(folder, loss=0.3)
    own = vehicle_bytes(folder)
    filler = GapFiller(size=len(own), held=Ranges(), end=None, roundtrip=timed(0.01))
    _, sent = download(vehicle, filler)
    last = [ask for at, ask, _ in sent if at == sent[-1][0]]     # the last tick's requests
    assert len(last) > len(set(last)), last                     # copies: a lost one would cost a round trip


def test_a_stream_that_stops_just_short_of_the_listed_size_is_judged_after_one_round_trip():
    """Its packets came to within a few of the listed size and stopped: the end (a short packet, sent in the same
    call) was lost. The filler looks again after one round trip, not three, and asks the rest as gaps."""
    size = 100 * CHUNK + 40
    filler = GapFiller(size=size, held=Ranges(), end=None, roundtrip=RoundTrip(initial=0.2))   # not timed yet
    assert filler.requests(0.0) == [(0, OPEN_END)] * 2
    for i in range(100):                                        # the short last packet (40 bytes at 9000) is lost
        filler.on_data(i * CHUNK, CHUNK, 0.03 + i * 0.0001)
    quiet = 0.03 + 99 * 0.0001
    assert filler.requests(quiet) == []
    assert filler.due == pytest.approx(quiet + filler.rtt)      # one round trip of silence, then the end is asked
    assert filler.rtt == pytest.approx(0.03)                    # (the stream's first packet measured it)
    asked = filler.due
    assert filler.requests(asked) == [(100 * CHUNK, CHUNK)]     # the rest of the listed size, as a gap
    filler.on_data(100 * CHUNK, 40, asked + 0.03)               # the short packet: the log ends here
    assert filler.end == size and filler.done


def test_a_short_answer_to_a_request_for_less_than_a_packet_is_not_the_logs_end():
    size = 30 * CHUNK
    held = Ranges([(0, 10 * CHUNK), (10 * CHUNK + 50, size)])  # 40 bytes missing in the middle
    filler = GapFiller(size=size, held=held, end=size, roundtrip=timed(0.01))
    assert filler.requests(0.0) == [(10 * CHUNK, 50)] * 2          # (the last few go twice)
    filler.on_data(10 * CHUNK, 50, 0.01)
    assert filler.end == size and filler.done


def test_what_was_in_flight_when_the_link_dropped_is_asked_again():
    size = 40 * CHUNK
    held = Ranges([(0, 5 * CHUNK), (6 * CHUNK, 17 * CHUNK), (18 * CHUNK, 30 * CHUNK), (31 * CHUNK, size)])
    filler = GapFiller(size=size, held=held, end=size, roundtrip=timed(0.01))
    first = filler.requests(0.0)
    assert sorted(set(first)) == [(5 * CHUNK, CHUNK), (17 * CHUNK, CHUNK), (30 * CHUNK, CHUNK)]
    assert filler.requests(0.001) == []                         # in flight: not asked twice
    filler.link_lost()
    assert sorted(set(filler.requests(0.002))) == sorted(set(first))


def test_a_list_asks_again_only_for_the_ids_it_misses_after_a_tries_wait():
    requests = LogRequests(lambda: (1, 1))
    rt = RoundTrip()                                            # not timed yet
    listing = LogListing(requests, rt)
    first = listing.requests(0.0)
    assert [m.get_type() for m in first] == ["LOG_REQUEST_END", "LOG_REQUEST_LIST"] * 2
    assert (first[1].start, first[1].end) == (0, 0xFFFF)
    factory = mavlink.MAVLink(None, 1, 1)
    for log_id in (1, 2, 5):                                    # of 5: entries 3 and 4 lost
        assert not listing.on_entry(factory.log_entry_encode(log_id, 5, 5, 0, 1000 * log_id), 0.01)
    assert rt.estimate == pytest.approx(0.01)                   # the list asked once timed the link
    wait = max(0.04, rt.timeout())                              # LIST_RETRY, or the link's timeout
    assert listing.requests(0.01 + wait - 0.001) == []
    again = listing.requests(0.01 + wait)
    assert [(m.get_type(), getattr(m, "start", None), getattr(m, "end", None)) for m in again] == \
        [("LOG_REQUEST_END", None, None), ("LOG_REQUEST_LIST", 3, 4)] * 2
    listing.on_entry(factory.log_entry_encode(3, 5, 5, 0, 3000), 0.2)
    assert listing.on_entry(factory.log_entry_encode(4, 5, 5, 0, 4000), 0.2)
    assert [e.id for e in listing.result()] == [1, 2, 3, 4, 5]
