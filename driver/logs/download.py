"""One log downloaded into FILE: by LOG_DATA (the gap filler asks, filler.py) or by MAVLink FTP of its file
(driver/ftp/reader.py), into FILE.part and its map (partfile.py), resumed from them, checked with DFReader.

* A resumed .part's last held bytes are fetched again and must come back the same, else the .part was another
  log's: it is set aside as .part.old and the log fetched afresh (ids restart at 1 after an erase).
* LOG_REQUEST_END stops the stream but hundreds of queued LOG_DATA still come: any LOG_DATA of the log being
  fetched is kept, whichever request it answers.
* A lost link pauses the download (nothing is asked until the vehicle is heard again); while LOG_DATA comes it goes
  on though heartbeats are lost. With the link up and nothing new for :data:`STALL_LIMIT`, it ends, resumable.
* The finished file has the size the vehicle's stream ended at and DFReader reads it to its last byte (check.py);
  only then is it renamed to FILE.

Called on the driver's threads with the vehicle's state lock held; the file work is the PartFile's worker's.
"""
from __future__ import annotations

import logging
from collections import deque

from ..core.ports import Outbox
from ..core.roundtrip import RoundTrip
from ..ftp.reader import FtpList, FtpSpanRead
from .check import LogCheck
from .filler import GapFiller
from .model import LogEntry, LogProgress
from .partfile import PartFile
from .ranges import Ranges
from .wire import CHUNK, LogRequests

__all__ = ["LogDownload", "STALL_LIMIT"]

log = logging.getLogger(__name__)

# With the link up (heartbeats heard) and not one new byte for 20 s, the vehicle is not serving this download
# (another station's transfer holds it, or it was armed): it ends, resumable. Far longer than any silence the fault
# matrix puts on a link that stays up (150 ms bursts, a 1 s outage), and the FTP read's own stall alike.
STALL_LIMIT = 20.0
# A download goes on without a heartbeat while LOG_DATA came within the last second: at 30 % loss each way three
# heartbeats in a row are lost every half minute or so, and the download stopped until the next one (bff0406).
DATA_ALIVE = 1.0
# The bytes go to the .part and its map every 0.25 s: what a crash makes fetch again (1.4 MB at SITL's 5.5 MB/s,
# a quarter second of the stream); each costs two fsyncs and the map, on the part file's own worker.
FLUSH_INTERVAL = 0.25
# The rate shown is the bytes held over the last second: it smooths the stream's bursts, and follows a link that
# slows down within a second.
RATE_WINDOW = 1.0
# MAVLink FTP: the log's read uses session 1, the parameters' session 0 (the vehicle keeps the two files apart),
# and the log folders: HAL_BOARD_LOG_DIRECTORY on a flight controller's SD card, then SITL's.
FTP_SESSION = 1
LOG_FOLDERS = (b"/APM/LOGS", b"logs")


