"""``vehicle.logs``: list, download and erase the vehicle's DataFlash logs, one operation at a time, the others
queued; cancel stops what runs and drops what waits.

The parts: the list (listing.py: LOG_REQUEST_LIST / LOG_ENTRY, complete under loss), one download (download.py:
LOG_DATA asked by the gap filler, filler.py, or MAVLink FTP by driver/ftp/reader.py; the bytes to FILE.part and its
map on a worker thread, partfile.py; DFReader's check, check.py), and the erase here.

* Armed, the vehicle ignores every LOG_* request (the first with "Disarm for log download"): the request fails
  with that text.
* LOG_ERASE has no reply: the list is read first (what is there now), and again after the erase, which is sent
  again while a log from the first list is still there.

Threads: requests come from any thread; ``on_message``, ``on_ftp``, ``on_text`` and ``service`` run on the driver's
reader and ticker threads with the vehicle's state lock held; futures are settled off that lock by the settler.
This part keeps only the ports it uses (driver.core.ports: the state port, the outbox, the settler, the clock),
never the vehicle.
"""
from __future__ import annotations

import logging
import os
from collections import deque
from concurrent.futures import Future

from ..core.ports import Ports
from .download import LogDownload
from .listing import LogListing
from .model import LogEntry, LogOutcome, LogProgress
from .partfile import PartFile
from .wire import ALL_IDS, DISARM_TEXT, LogRequests

__all__ = ["LogControl", "LogEntry", "LogOutcome", "LogProgress", "DISARM_TEXT"]

log = logging.getLogger(__name__)

# LOG_ERASE has no reply: the list that judges it is asked 1 s later. AP_Logger_File deletes about 50 files a second
# on a Pixhawk's SD card (its own note), so 1 s covers most vehicles; a list too early only sends LOG_ERASE again,
# three times at most before the logs still there are told.
ERASE_WAIT = 1.0
ERASE_TRIES = 3
# Closing the driver waits this long (s) for a download's last bytes to reach the .part and its map; a disk slower
# than that is not waited for (the map on disk still names only bytes that are there).
CLOSE_WAIT = 5.0
REPLAYING = "replaying a recording: no vehicle to ask"


class _Job:
    def __init__(self, kind: str, name: str, log_id: int = 0, path: str = "", via: str = "auto") -> None:
        self.kind, self.name, self.future = kind, name, Future()
        self.log_id, self.path, self.via = log_id, path, via
        self.started = 0.0
        self.listed = False                     # a download or an erase reads the list first: what is there now
        self.erase_tries = 0                    # LOG_ERASE sent
        self.erase_at = 0.0                     # when the list that judges the last one is due
        self.before_erase: tuple = ()           # the list the erase began from


