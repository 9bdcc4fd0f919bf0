"""List, download and erase the vehicle's DataFlash logs over LOG_* messages, as ArduCopter answers them.

What ArduCopter 4.6.3 does (tests/data/recordings/arducopter-4.6-sitl-logs.*, README there) and what is done
about it here:

* LOG_REQUEST_LIST 0..0xffff gives one LOG_ENTRY per log; a list of ids past the last one floods LOG_ENTRY (size
  0) for ~40 s. So only 0..0xffff is asked, ids that went missing are asked again as a range inside last_log_num,
  entries outside 1..last_log_num are ignored, and LOG_REQUEST_END follows every listing. The vehicle sends the
  first entry on receipt (a list of one log is over at once), so each try asks twice, END before each LIST: the
  second never finds the first listing running, and one lost request or entry costs no try.
* LOG_REQUEST_DATA (ofs, count) streams 90-byte LOG_DATA in order. ArduPilot serves a request at once, on
  receipt, up to num_sends packets (SITL 40, USB 250, a flow-controlled serial port 10, a radio without flow
  control 1: AP_Logger_MAVLinkLogTransfer.cpp); one that ends within them ends the transfer, so the next request
  of the same batch is served too. A longer one keeps the transfer running, and while it runs (or a listing does)
  a new request is dropped (the Solo's 3.3 moves the transfer to it instead), so every listing is preceded by
  LOG_REQUEST_END. A download first asks from where the held bytes end to the end of the log (open-ended: the
  log's true end is where a short packet, or a packet of count 0, says it is, so a log that grew since the list
  is fetched whole). Then the gaps that loss left are filled by pipelining: one request per missing packet (never
  more than any link's one call sends, so never dropped for a transfer still running, and never a held byte asked
  again), as many in flight as the link carries in a round trip (its packet rate, measured on the stream, times
  the round trip, x1.5, over the share of requests and answers the stream's loss says arrive), sent at 1.25x the
  pace the vehicle sends (over the share of requests that arrive) in bursts of at most 20 ms of it: a batch that
  overflows the vehicle's transmit buffer leaves a transfer running, and every request after it is dropped. The
  vehicle answers in order, so when a request's packet arrives every request sent before it that is still
  unanswered was lost (or its packet was): it is asked again on the next sweep over the gaps; silence for two
  round trips clears them all; once fewer are missing than the vehicle sends in a round trip, each goes several
  times (its spare room spent on copies, so the tail is not a string of round trips), the last few at least
  twice, the very last three times. A stream silent for a round trip within a few packets of the listed size
  lost its end (the short packet): that is probed with the gaps, or, a few packets short of the listed size, the
  packets up to it are gaps like the others. A gap longer than 256 packets or that window (a dropped link, a burst of loss), nothing else in
  flight, is streamed as one request. Nothing held is ever thrown away: no log is restarted because chunks were
  lost.
* LOG_REQUEST_END stops the stream but hundreds of queued LOG_DATA still come: any LOG_DATA of the log being
  fetched is kept, whichever request it answers.
* Armed, the vehicle ignores every LOG_* request (the first with "Disarm for log download"): the request fails
  with that text.

The bytes go to ``FILE.part`` with a map of the ranges held in ``FILE.part.json`` (ranges.py): a dropped link or
an app restart resumes from it. The finished file has the size the vehicle's stream ended at and DFReader reads
it to its last byte (check.py); only then is it renamed to FILE.

Threads: requests come from any thread; ``on_message``, ``on_text`` and ``service`` run on the driver's reader and
ticker threads with the vehicle's lock held; futures are settled by the vehicle's Notifier; the file check runs
on a thread of its own.
"""
from __future__ import annotations

import errno
import logging
import os
import threading
from collections import OrderedDict, deque
from concurrent.futures import Future
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..ftp.reader import FtpList, FtpSpanRead
from .check import LogFileError, check_dataflash
from .ranges import PartMap, Ranges, load_part_map, save_part_map

__all__ = ["LogControl", "LogEntry", "LogOutcome", "LogProgress", "DISARM_TEXT"]

log = logging.getLogger(__name__)

CHUNK = 90                      # bytes in one LOG_DATA
ALL_IDS = (0, 0xFFFF)
OPEN_END = 0xFFFFFFFF
DISARM_TEXT = "Disarm for log download"
LIST_TRIES = 12                 # listings of the missing ids before the list is given up
LIST_RETRY_FIRST = 0.04         # s before the first list is asked again (half of it more each try), no round trip
                                # known yet: a listing asked again is only ended and begun again
LIST_RETRY_MIN = 0.05           # s, at least, when one is
STALL_LIMIT = 20.0              # s without one new byte (link up) before a download is given up, resumable
FLUSH_INTERVAL = 0.25           # s between writes of the .part file and its map
ERASE_WAIT = 1.0                # s after LOG_ERASE before the list that confirms it
ERASE_TRIES = 3
FTP_SESSION = 1                 # the parameters' FTP uses session 0: the vehicle keeps the two files apart
LOG_FOLDERS = (b"/APM/LOGS", b"logs")   # HAL_BOARD_LOG_DIRECTORY: a flight controller's SD card, then SITL's
FILL_MIN = 4                    # gap requests in flight at least (a radio port's transmit buffer holds ~9 LOG_DATA)
FILL_MAX = 8192                 # ... and at most (what one batch of requests may ask of the vehicle)
ANSWERED_MIN = 0.4              # ... counting at most 2.5x for loss: frames a starved reader drops look like
                                # loss too, and more requests would only drop more
TAIL_TWICE = 32                 # at most this many missing packets are each asked twice
TAIL_THRICE = 8                 # ... and at most this many three times
COPIES_MAX = 6                  # ... and at most this many times each (the vehicle's room in a round trip allowing)
STREAM_GAP = 256                # a gap of more packets than this (or than the window), nothing else in flight, is
                                # streamed: one request instead of one a packet (a dropped link, a burst of loss)