class LogDownload:
    """Log ``entry`` into ``path`` by ``via`` ("log_data" or "ftp"). :meth:`service` each tick returns what to send;
    :attr:`result` (ok, reason, the outcome's fields) once it is over, for the job queue to tell."""

    def __init__(self, entry: LogEntry, path: str, via: str, started: float, outbox: Outbox, requests: LogRequests,
                 roundtrip: RoundTrip, after: PartFile | None) -> None:
        self.entry, self.path, self._via, self._started = entry, path, via, started
        self._outbox, self._requests, self._roundtrip = outbox, requests, roundtrip
        self.part = PartFile(path, entry, outbox.wake, after)
        self.phase = "opening"                  # opening, downloading, closing (giving up), checking
        self.result: tuple[bool, str, dict] | None = None
        self.held = Ranges()
        self.filler: GapFiller | None = None    # by LOG_DATA
        self.ftp: FtpList | FtpSpanRead | None = None   # by FTP: the folder's list, then the file's read
        self._ftp_failure = ""
        self._ftp_end: int | None = None
        self._resume_check: tuple[int, bytes] | None = None
        self._resumed = self._received = 0
        self._progress_at = self._flushed_at = started
        self._history: deque = deque()          # (time, held) for the rate shown
        self._giving_up = ""
        self._fields: dict = {}

    @property
    def end(self) -> int | None:
        """The log's end, as the vehicle's stream (or the FTP read) told it."""
        return self.filler.end if self.filler is not None else self._ftp_end

    def _size_text(self) -> str:
        return f"{self.end} bytes" if self.end is not None else f"at least {self.entry.size} bytes"

    # -- news (the reader's thread) --------------------------------------------------------------------------------
    def on_data(self, m, now: float) -> None:
        if self.filler is None or self.phase != "downloading":
            return
        count, offset = min(int(m.count), CHUNK), int(m.ofs)
        self._received += count
        data = bytes(m.data[:count])
        if count and self._resume_check is not None:
            self._same_log(offset, data)
        if self.filler.on_data(offset, count, now):
            self.part.put(offset, data)
            self._progress_at = now
        if self.filler.due is not None and self.filler.due <= now:
            self._outbox.wake()

    def on_ftp(self, m, now: float) -> None:
        """A FILE_TRANSFER_PROTOCOL reply while the log is read by FTP."""
        ftp = self.ftp
        if ftp is None or self.phase != "downloading":
            return
        failure = ftp.on_message(m, now)
        if isinstance(ftp, FtpList):
            self._ftp_failure = failure or self._ftp_failure
        else:
            if ftp.taken is not None:           # a new chunk, already counted held in self.held by the reader
                (offset, chunk), ftp.taken = ftp.taken, None
                if self._resume_check is not None:
                    self._same_log(offset, chunk)
                self.held.add(offset, offset + len(chunk))   # (again, if _same_log began afresh)
                self.part.put(offset, chunk)
                self._received += len(chunk)
                self._progress_at = now
            if ftp.end is not None:
                self._ftp_end = ftp.end
            self._ftp_failure = failure or self._ftp_failure
        self._outbox.wake()

    # -- each tick (the ticker's thread) -----------------------------------------------------------------------
    def service(self, now: float, link_up: bool) -> list:
        part = self.part
        if self.phase == "opening":
            if part.failure:
                self.result = (False, part.failure, {})
                return []
            if part.resumed is None:
                return []                       # the worker wakes the ticker once the .part is open
            self._begin(now)
        if self.phase == "closing":
            if part.closed():
                self.result = (False, part.failure or f"{self._giving_up}: {part.saved} bytes of "
                               f"{self._size_text()} kept in {self.path}.part, download again to resume", {})
            return []
        if self.phase == "checking":
            self._checked()
            return []
        if part.failure:
            self.result = (False, part.failure, {})
            return [self._requests.end()]
        if now - self._flushed_at >= FLUSH_INTERVAL:
            part.flush(self.held, self.end)
            self._flushed_at = now
        if self.end is not None and self.held.whole(self.end):
            return self._complete(now)
        heard = self.filler.last_heard if self.filler is not None else 0.0
        if not link_up and now - heard > DATA_ALIVE:
            if self.filler is not None:
                self.filler.link_lost()
            self._progress_at = now             # a lost link pauses: the download goes on when it is back
            return []
        if self.ftp is not None:
            return self._service_ftp(now)
        if now - self._progress_at > STALL_LIMIT:
            self._give_up(f"no data from the vehicle for {STALL_LIMIT:.0f} s")
            return [self._requests.end()]
        asks = self.filler.requests(now)
        if self.filler.due is not None:
            self._outbox.tick_within(max(0.0, self.filler.due - now))
        out, last, msg = [], None, None
        for ask in asks:                        # a request that goes twice is one message sent twice
            if ask != last:
                msg, last = self._requests.data(self.entry.id, *ask), ask
            out.append(msg)
        return out

    def progress(self, now: float) -> LogProgress:
        if self.phase == "checking":
            return LogProgress(self.entry.id, self.path, self.end, self.end, 0.0, "checking")
        held = self.held.total()
        self._history.append((now, held))
        while len(self._history) > 2 and now - self._history[0][0] > RATE_WINDOW:
            self._history.popleft()
        t0, h0 = self._history[0]
        rate = (held - h0) / (now - t0) if now > t0 else 0.0
        return LogProgress(self.entry.id, self.path, self.end or max(self.entry.size, held), held, rate,
                           "downloading")

    def close(self) -> None:
        """Stop here: what is held goes to the .part (resumable); the worker closes it."""
        if self.phase in ("opening", "downloading"):
            self.part.close(self.held, self.end)
            self.phase = "closing"

    # -- the steps ---------------------------------------------------------------------------------------------
    def _begin(self, now: float) -> None:
        resumed = self.part.resumed
        self.held, self._resume_check = resumed.held, resumed.check
        self._resumed = self.held.total()
        if self._via == "ftp":
            self._ftp_end = resumed.end
            # the log folder listed first: a LOG_ENTRY id is a place in the list, not the file's number
            self.ftp = FtpList(now, LOG_FOLDERS, session=FTP_SESSION, stall=STALL_LIMIT)
        else:
            self.filler = GapFiller(self.entry.size, self.held, resumed.end, self._roundtrip)
        if self._resumed:
            log.info("log %d: resuming with %d bytes held", self.entry.id, self._resumed)
        self.phase = "downloading"
        self._progress_at = self._flushed_at = now

    def _complete(self, now: float) -> list:
        """Every byte to the end held: the worker writes the last, cuts the file at the end, DFReader checks it."""
        filler = self.filler
        self._fields = dict(log_id=self.entry.id, path=self.path, size=self.end, seconds=now - self._started,
                            bytes_received=self._received, resumed_from=self._resumed,
                            bytes_requested=filler.bytes_requested if filler else 0,
                            bytes_rerequested=filler.bytes_rerequested if filler else 0)
        self.part.finish(self.held, self.end, self.entry.size)
        self.phase = "checking"
        done = [self.ftp.terminate(self._outbox.target())] if self.ftp is not None else []
        return done + [self._requests.end()]

    def _checked(self) -> None:
        part, fields = self.part, self._fields
        if part.failure:
            self.result = (False, part.failure, {})
        elif isinstance(part.checked, LogCheck):
            reason = f"log {fields['log_id']} saved to {self.path}"
            if part.checked.ending:
                reason += f"; it ends with {part.checked.ending}"
            self.result = (True, reason, dict(fields, messages=part.checked.messages, ending=part.checked.ending))
        elif part.checked is not None:
            self.result = (False, f"log {fields['log_id']} downloaded ({fields['size']} bytes) but {part.checked}",
                           fields)

    def _give_up(self, why: str) -> None:
        """End the download, resumable: what is held goes to the .part first; the reason tells what the map on
        disk names (a full disk tells its own reason)."""
        self._giving_up = why
        self.close()

    def _same_log(self, offset: int, data: bytes) -> None:
        """Bytes at ``offset`` from the vehicle against what the resumed .part held there (PartFile._recheck)."""
        start, expect = self._resume_check
        lo, hi = max(offset, start), min(offset + len(data), start + len(expect))
        if lo >= hi:
            return
        if data[lo - offset:hi - offset] != expect[lo - start:hi - start]:
            log.warning("log %d: byte %d differs from %s.part: another log with that number", self.entry.id, lo,
                        self.path)
            self._another_log()
        elif lo == start:
            self._resume_check = (hi, expect[hi - start:]) if hi < start + len(expect) else None

    def _another_log(self) -> None:
        """The .part was another log's: set aside; only this session's bytes are kept."""
        self.held = self.part.start_afresh()
        self._resumed, self._resume_check = 0, None
        if self.filler is not None:
            self.filler.restart(self.held)
        else:
            self._ftp_end = None
            if isinstance(self.ftp, FtpSpanRead):
                self.ftp.held, self.ftp.next_burst = self.held, 0

    # -- by MAVLink FTP ----------------------------------------------------------------------------------------
    def _service_ftp(self, now: float) -> list:
        target = self._outbox.target()
        msgs, failure = self.ftp.service(now, target)
        if isinstance(self.ftp, FtpList) and self.ftp.done:
            path, failure = self._log_file()
            if path:
                # the read's bytes go to the .part as they come; what is held is self.held; its first burst
                # begins at the first chunk the .part lacks; bursts unbounded (one per 500 packets of the log)
                self.ftp = FtpSpanRead(now, path.encode(), FTP_SESSION, max_bursts=1 << 30, stall=STALL_LIMIT,
                                       seq=self.ftp.seq, held=self.held, roundtrip=self._roundtrip)
        failure = failure or self._ftp_failure
        if failure:
            self._give_up(f"MAVLink FTP {failure}")
            return msgs + [self.ftp.terminate(target)]
        return msgs

    def _log_file(self) -> tuple[str, str]:
        """(path, "") of the file of this log in the folder listed, else ("", why not): the oldest log's number +
        id - 1 (AP_Logger_Backend::log_num_from_list_entry), and its size must be the list's."""
        listing, entry = self.ftp, self.entry
        numbers = sorted(int(n[:-4]) for n in listing.files if n.upper().endswith(".BIN") and n[:-4].isdigit())
        if not numbers:
            return "", f"found no log in {listing.folder.decode()}"
        name = f"{numbers[0] + entry.id - 1:08d}.BIN"
        path = f"{listing.folder.decode().rstrip('/')}/{name}"
        size = next((s for n, s in listing.files.items() if n.upper() == name), None)
        if size != entry.size:
            return "", (f"found {path} with {size} bytes where log {entry.id} has {entry.size}" if size is not None
                        else f"found no {path} for log {entry.id}") + ": download it by LOG_DATA"
        return path, ""