class LogControl:
    """The vehicle's DataFlash logs, over ``ports`` (the vehicle's, :class:`~driver.core.ports.Ports`): its
    firmware profile says whether it offers MAVLink FTP."""

    def __init__(self, ports: Ports) -> None:
        self._state, self._lock = ports.state, ports.state.lock
        self._outbox, self._settler, self._clock = ports.outbox, ports.settler, ports.clock
        self._firmware = ports.firmware
        self._requests = LogRequests(self._outbox.target)
        self._jobs: deque[_Job] = deque()
        self._listing: LogListing | None = None
        self._download: LogDownload | None = None
        self._part: PartFile | None = None      # the last download's files (the next one opens after they close)
        self._closing: list[tuple[PartFile, _Job, dict]] = []   # jobs told once their download's files are closed
        self._refused: str | None = None
        self._roundtrip = ports.roundtrip       # the link's one round trip: every wait for an answer
        self.entries: tuple | None = ()         # the last complete list (None: asked again, after an erase)
        self.progress: LogProgress | None = None

    # -- requests (any thread) -----------------------------------------------------------------------------
    def list(self) -> Future:
        """Every log on the vehicle: a LogOutcome whose ``entries`` are LogEntry by id."""
        return self._queue(_Job("list", "log list"))

    def download(self, log_id: int, path: str, via: str = "auto") -> Future:
        """Log ``log_id`` into ``path`` (resuming from ``path``.part where one is there); a LogOutcome.

        ``via``: "log_data" (LOG_REQUEST_DATA), "ftp" (MAVLink FTP of its file, found by listing
        ``/APM/LOGS`` or SITL's ``logs``) or "auto", which is
        LOG_DATA: measured on ArduCopter 4.6.3 over TCP it moved 5.5 MB/s against FTP's 43 kB/s (the logs
        recording), and on a radio ArduPilot keeps FTP bursts to a third of the link while LOG_DATA takes what is
        free. The Solo (3.3) has no FTP at all."""
        job = _Job("download", f"log download {log_id}", log_id, os.path.abspath(path),
                   "ftp" if via == "ftp" else "log_data")
        if not isinstance(log_id, int) or not 1 <= log_id <= 0xFFFF:
            return self._done(job, f"no log {log_id}: log numbers go from 1 to 65535")
        if via not in ("auto", "log_data", "ftp"):
            return self._done(job, f"no way {via!r} to download: auto, log_data or ftp")
        if via == "ftp" and self._firmware.ftp is False:
            return self._done(job, "the vehicle offers no MAVLink FTP (MAV_PROTOCOL_CAPABILITY_FTP): "
                                   "download by LOG_DATA")
        return self._queue(job)

    def download_latest(self, path: str) -> Future:
        """The newest log (the list is read first)."""
        return self._queue(_Job("download", "log download latest", -1, os.path.abspath(path)))

    def erase(self) -> Future:
        """LOG_ERASE (no reply: a list afterwards confirms it, and it is sent again if the logs are still there)."""
        return self._queue(_Job("erase", "log erase"))

    def cancel(self) -> None:
        """Stop what runs and drop what waits; a download keeps its .part to resume from."""
        with self._lock:
            jobs = list(self._jobs)
            for job in jobs:
                self._end(job, False, "cancelled")
            self._outbox.post(self._requests.end())
        self._outbox.wake()

    def close(self) -> None:
        """The driver closes: what runs stops, its last bytes on disk before it is told."""
        with self._lock:
            jobs = list(self._jobs)
            self._jobs.clear()
            self._stop_download()
        if self._part is not None:
            self._part.wait_closed(CLOSE_WAIT)
        with self._lock:
            for _, job, told in self._closing:
                self._settle(job, **told)
            self._closing.clear()
            for job in jobs:
                self._settle(job, False, "driver closed")

    def _queue(self, job: _Job) -> Future:
        if self._state.state.link.replay:
            return self._done(job, REPLAYING)
        with self._lock:
            self._jobs.append(job)
        self._outbox.wake()
        return job.future

    @staticmethod
    def _done(job: _Job, reason: str) -> Future:
        job.future.set_result(LogOutcome(job.name, False, reason))
        return job.future

    # -- the driver's threads (lock held) ------------------------------------------------------------------
    def on_message(self, m) -> None:
        kind = m.get_type()
        if kind == "LOG_ENTRY" and self._listing is not None:
            complete = self._listing.on_entry(m, self._clock())
            if complete:
                self._outbox.wake()
        elif kind == "LOG_DATA" and self._download is not None and m.id == self._download.entry.id:
            self._download.on_data(m, self._clock())

    def on_ftp(self, m) -> None:
        """A FILE_TRANSFER_PROTOCOL reply (reader thread, lock held): a log's, while one is read by FTP."""
        if self._download is not None:
            self._download.on_ftp(m, self._clock())

    def on_text(self, text: str) -> None:
        if text.startswith(DISARM_TEXT) and self._jobs:
            self._refused = text

    def service(self, now: float, state) -> list:
        if self._closing:
            self._tell_closed()
        if not self._jobs:
            return []
        job = self._jobs[0]
        if not job.started:
            self._refused = None                 # a refusal told before this job's first request is not its own
        if self._refused is not None:
            self._refused, reason = None, self._refused
            self._end(job, False, f"{reason}: the vehicle ignores log requests while armed")
            return [self._requests.end()]
        if not job.started:
            job.started = now
            if state.armed:                      # the vehicle says why only once: ask, and tell its words
                self._end(job, False, f"{DISARM_TEXT}: the vehicle ignores log requests while armed")
                return [self._requests.list(*ALL_IDS)]
        if state.link.replay:                     # (asked before the link was first told a recording)
            self._end(job, False, REPLAYING)
            return []
        link_up = state.connected                 # a lost link pauses: the download goes on when it is back
        if job.kind == "list" or (job.kind == "download" and not job.listed and self._download is None):
            return self._service_list(job, now, link_up)
        if job.kind == "download":
            return self._service_download(job, now, link_up)
        return self._service_erase(job, now, link_up)

    # -- listing -----------------------------------------------------------------------------------------------
    def _service_list(self, job: _Job, now: float, link_up: bool) -> list:
        listing = self._listing
        if listing is None:
            listing = self._listing = LogListing(self._requests, self._roundtrip)
            self.progress = LogProgress(0, "", 0, 0, 0.0, "listing")
        if not link_up:
            return []
        if listing.complete:
            return self._listed(job)
        out = listing.requests(now)
        if listing.failure:
            self._end(job, False, listing.failure)
        elif listing.quiet_until > now:
            self._outbox.tick_within(listing.quiet_until - now)     # asked again on time
        return out

    def _listed(self, job: _Job) -> list:
        entries = self._listing.result()
        self._listing = None
        self.entries = entries
        self.progress = None
        job.listed = True
        if job.kind == "list":
            self._end(job, True, f"{len(entries)} logs", entries=entries)
        elif job.kind == "download" and job.log_id < 0:
            if not entries:
                self._end(job, False, "no logs on the vehicle")
            else:
                job.log_id = entries[-1].id
        elif job.kind == "download" and not any(e.id == job.log_id for e in entries):
            have = f"logs {entries[0].id} to {entries[-1].id}" if entries else "no logs"
            self._end(job, False, f"no log {job.log_id} on the vehicle ({have})")
        self._outbox.wake()
        return [self._requests.end()]

    # -- downloading -------------------------------------------------------------------------------------------
    def _service_download(self, job: _Job, now: float, link_up: bool) -> list:
        d = self._download
        if d is None:
            entry = next(e for e in self.entries if e.id == job.log_id)
            if entry.size == 0:
                self._end(job, False, f"log {entry.id} is empty (0 bytes) on the vehicle")
                return []
            d = self._download = LogDownload(entry, job.path, job.via, job.started, self._outbox, self._requests,
                                             self._roundtrip, after=self._part)
            self._part = d.part
        out = d.service(now, link_up)
        if d.result is not None:
            ok, reason, fields = d.result
            self._end(job, ok, reason, **fields)
        else:
            self.progress = d.progress(now)
        return out

    def _stop_download(self) -> PartFile | None:
        """Stop what runs; the files of the download stopped, still closing (the worker writes the last bytes)."""
        d, self._download, self._listing, self.progress = self._download, None, None, None
        if d is None:
            return None
        d.close()
        return d.part

    # -- erasing -----------------------------------------------------------------------------------------------
    def _service_erase(self, job: _Job, now: float, link_up: bool) -> list:
        """The list first (what is there now), LOG_ERASE (no reply), then lists until none of those logs is left."""
        if not link_up:
            return []
        if not job.listed:
            return self._service_list(job, now, link_up)
        if job.erase_tries:
            if now < job.erase_at:
                return []
            if self.entries is None:             # the list that tells whether the erase was done
                return self._service_list(job, now, link_up)
            if not any(self._still_there(job, e) for e in self.entries):
                self._end(job, True, f"logs erased; {len(self.entries)} on the vehicle now", entries=self.entries)
                return []
            if job.erase_tries >= ERASE_TRIES:
                self._end(job, False, f"the logs are still there after {ERASE_TRIES} LOG_ERASE")
                return []
        else:
            job.before_erase = self.entries
            if not job.before_erase:
                self._end(job, True, "no logs on the vehicle to erase", entries=())
                return []
        job.erase_tries += 1
        job.erase_at = now + ERASE_WAIT
        self.progress = LogProgress(0, "", 0, 0, 0.0, "erasing")
        self.entries = None
        return [self._requests.erase()]

    @staticmethod
    def _still_there(job: _Job, entry: LogEntry) -> bool:
        """A log from the list before the erase: same id and time, as big or bigger (the open log grows). A vehicle
        logging while disarmed (LOG_DISARMED) begins log 1 again right after an erase: smaller, so not "still
        there"; ids restart at 1, so an id alone proves nothing."""
        return any(e.id == entry.id and e.time_utc == entry.time_utc and entry.size >= e.size
                   for e in job.before_erase)

    # -- the end of a job --------------------------------------------------------------------------------------
    def _end(self, job: _Job, ok: bool, reason: str, **fields) -> None:
        """``job`` is over (the one running, or one waiting): what runs for it stops, and it is told, once its
        download's files are closed: whoever is told may read the .part and its map at once (the window shows what
        a cancel kept, a resume opens them)."""
        part = None
        if self._jobs and self._jobs[0] is job:
            self._jobs.popleft()
            part = self._stop_download()
        elif job in self._jobs:
            self._jobs.remove(job)
        told = dict(ok=ok, reason=reason, **fields)
        if part is not None and not part.closed():
            self._closing.append((part, job, told))     # the worker wakes the ticker when it has closed them
        else:
            self._settle(job, **told)

    def _tell_closed(self) -> None:
        for item in [c for c in self._closing if c[0].closed()]:
            self._closing.remove(item)
            self._settle(item[1], **item[2])

    def _settle(self, job: _Job, ok: bool, reason: str, **fields) -> None:
        if not ok:
            log.warning("%s: %s", job.name, reason)
        self._settler.settle(job.future, LogOutcome(job.name, ok, reason, **fields))