FILL_GAIN = 1.5                 # in flight: this many times the link's packets in a round trip (loss aside) ...
FILL_RTT_MIN = 0.05             # ... a round trip of at least this (s): one measured while the vehicle's transmit
                                # buffer runs dry is short, and fewer requests in flight would keep it dry; the
                                # pace (PACE_GAIN) is what keeps the vehicle from being flooded
PACE_GAIN = 1.25                # gap requests are sent at this many times the rate the vehicle answers them, ...
PACE_BURST = 0.02               # ... at most this many seconds of them at once: a burst the vehicle's transmit
                                # buffer cannot take at once leaves a transfer running, and ArduPilot drops every
                                # request that comes while one runs ("Log download in progress")
PACE_TICK = 0.005               # s between sends of paced gap requests, at most (their answers wake the sender)
END_WAIT = 0.02                 # s of silence at least after the listed size's last whole packet before its end
                                # counts as lost ...
END_NEAR = 8                    # ... once a packet this close to it came (the few before the end may be lost too)
DATA_ALIVE = 1.0                # s since the last LOG_DATA within which a download goes on with no heartbeat heard:
                                # at 30 % loss each way three heartbeats in a row are lost every half minute or so


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


class _Job:
    def __init__(self, kind: str, name: str, future: Future, log_id: int = 0, path: str = "") -> None:
        self.kind, self.name, self.future = kind, name, future
        self.log_id, self.path = log_id, path
        self.started = 0.0
        self.checking = False                   # DFReader reads the finished file (a thread of its own)
        self.ftp = False                        # read by MAVLink FTP instead of LOG_DATA
        self.listed = False                     # a download reads the list first: sizes and times as they are now


class _Listing:
    """One list in progress: entries by id, the tries left, when the next re-ask is due."""

    def __init__(self) -> None:
        self.entries: dict[int, LogEntry] = {}
        self.last: int | None = None
        self.tries = 0
        self.quiet_until = 0.0
        self.asked_at = 0.0                     # the last LOG_REQUEST_LIST, until its first answer times it


class _Download:
    def __init__(self, job: _Job, entry: LogEntry, part: PartMap, resumed: int) -> None:
        self.job, self.entry, self.part = job, entry, part
        self.ranges = part.ranges
        self.size = entry.size                  # known lower bound until the stream's end is seen
        self.end: int | None = None             # the log's end, as a short (or empty) LOG_DATA said
        self.resumed = resumed
        self.pending: list[tuple[int, bytes]] = []
        self.window: tuple[int, int] | None = None
        self.sent_at = 0.0
        self.last_rx = 0.0
        self.first_rx: float | None = None      # the window's first packet: when, and its offset
        self.first_ofs = self.last_ofs = 0
        self.rtt = 0.3
        self.rtt_seen = False                   # rtt is measured (else the first guess)
        self.idle_rtt: float | None = None      # the round trip of a stream's first packet, nothing else in flight:
                                                # the link's own, without the queues a busy link builds up
        self.asks: OrderedDict[int, tuple[int, float]] = OrderedDict()   # offset: (count, sent at), in order sent
        self.asked_at = 0.0
        self.cursor = 0                         # where the sweep over the gaps goes on
        self.tail_full: set[int] = set()        # offsets where a probe of the unknown end found a full packet
        self.streamed = False                   # the open-ended pass was asked
        self.short_asks: dict[int, int] = {}    # offset: count of the gap requests for less than a packet
        self.rate = 0.0                         # packets/s seen while a window streams
        self.loss = 0.0                         # share of a stream's packets lost on the way
        self.stream_got = 0                     # packets of the window that arrived
        self.fill_got = 0                       # gap requests answered since fill_from
        self.fill_from: float | None = None
        self.tokens = 0.0                       # gap requests that may go now (paced at the answer rate)
        self.tokens_at: float | None = None
        self.received = self.requested = self.rerequested = 0
        self.kept = resumed                     # bytes the .part map on disk names (what survives a failure)
        self.progress_at = 0.0
        self.flushed_at = 0.0
        self.history: deque = deque()           # (time, held) for the rate shown
        self.file = None
        self.ftp: FtpSpanRead | None = None     # the FTP read, when the log comes that way
        self.ftp_failure = ""
        self.verify: tuple[int, bytes] | None = None   # held bytes asked again: (offset, what the .part had)


class LogControl:
    """``vehicle.logs``: the vehicle's DataFlash logs (one operation at a time, the others queued)."""

    def __init__(self, vehicle) -> None:
        self._v = vehicle
        self._jobs: deque[_Job] = deque()
        self._listing: _Listing | None = None
        self._download: _Download | None = None
        self._refused: str | None = None
        self._erase_at = 0.0
        self._erase_before: tuple = ()
        self._erase_tries = 0
        self._check_thread: threading.Thread | None = None
        self._list_rtt: float | None = None     # s from a LOG_REQUEST_LIST to its first LOG_ENTRY
        self.entries: tuple = ()                # the last complete list
        self.progress: LogProgress | None = None

    # -- requests (any thread) -----------------------------------------------------------------------------
    def list(self) -> Future:
        """Every log on the vehicle: a LogOutcome whose ``entries`` are LogEntry by id."""
        return self._queue(_Job("list", "log list", Future()))

    def download(self, log_id: int, path: str, via: str = "auto") -> Future:
        """Log ``log_id`` into ``path`` (resuming from ``path``.part where one is there); a LogOutcome.

        ``via``: "log_data" (LOG_REQUEST_DATA), "ftp" (MAVLink FTP of its file, found by listing
        ``/APM/LOGS`` or SITL's ``logs``) or "auto", which is
        LOG_DATA: measured on ArduCopter 4.6.3 over TCP it moved 5.5 MB/s against FTP's 43 kB/s (the logs
        recording), and on a radio ArduPilot keeps FTP bursts to a third of the link while LOG_DATA takes what is
        free. The Solo (3.3) has no FTP at all."""
        job = _Job("download", f"log download {log_id}", Future(), log_id, os.path.abspath(path))
        if not isinstance(log_id, int) or not 1 <= log_id <= 0xFFFF:
            return self._done(job, False, f"no log {log_id}: log numbers go from 1 to 65535")
        if via not in ("auto", "log_data", "ftp"):
            return self._done(job, False, f"no way {via!r} to download: auto, log_data or ftp")
        if via == "ftp" and self._v._params.ftp_capable is False:
            return self._done(job, False, "the vehicle offers no MAVLink FTP (MAV_PROTOCOL_CAPABILITY_FTP): "
                                          "download by LOG_DATA")
        job.ftp = via == "ftp"
        return self._queue(job)

    def download_latest(self, path: str) -> Future:
        """The newest log (the list is read first)."""
        return self._queue(_Job("download", "log download latest", Future(), -1, os.path.abspath(path)))

    def erase(self) -> Future:
        """LOG_ERASE (no reply: a list afterwards confirms it, and it is sent again if the logs are still there)."""
        return self._queue(_Job("erase", "log erase", Future()))

    def cancel(self) -> None:
        """Stop what runs and drop what waits; a download keeps its .part to resume from."""
        v = self._v
        with v._lock:
            jobs = list(self._jobs)
            self._jobs.clear()
            for job in jobs:
                self._finish(job, False, "cancelled")
            self._erase_tries = 0               # a new erase lists and judges afresh
            self._post_end()
        v._wake.set()

    def _queue(self, job: _Job) -> Future:
        v = self._v
        if v._replay is not None:
            return self._done(job, False, "replaying a recording: no vehicle to ask")
        with v._lock:
            self._jobs.append(job)
        v._wake.set()
        return job.future

    def _done(self, job: _Job, ok: bool, reason: str, **more) -> Future:
        job.future.set_result(LogOutcome(job.name, ok, reason, **more))
        return job.future

    # -- the driver's threads (lock held) ------------------------------------------------------------------
    def on_message(self, m) -> None:
        kind = m.get_type()
        if kind == "LOG_ENTRY" and self._listing is not None:
            self._on_entry(m)
        elif kind == "LOG_DATA" and self._download is not None and m.id == self._download.entry.id:
            self._on_data(m)

    def on_ftp(self, m) -> None:
        """A FILE_TRANSFER_PROTOCOL reply while a log is read by FTP (reader thread, lock held)."""
        d = self._download
        if d is None or d.ftp is None or d.job.checking:
            return
        now = self._v.clock()
        failure = d.ftp.on_message(m, now)
        if isinstance(d.ftp, FtpList):
            d.ftp_failure = failure or d.ftp_failure
            self._v._wake.set()
            return
        if d.ftp.taken is not None:             # a new chunk, already counted held in d.ranges by the engine
            (offset, chunk), d.ftp.taken = d.ftp.taken, None
            if d.verify is not None:
                self._same_log(d, offset, chunk)
            d.ranges.add(offset, offset + len(chunk))   # (again, if _same_log began afresh)
            d.pending.append((offset, chunk))
            d.received += len(chunk)
            d.progress_at = now
        if d.ftp.end is not None:
            d.end = d.part.size = d.ftp.end
        if failure:
            d.ftp_failure = failure
        self._v._wake.set()

    def on_text(self, text: str) -> None:
        if text.startswith(DISARM_TEXT) and self._jobs:
            self._refused = text

    def service(self, now: float, state) -> list:
        out: list = []
        if not self._jobs:
            return out
        job = self._jobs[0]
        if not job.started:
            self._refused = None                 # a refusal told before this job's first request is not its own
        if self._refused is not None:
            self._refused, reason = None, self._refused
            self._abort(job, f"{reason}: the vehicle ignores log requests while armed")
            return [self._end_message()]
        if not job.started:
            job.started = now
            if state.armed:                      # the vehicle says why only once: ask, and tell its words
                out.append(self._message("log_request_list", *ALL_IDS))
                self._abort(job, f"{DISARM_TEXT}: the vehicle ignores log requests while armed")
                return out
        link_up = state.connected                 # a lost link pauses: the download goes on when it is back
        if job.kind == "list" or (job.kind == "download" and not job.listed and self._download is None):
            out += self._service_list(job, now, link_up)
        elif job.kind == "download":
            out += self._service_download(job, now, link_up)
        elif job.kind == "erase":
            out += self._service_erase(job, now, link_up)
        return out

    def close(self) -> None:
        with self._v._lock:
            for job in list(self._jobs):
                self._abort(job, "driver closed")

    # -- listing ---------------------------------------------------------------------------------------------
    def _known(self, log_id: int) -> bool:
        return any(e.id == log_id for e in self.entries or ())

    def _service_list(self, job: _Job, now: float, link_up: bool) -> list:
        listing = self._listing
        if listing is None:
            listing = self._listing = _Listing()
            self.progress = LogProgress(0, "", 0, 0, 0.0, "listing")
        if not link_up:
            return []
        if now < listing.quiet_until:
            self._v._ticker.tick_within(listing.quiet_until - now)     # asked again on time
            return []
        wanted = self._missing_ids(listing)
        if listing.last is not None and not wanted:
            return self._listed(job)
        if listing.tries >= LIST_TRIES:
            self._listing = None
            missing = ", ".join(str(i) for i in wanted[:10]) if wanted else "all"
            self._abort(job, f"the log list is incomplete after {LIST_TRIES} tries (missing: {missing})")
            return [self._end_message()]
        listing.tries += 1
        # re-asked after a few round trips (the last list's, else 0.1 s), each try waiting longer: at 30 % loss
        # each way half of the round trips fail, and a listing under way is only ended and begun again (END goes
        # first), while an entry that comes holds the next try back (_on_entry)
        base = max(LIST_RETRY_MIN, 3 * self._list_rtt) if self._list_rtt is not None else LIST_RETRY_FIRST
        listing.quiet_until = now + base * (1 + (listing.tries - 1) / 2)
        listing.asked_at = now
        start, end = (wanted[0], wanted[-1]) if listing.last is not None else ALL_IDS
        log.debug("log list: try %d, ids %d-%d", listing.tries, start, end)
        # a transfer still running (a cancelled download's, its END lost) would drop the list: END goes first; and
        # all of it twice: the vehicle sends the first entry on receipt (a list of one log is over at once), the
        # second END ends the first listing, so the second LIST is never dropped as busy, and one lost request or
        # entry of the two costs no try
        ask = [self._end_message(), self._message("log_request_list", start, end)]
        return ask + ask

    @staticmethod
    def _missing_ids(listing: _Listing) -> list[int]:
        if listing.last is None:
            return []
        return [i for i in range(1, listing.last + 1) if i not in listing.entries]

    def _on_entry(self, m) -> None:
        listing = self._listing
        if listing.asked_at:                    # the link's round trip, a download's first guess of it
            self._list_rtt = self._v.clock() - listing.asked_at
            listing.asked_at = 0.0
        if m.num_logs == 0 or m.last_log_num == 0:
            listing.last = 0
        else:
            listing.last = m.last_log_num if listing.last is None else max(listing.last, m.last_log_num)
        if 1 <= m.id <= m.last_log_num:
            listing.entries[m.id] = LogEntry(m.id, m.size, m.time_utc)
            listing.quiet_until = min(listing.quiet_until, self._v.clock() + 0.3) \
                if not self._missing_ids(listing) else self._v.clock() + 0.3
        if not self._missing_ids(listing):
            listing.quiet_until = 0.0
            self._v._wake.set()

    def _listed(self, job: _Job) -> list:
        entries = tuple(sorted(self._listing.entries.values(), key=lambda e: e.id))
        self._listing = None
        self.entries = entries
        self.progress = None
        job.listed = True
        if job.kind == "erase":
            pass
        elif job.kind == "list":
            self._jobs.popleft()
            self._finish(job, True, f"{len(entries)} logs", entries=entries)
        elif job.log_id < 0:
            if not entries:
                self._abort(job, "no logs on the vehicle")
            else:
                job.log_id = entries[-1].id
        elif not self._known(job.log_id):
            have = f"logs {entries[0].id} to {entries[-1].id}" if entries else "no logs"
            self._abort(job, f"no log {job.log_id} on the vehicle ({have})")
        self._v._wake.set()
        return [self._end_message()]

    # -- downloading -----------------------------------------------------------------------------------------
    def _begin_download(self, job: _Job, now: float) -> _Download | None:
        entry = next(e for e in self.entries if e.id == job.log_id)
        if entry.size == 0:
            self._abort(job, f"log {entry.id} is empty (0 bytes) on the vehicle")
            return None
        part = load_part_map(job.path)
        fresh = part is None or part.log_id != entry.id or not part.ranges.spans \
            or part.ranges.spans[-1][1] > entry.size or not os.path.exists(job.path + ".part")
        if fresh and part is not None and part.ranges.spans:
            self._set_aside(job.path)           # another log (a shorter one) with that number: not mixed in
        if fresh:
            part = PartMap(entry.id, entry.time_utc, Ranges(), None, entry.size)
        try:
            folder = os.path.dirname(job.path)
            if folder:
                os.makedirs(folder, exist_ok=True)
            handle = open(job.path + ".part", "wb" if fresh else "r+b")
            if fresh:
                save_part_map(job.path, part)
        except OSError as exc:
            self._abort(job, f"{self._disk_words(exc)}: {job.path}: {exc.strerror or exc}")
            return None
        verify = None if fresh else self._recheck(part, handle, entry)
        d = _Download(job, entry, part, part.ranges.total())
        d.verify = verify
        if self._list_rtt is not None:
            d.rtt = self._list_rtt             # (a first request lost waits 3 of them, not 3 x 0.3 s)
        # the end the stream told, while the list still gives the size it was fetched by (a smaller end than the
        # list's is stale: the log grew, or its stream broke off)
        if part.size and part.size >= entry.size and part.listed in (0, entry.size):
            d.end = part.size
        d.file = handle
        d.progress_at = d.flushed_at = now
        if job.ftp:
            if not self._flush(d):
                return None
            self._start_ftp(d, now)
        if d.resumed:
            log.info("log %d: resuming with %d bytes held", entry.id, d.resumed)
        return d

    @staticmethod
    def _recheck(part: PartMap, handle, entry: LogEntry) -> tuple[int, bytes]:
        """The .part's last held bytes are fetched again and must come back the same, else it is another log.

        Neither id nor time tells a log apart: ids restart at 1 after an erase, a board without a clock dates every
        log alike, and the open log's time is the clock's now at each list (AP_Logger_File::_get_log_time). The
        last held bytes (DataFlash records with their TimeUS) differ between two logs; the first ones (FMT, PARM)
        do not. So they are un-held here and compared when they come (:meth:`_same_log`)."""
        a, b = part.ranges.spans[-1]
        start = max(a, b - CHUNK)
        handle.seek(start)
        expect = handle.read(b - start)
        part.ranges = Ranges(part.ranges.spans[:-1] + ([[a, start]] if start > a else []))
        part.time_utc, part.listed = entry.time_utc, entry.size
        return start, expect

    def _same_log(self, d: _Download, ofs: int, data: bytes) -> None:
        """Bytes at ``ofs`` from the vehicle against what the resumed .part held there (see :meth:`_recheck`)."""
        start, expect = d.verify
        lo, hi = max(ofs, start), min(ofs + len(data), start + len(expect))
        if lo >= hi:
            return
        if data[lo - ofs:hi - ofs] != expect[lo - start:hi - start]:
            self._another_log(d, lo)
        elif lo == start:
            d.verify = (hi, expect[hi - start:]) if hi < start + len(expect) else None

    def _another_log(self, d: _Download, ofs: int) -> None:
        """The .part was another log's: set aside as .part.old; only this session's bytes are kept."""
        path = d.job.path
        log.warning("log %d: byte %d differs from %s.part: another log with that number; kept as .part.old, "
                    "fetched afresh", d.entry.id, ofs, path)
        d.file.close()
        self._set_aside(path)
        try:
            d.file = open(path + ".part", "wb")
        except OSError as exc:
            d.file = None
            self._abort(d.job, f"{path}.part: {exc.strerror or exc}")
            return
        d.part = PartMap(d.entry.id, d.entry.time_utc, Ranges((o, o + len(b)) for o, b in d.pending), None,
                         d.entry.size)
        d.ranges, d.end, d.resumed, d.verify = d.part.ranges, None, 0, None
        if isinstance(d.ftp, FtpSpanRead):
            d.ftp.held, d.ftp.next_burst = d.ranges, 0

    @staticmethod
    def _set_aside(path: str) -> None:
        try:
            os.replace(path + ".part", path + ".part.old")
        except OSError:
            pass

    def _service_download(self, job: _Job, now: float, link_up: bool) -> list:
        if job.checking:
            return []
        d = self._download
        if d is None:
            d = self._download = self._begin_download(job, now)
            if d is None:
                return []
        if d.job is not job:
            return []
        if now - d.flushed_at >= FLUSH_INTERVAL:
            if not self._flush(d):
                return [self._end_message()]
        self._show(d, now)
        end = d.end
        if end is not None and d.ranges.whole(end):
            return self._complete(d)
        if not link_up and now - d.last_rx > DATA_ALIVE:
            d.window = None
            d.asks.clear()
            d.progress_at = now
            return []
        if d.ftp is not None:
            return self._service_ftp(d, now)
        if now - d.progress_at > STALL_LIMIT:
            self._give_up(d, f"no data from the vehicle for {STALL_LIMIT:.0f} s")
            return [self._end_message()]
        if d.window is not None:
            wait = self._stream_wait(d) - (now - max(d.sent_at, d.last_rx))
            if wait > 0:
                self._v._ticker.tick_within(wait)   # looked at again when the silence would end it
                return []
            self._measure(d, now)
            d.window = None                     # silence: the rest of that window was lost
        held_to = d.ranges.spans[-1][1] if d.ranges.spans else 0
        if d.end is None and (not d.streamed or not held_to or held_to in d.tail_full):
            # from where the held bytes end to the log's own end: the first pass, or a log still going on
            # twice: the first pass (a second request is dropped while the first one streams, and 3.3 only
            # begins again at the same place), and the last few packets (served within one call, so twice):
            # a lost one would cost a round trip with nothing else in flight
            first = not d.streamed and not held_to
            tail = d.streamed and held_to and d.size - held_to <= TAIL_TWICE * CHUNK
            ask = self._stream(d, held_to, OPEN_END - held_to, now)
            return [ask, ask] if first or tail else [ask]
        return self._fill(d, now)

    @staticmethod
    def _stream_wait(d: _Download) -> float:
        """Silence that ends a stream's window: three round trips; once its packets came within a few of the listed
        size, one round trip (the end follows them at once, in the same call, so silence there means the end was
        lost; a log that grew since the list keeps coming, and each packet restarts the wait)."""
        if d.end is None and d.first_rx is not None and d.last_ofs + END_NEAR * CHUNK > d.size:
            return max(END_WAIT, d.rtt)
        return max(0.05, 3 * d.rtt)

    def _service_ftp(self, d: _Download, now: float) -> list:
        msgs, failure = d.ftp.service(now, self._v._target_ids())
        if isinstance(d.ftp, FtpList) and d.ftp.done:
            path, failure = self._log_file(d)
            if path:
                self._open_ftp(d, now, path)
        failure = failure or d.ftp_failure
        if failure:
            self._give_up(d, f"MAVLink FTP {failure}")
            return msgs + [d.ftp.terminate(self._v._target_ids())]
        return msgs

    def _start_ftp(self, d: _Download, now: float) -> None:
        """The log folder listed first: a LOG_ENTRY id is a place in the list, not the file's number."""
        d.ftp = FtpList(now, LOG_FOLDERS, session=FTP_SESSION, stall=STALL_LIMIT)

    @staticmethod
    def _log_file(d: _Download) -> tuple[str, str]:
        """(path, "") of the file of log ``d.entry.id`` in the folder listed, else ("", why not): the oldest log's
        number + id - 1 (AP_Logger_Backend::log_num_from_list_entry), and its size must be the list's."""
        listing = d.ftp
        numbers = sorted(int(n[:-4]) for n in listing.files if n.upper().endswith(".BIN") and n[:-4].isdigit())
        if not numbers:
            return "", f"found no log in {listing.folder.decode()}"
        name = f"{numbers[0] + d.entry.id - 1:08d}.BIN"
        path = f"{listing.folder.decode().rstrip('/')}/{name}"
        size = next((s for n, s in listing.files.items() if n.upper() == name), None)
        if size != d.entry.size:
            return "", (f"found {path} with {size} bytes where log {d.entry.id} has {d.entry.size}" if size is not None
                        else f"found no {path} for log {d.entry.id}") + ": download it by LOG_DATA"
        return path, ""

    def _open_ftp(self, d: _Download, now: float, path: str) -> None:
        """The FTP read of the log's file: its bytes go to the .part as they come, what is held is ``d.ranges``;
        the first burst begins at the first chunk the .part lacks."""
        ftp = d.ftp = FtpSpanRead(now, path.encode(), FTP_SESSION, max_bursts=1 << 30, stall=STALL_LIMIT,
                                  seq=d.ftp.seq, held=d.ranges)
        first = ftp.missing(1)
        ftp.next_burst = first[0] if first else ftp._top()

    def _stream(self, d: _Download, start: int, count: int, now: float):
        """One request streamed as a window: the log's tail (open-ended) or a long gap."""
        if d.end is not None:
            count = min(count, d.end - start)
        d.window = (start, start + count)
        d.streamed = True
        log.debug("log %d: stream %d+%d (rtt %.3f s, %.0f packets/s)", d.entry.id, start, count, d.rtt, d.rate)
        d.sent_at = now
        d.first_rx = None
        d.stream_got = 0
        self._count_asked(d, start, count)
        return self._message("log_request_data", d.entry.id, start, count)

    def _count_asked(self, d: _Download, start: int, count: int) -> None:
        upto = min(start + count, d.end if d.end is not None else max(d.size, start))
        d.requested += max(0, upto - start)
        d.rerequested += d.ranges.held(start, upto)

    def _fill_window(self, d: _Download) -> int:
        """Gap requests in flight: what the link carries in a round trip (its packet rate on the stream times the
        round trip), with a margin, and more for the requests and answers a loss takes (the stream's loss share,
        taken for both ways): enough to keep the vehicle sending, not more, so a radio is not flooded."""
        answered = max(ANSWERED_MIN, (1.0 - d.loss) ** 2)
        return int(min(FILL_MAX, max(FILL_MIN, FILL_GAIN * d.rate * max(d.rtt, FILL_RTT_MIN) / answered)))

    @staticmethod
    def _copies(d: _Download, left: int | None, window: int) -> int:
        """How many times each gap request goes, ``left`` packets still missing (None: the end is not known).

        While the missing packets outnumber what the vehicle sends in a round trip, once: the vehicle is the
        bottleneck, and a copy's answer would take a missing packet's place. Fewer, and the download waits on
        round trips instead (at 30 % loss each way half the requests come to nothing, so the last thousand packets
        take ten of them): the vehicle's spare room in a round trip is spent on copies, each of which lowers the
        odds that a packet is still missing after the next one. The last few go twice, the very last three times,
        even when no loss was seen: a lost one costs a whole round trip with nothing else in flight."""
        if left is None:
            return 1
        copies = 1 if left >= min(window // 4, TAIL_TWICE) else 2 if left >= TAIL_THRICE else 3
        if d.loss > 0 and d.rate > 0 and d.idle_rtt is not None:
            # requests answered in one of the link's own round trips (the smoothed one grows with the queues of a
            # busy link, where copies only queue longer: through a relay to SITL that rule received up to 40 % more)
            room = d.rate * d.idle_rtt / max(ANSWERED_MIN, 1.0 - d.loss)
            copies = max(copies, min(COPIES_MAX, int(room // max(1, left))))
        return copies

    def _fill(self, d: _Download, now: float) -> list:
        """Ask for the missing packets one request each, sweeping the gaps from the cursor, while fewer than the
        window are in flight; a gap longer than the window, with nothing in flight, is streamed instead."""
        if d.asks and now - max(d.asked_at, d.last_rx) >= max(0.05, 2 * d.rtt):
            d.asks.clear()                      # silence: all of them (or their answers) were lost
        self._measure_fill(d, now)
        window = self._fill_window(d)
        want = wanted = min(window - len(d.asks), self._paced(d, now))
        if want <= 0:
            return []
        out, end = [], d.end
        copies = self._copies(d, (end - d.ranges.total()) // CHUNK if end is not None else None, window)
        if end is None:                         # the stream's last packet was lost: probe the end with the gaps
            end = d.ranges.spans[-1][1]
            listed = -(-d.size // CHUNK) * CHUNK
            if end < listed <= end + TAIL_TWICE * CHUNK:
                # a few packets short of the listed size, where the log goes on at least: those packets are gaps
                # like the others, each asked for a whole packet, so the last one's answer comes short where the
                # log ends (or full if it grew); further short, the probe below, then a stream (a lost run)
                end = listed
            elif end not in d.asks:
                d.asks[end] = (CHUNK, now)
                probe = self._message("log_request_data", d.entry.id, end, CHUNK)
                out += [probe, probe]           # twice: one packet, whose loss costs a whole round
                want -= 1
        gaps, wrapped = d.ranges.gaps(d.cursor, end), d.cursor == 0
        while want > 0:
            gap = next(gaps, None)
            if gap is None:
                if wrapped:
                    break
                d.cursor, wrapped = 0, True     # the next sweep: what went unanswered is asked again
                gaps = d.ranges.gaps(0, end)
                continue
            a, b = gap
            if b - a > max(min(window, STREAM_GAP), 32) * CHUNK and not d.asks and not out:
                d.cursor = b
                return [self._stream(d, a, -(-(b - a) // CHUNK) * CHUNK, now)]
            for ofs in range(a, b, CHUNK):
                if ofs in d.asks:
                    continue
                count = min(CHUNK, b - ofs)
                d.asks[ofs] = (count, now)
                if count < CHUNK:
                    d.short_asks[ofs] = count   # its answer is short too, and not the log's end
                d.requested += count
                out += [self._message("log_request_data", d.entry.id, ofs, count)] * copies
                d.cursor = ofs + count
                want -= 1
                if not want:
                    break
        if d.rate > 0:                          # paced: what went is spent, more may go once the pace allows
            d.tokens -= wanted - want
            if d.tokens < 1.0 and len(d.asks) < window:
                self._v._ticker.tick_within(PACE_TICK)
        if out:
            d.asked_at = now
            log.debug("log %d: %d gap requests (%d in flight, window %d, rtt %.3f s, %.0f packets/s, loss %.2f)",
                      d.entry.id, len(out), len(d.asks), window, d.rtt, d.rate, d.loss)
        return out

    def _on_data(self, m) -> None:
        d = self._download
        now = self._v.clock()
        count = min(int(m.count), CHUNK)
        ofs = int(m.ofs)
        d.last_rx = now
        d.received += count
        if count:
            data = bytes(m.data[:count])
            if d.verify is not None:
                self._same_log(d, ofs, data)
            if d.ranges.add(ofs, ofs + count):
                d.pending.append((ofs, data))
                d.progress_at = now
        expected = d.short_asks.get(ofs, CHUNK)
        ask = d.asks.get(ofs)
        if ask is not None:                     # a gap request's answer: the ones sent before it went unanswered
            while d.asks.popitem(last=False)[0] != ofs:
                pass
            expected = ask[0]
            self._round_trip(d, now - ask[1])
            d.fill_got += 1
            top = ofs + count
            if d.end is None and count == CHUNK and top == d.ranges.spans[-1][1] and \
                    not top < d.size <= top + TAIL_TWICE * CHUNK:
                d.tail_full.add(top)            # the log goes on past the probe: stream the rest (not the last few)
            if len(d.asks) <= self._fill_window(d) // 2 or now - d.asked_at >= PACE_TICK:
                self._v._wake.set()
        if count < expected and (d.end is None or ofs + count < d.end):
            d.end = ofs + count                 # a short packet: the log ends here (the vehicle's word)
            d.part.size = d.end
        window = d.window
        if window is None or not window[0] <= ofs < window[1]:
            return                              # queued from an earlier request: kept, but it times nothing
        if d.first_rx is None:
            d.first_rx, d.first_ofs = now, ofs
            sample = now - d.sent_at
            self._round_trip(d, sample)
            d.idle_rtt = sample if d.idle_rtt is None else min(d.idle_rtt, sample)
        d.last_ofs = ofs
        d.stream_got += 1
        if ofs + count >= window[1] or count < CHUNK:
            self._measure(d, now)
            d.window = None
            self._v._wake.set()

    @staticmethod
    def _round_trip(d: _Download, seconds: float) -> None:
        d.rtt = 0.875 * d.rtt + 0.125 * seconds if d.rtt_seen else seconds
        d.rtt_seen = True

    @staticmethod
    def _measure(d: _Download, now: float) -> None:
        """The stream's rate (packets/s, lost ones counted) from this window's first and last packets, and the
        share of its packets the link lost."""
        if d.first_rx is not None and d.last_rx > d.first_rx and d.last_ofs > d.first_ofs:
            span = (d.last_ofs - d.first_ofs) / CHUNK
            rate = span / (d.last_rx - d.first_rx)
            d.rate = rate if d.rate == 0 else 0.5 * d.rate + 0.5 * rate
            if span >= 50:
                d.loss = min(0.9, max(0.0, 1.0 - d.stream_got / (span + 1)))

    @staticmethod
    def _paced(d: _Download, now: float) -> int:
        """Gap requests that may go now: a token bucket filled at PACE_GAIN times the rate the vehicle sends (over
        the share of requests that reach it), holding PACE_BURST of it, so the requests come at the pace the
        vehicle answers them rather than in bursts it drops. Unpaced while the rate is unknown."""
        if d.rate <= 0:
            return FILL_MAX
        pace = PACE_GAIN * d.rate / max(ANSWERED_MIN, 1.0 - d.loss)
        elapsed = PACE_BURST if d.tokens_at is None else now - d.tokens_at
        d.tokens = min(max(1.0, pace * PACE_BURST), d.tokens + pace * elapsed)
        d.tokens_at = now
        return int(d.tokens)

    @staticmethod
    def _measure_fill(d: _Download, now: float) -> None:
        """The rate the gap requests are answered at, lost answers counted, raises the stream's: a stream cut
        short (a link that dropped, a log already mostly held) measures nothing, and a window left at FILL_MIN
        would then crawl through the whole log. Requests paced PACE_GAIN faster than answered are answered faster
        until the link is full, so the pace grows by up to PACE_GAIN each period until it stops paying."""
        if d.fill_from is None or not d.asks:
            d.fill_from, d.fill_got = now, 0
            return
        elapsed = now - d.fill_from
        if elapsed < max(0.1, 2 * d.rtt):
            return
        sample = d.fill_got / elapsed / max(ANSWERED_MIN, 1.0 - d.loss)
        if sample > d.rate:
            d.rate = sample
        d.fill_from, d.fill_got = now, 0

    def _flush(self, d: _Download) -> bool:
        """The bytes received since the last flush into the .part, then the map that names them; False (the
        download ended, resumable) when the disk refuses them."""
        d.flushed_at = self._v.clock()
        try:
            for ofs, data in d.pending:
                d.file.seek(ofs)
                d.file.write(data)
            d.file.flush()
            d.pending.clear()
            save_part_map(d.job.path, d.part)
            d.kept = d.ranges.total()
            return True
        except OSError as exc:
            # The map on disk is still the last one saved, and it names only bytes that were flushed before it:
            # the .part stays resumable whatever this write left behind it.
            waiting = sum(len(data) for _, data in d.pending)
            self._close_download(d)
            self._abort(d.job, f"{self._disk_words(exc)}: {d.job.path}.part could not take {waiting} more bytes "
                               f"({exc.strerror or exc}); kept {d.kept} bytes in {d.job.path}.part, resumable")
            return False

    @staticmethod
    def _disk_words(exc: OSError) -> str:
        if exc.errno in (errno.ENOSPC, errno.EDQUOT):
            return "no space left on the disk"
        if exc.errno == errno.EFBIG:
            return "no room for a larger file"      # the file system's or the process's (RLIMIT_FSIZE) limit
        return "could not write the log"

    def _give_up(self, d: _Download, why: str) -> None:
        """End the download, resumable: what is held goes to the .part first (a full disk tells its own reason)."""
        if self._flush(d):
            self._close_download(d)
            self._abort(d.job, f"{why}: {d.kept} bytes of {self._size_text(d)} kept in {d.job.path}.part, "
                               "download again to resume")

    def _show(self, d: _Download, now: float) -> None:
        held = d.ranges.total()
        d.history.append((now, held))
        while len(d.history) > 2 and now - d.history[0][0] > 1.0:
            d.history.popleft()
        t0, h0 = d.history[0]
        rate = (held - h0) / (now - t0) if now > t0 else 0.0
        self.progress = LogProgress(d.entry.id, d.job.path, d.end or max(d.size, held), held, rate, "downloading")

    @staticmethod
    def _size_text(d: _Download) -> str:
        return f"{d.end} bytes" if d.end is not None else f"at least {d.size} bytes"

    def _close_download(self, d: _Download) -> None:
        if d.file is not None:
            try:
                d.file.close()
            except OSError as exc:              # bytes still buffered on a full disk: the map does not name them
                log.info("log %d: %s.part closed without its last bytes (%s)", d.entry.id, d.job.path, exc)
            d.file = None
        self._download = None
        self.progress = None

    def _complete(self, d: _Download) -> list:
        if not self._flush(d):
            return [self._end_message()]
        job = d.job
        done = [d.ftp.terminate(self._v._target_ids())] if d.ftp is not None else []
        d.file.truncate(d.end)
        self._close_download(d)
        self.progress = LogProgress(d.entry.id, job.path, d.end, d.end, 0.0, "checking")
        seconds = self._v.clock() - job.started
        fields = dict(log_id=d.entry.id, path=job.path, size=d.end, seconds=seconds, bytes_received=d.received,
                      bytes_requested=d.requested, bytes_rerequested=d.rerequested, resumed_from=d.resumed)
        job.checking = True
        thread = threading.Thread(target=self._check, args=(job, fields, d.entry.size), name="log-check",
                                  daemon=True)
        self._check_thread = thread
        thread.start()
        return done + [self._end_message()]

    def _check(self, job: _Job, fields: dict, announced: int) -> None:
        """DFReader reads the whole .part (off the driver's threads), then it becomes the file. ``announced``: the
        size the vehicle listed just before this download; a stream that ended short of it is no whole log."""
        path = job.path
        try:
            checked = check_dataflash(path + ".part", announced)
            os.replace(path + ".part", path)
            os.remove(path + ".part.json")
            ok, reason = True, f"log {fields['log_id']} saved to {path}"
            if checked.ending:
                reason += f"; it ends with {checked.ending}"
            more = dict(messages=checked.messages, ending=checked.ending)
        except (LogFileError, OSError) as exc:
            ok, more = False, {}
            reason = f"log {fields['log_id']} downloaded ({fields['size']} bytes) but {exc}"
        with self._v._lock:
            if self._jobs and self._jobs[0] is job:
                self._jobs.popleft()
            self.progress = None
            self._finish(job, ok, reason, **more, **fields)
        self._v._wake.set()

    # -- erasing -----------------------------------------------------------------------------------------------
    def _service_erase(self, job: _Job, now: float, link_up: bool) -> list:
        """The list first (what is there now), LOG_ERASE (no reply), then lists until none of those logs is left."""
        if not link_up:
            return []
        if not job.listed:
            self._erase_tries = 0
            return self._service_list(job, now, link_up)
        if self._erase_tries:
            if now < self._erase_at:
                return []
            if self.entries is None:             # the list that tells whether the erase was done
                return self._service_list(job, now, link_up)
            if not any(self._still_there(e) for e in self.entries):
                self._erase_tries = 0
                self._jobs.popleft()
                self._finish(job, True, f"logs erased; {len(self.entries)} on the vehicle now", entries=self.entries)
                return []
            if self._erase_tries >= ERASE_TRIES:
                self._erase_tries = 0
                self._abort(job, f"the logs are still there after {ERASE_TRIES} LOG_ERASE")
                return []
        if not self._erase_tries:
            self._erase_before = self.entries
            if not self._erase_before:
                self._jobs.popleft()
                self._finish(job, True, "no logs on the vehicle to erase", entries=())
                return []
        self._erase_tries += 1
        self._erase_at = now + ERASE_WAIT
        self.progress = LogProgress(0, "", 0, 0, 0.0, "erasing")
        self.entries = None
        return [self._message("log_erase")]

    def _still_there(self, entry: LogEntry) -> bool:
        """A log from the list before the erase: same id and time, as big or bigger (the open log grows). A vehicle
        logging while disarmed (LOG_DISARMED) begins log 1 again right after an erase: smaller, so not "still
        there"; ids restart at 1, so an id alone proves nothing."""
        return any(e.id == entry.id and e.time_utc == entry.time_utc and entry.size >= e.size
                   for e in self._erase_before)

    # -- helpers -----------------------------------------------------------------------------------------------
    def _message(self, name: str, *fields):
        target = self._v._target_ids()
        return getattr(mavlink, f"MAVLink_{name}_message")(*target, *fields)

    def _end_message(self):
        return self._message("log_request_end")

    def _post_end(self) -> None:
        d = self._download
        if d is not None and (d.file is None or self._flush(d)):
            self._close_download(d)
        self._listing = None
        self._v._post(self._end_message())

    def _abort(self, job: _Job, reason: str) -> None:
        d = self._download
        if d is not None and d.job is job:
            if d.file is not None and not self._flush(d):
                return                          # the disk refused the last bytes: that is the reason told
            self._close_download(d)
        if self._jobs and self._jobs[0] is job:
            self._jobs.popleft()
            self._listing = None
        elif job in self._jobs:
            self._jobs.remove(job)
        self.progress = None
        self._finish(job, False, reason)

    def _finish(self, job: _Job, ok: bool, reason: str, **more) -> None:
        if not ok:
            log.warning("%s: %s", job.name, reason)
        self._v._notifier.settle(job.future, LogOutcome(job.name, ok, reason, **more))
