"""``FILE.part`` and its map ``FILE.part.json`` for one download, written on a worker thread of their own.

The bytes of a log go to FILE.part at their offsets, and the map (ranges.py) names the ranges written, so a
dropped link or an app restart resumes from them. The driver's reader and ticker hold the vehicle's state lock
while they handle a LOG_DATA; all they do here is queue. Everything that touches the disk (opening and checking a
resumed .part, the writes, the fsyncs, the map of tens of thousands of spans a lossy download holds: 33 ms to save
for a 20 MB log at 30 % loss, four times a second) runs on the worker, so a slow disk never holds that lock.

What resume relies on, in the order the worker does it: a batch of bytes written, the .part fsynced, then the map
saved (its tmp file fsynced before it replaces the map). The map it saves is the download's held ranges as they
were when that batch was handed over: every byte they name was put in that batch or an earlier one, so the map
never claims bytes that are not on disk. A write the disk refuses leaves the last map as it was. Each new
PartFile waits for the one before it to close its file (a download resumed at once after a cancel reads a
finished .part).
"""
from __future__ import annotations

import errno
import logging
import os
import queue
import threading
from dataclasses import dataclass
from typing import Callable

from .check import LogCheck, LogFileError, check_dataflash
from .model import LogEntry
from .ranges import PartMap, Ranges, load_part_map, save_part_map
from .wire import CHUNK

__all__ = ["PartFile", "Resumed"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Resumed:
    """What the .part holds when it is opened: ``held`` (the caller's own copy of the ranges), where the vehicle's
    stream said the log ends (None: not known, or stale), and the last held bytes, un-held to be fetched again
    and compared (``check``: (offset, what the .part had there); see :meth:`PartFile._recheck`)."""
    held: Ranges
    end: int | None
    check: tuple[int, bytes] | None


class PartFile:
    """The files of one download. The caller (any one thread at a time: the driver's, under the state lock) calls
    :meth:`put` for each byte it holds, :meth:`flush` with what it holds, :meth:`start_afresh`, :meth:`finish`,
    :meth:`close`, and reads :attr:`resumed`, :attr:`failure`, :attr:`saved`, :attr:`checked`; ``wake`` is called
    when one of those has news."""

    def __init__(self, path: str, entry: LogEntry, wake: Callable[[], None], after: "PartFile | None" = None):
        self.path, self._entry, self._wake = path, entry, wake
        self.resumed: Resumed | None = None     # set once the .part is open
        self.failure = ""                       # the disk's refusal, in words (then nothing more is written)
        self.saved = 0                          # bytes the map on disk names
        self.checked: LogCheck | str | None = None   # after finish(): DFReader's count, or why the file is no log
        self._pending: list[tuple[int, bytes]] = []  # bytes put since the last flush (the caller's side)
        self._commands: queue.SimpleQueue = queue.SimpleQueue()
        self._closed = threading.Event()
        # the worker's side
        self._file = None
        self._map: PartMap | None = None
        self._unsynced = 0                      # bytes written since the last map saved
        self._named: Ranges | None = None       # what the next map names: the held ranges of the last batch
        self._thread = threading.Thread(target=self._run, args=(after,), name="log-part", daemon=True)
        self._thread.start()

    # -- the caller's side (no I/O) ------------------------------------------------------------------------------
    def put(self, offset: int, data: bytes) -> None:
        self._pending.append((offset, data))

    def flush(self, held: Ranges, end: int | None) -> None:
        """Hand the bytes put so far to the worker, with what the caller holds once they are written (every byte
        of it put by now) and the log's end as the stream told it: the map it saves next."""
        batch, self._pending = self._pending, []
        self._commands.put(("write", batch, held.copy(), end))

    def start_afresh(self) -> Ranges:
        """The .part was another log's: it is set aside as .part.old and a new one begun. The bytes put since
        the last flush (this session's, from the vehicle) go to the new one: returns them as ranges."""
        self._commands.put(("afresh",))
        return Ranges((o, o + len(b)) for o, b in self._pending)

    def finish(self, held: Ranges, end: int, announced: int) -> None:
        """The log is whole: the last bytes to disk, the file cut at ``end``, then DFReader reads it (it must reach
        ``announced``, the size listed) and it becomes FILE (:attr:`checked` tells)."""
        self.flush(held, end)
        self._commands.put(("finish", end, announced))

    def close(self, held: Ranges, end: int | None) -> None:
        """The download stops: the last bytes to disk and the .part closed, resumable."""
        self.flush(held, end)
        self._commands.put(("close",))

    def closed(self) -> bool:
        return self._closed.is_set()

    def wait_closed(self, timeout: float | None = None) -> bool:
        return self._closed.wait(timeout)

    # -- the worker ----------------------------------------------------------------------------------------------
    def _run(self, after: "PartFile | None") -> None:
        if after is not None:
            after.wait_closed()
        try:
            self.resumed = self._open()
            self._wake()
            while True:
                command = self._commands.get()
                if command[0] == "write":       # each batch synced and named on its own: a worker that lags
                    self._write(*command[1:])   # keeps its map one batch behind, not many (a disk that fills
                    self._sync()                # meanwhile keeps what came before it)
                elif command[0] == "afresh":
                    self._afresh()
                elif command[0] == "finish":
                    self._finish(*command[1:])
                    return
                else:
                    self._close_file()
                    return
        except Exception as exc:                # noqa: BLE001 - told, never a silent dead download
            if not self.failure:
                log.exception("log %d: %s.part", self._entry.id, self.path)
                self.failure = f"could not write the log: {self.path}.part: {exc}"
            self._close_file()
        finally:
            self._closed.set()
            self._wake()

    def _open(self) -> Resumed:
        """A .part of this log (same id, not longer than listed, with its map) is resumed; anything else is set
        aside as .part.old (another log with that number: not mixed in) and a new one begun."""
        path, entry = self.path, self._entry
        part = load_part_map(path)
        fresh = part is None or part.log_id != entry.id or not part.ranges.spans \
            or part.ranges.spans[-1][1] > entry.size or not os.path.exists(path + ".part")
        if fresh and part is not None and part.ranges.spans:
            _set_aside(path)
        if fresh:
            part = PartMap(entry.id, entry.time_utc, Ranges(), None, entry.size)
        # the end the stream told, while the list still gives the size it was fetched by (a smaller end than the
        # list's is stale: the log grew, or its stream broke off)
        end = part.size if part.size and part.size >= entry.size and part.listed in (0, entry.size) else None
        try:
            folder = os.path.dirname(path)
            if folder:
                os.makedirs(folder, exist_ok=True)
            self._file = open(path + ".part", "wb" if fresh else "r+b")
            if fresh:
                save_part_map(path, part)
        except OSError as exc:
            self.failure = f"{_disk_words(exc)}: {path}: {exc.strerror or exc}"
            raise
        check = None if fresh else self._recheck(part)
        self._map = part
        self.saved = part.ranges.total()
        return Resumed(part.ranges.copy(), end, check)

    def _recheck(self, part: PartMap) -> tuple[int, bytes]:
        """The .part's last held bytes are fetched again and must come back the same, else it is another log.

        Neither id nor time tells a log apart: ids restart at 1 after an erase, a board without a clock dates every
        log alike, and the open log's time is the clock's now at each list (AP_Logger_File::_get_log_time). The
        last held bytes (DataFlash records with their TimeUS) differ between two logs; the first ones (FMT, PARM)
        do not. So they are un-held here, and the download compares them when they come."""
        a, b = part.ranges.spans[-1]
        start = max(a, b - CHUNK)
        self._file.seek(start)
        expect = self._file.read(b - start)
        part.ranges = Ranges(part.ranges.spans[:-1] + ([[a, start]] if start > a else []))
        part.time_utc, part.listed = self._entry.time_utc, self._entry.size
        return start, expect

    def _write(self, batch: list[tuple[int, bytes]], held: Ranges, end: int | None) -> None:
        if self.failure:
            return                              # the disk refused: the map on disk stays what it was
        self._unsynced += sum(len(data) for _, data in batch)
        i = 0
        try:
            while i < len(batch):               # runs of consecutive chunks, one write each
                start, data = batch[i]
                run, top = [data], start + len(data)
                i += 1
                while i < len(batch) and batch[i][0] == top:
                    run.append(batch[i][1])
                    top += len(batch[i][1])
                    i += 1
                self._file.seek(start)
                self._file.write(b"".join(run))
        except OSError as exc:
            self._refused(exc)
            return
        self._named, self._map.size = held, end

    def _sync(self) -> None:
        """What was written to the disk, then the map that names it."""
        if self._named is None or self.failure:
            return
        try:
            self._file.flush()
            self._map.ranges, self._named = self._named, None
            save_part_map(self.path, self._map)     # fsyncs the .part first
            self._unsynced = 0
            self.saved = self._map.ranges.total()
        except OSError as exc:
            self._refused(exc)

    def _refused(self, exc: OSError) -> None:
        self.failure = f"{_disk_words(exc)}: {self.path}.part could not take {self._unsynced} more bytes " \
                       f"({exc.strerror or exc}); kept {self.saved} bytes in {self.path}.part, resumable"
        self._wake()

    def _afresh(self) -> None:
        log.warning("log %d: %s.part holds another log with that number: kept as .part.old, fetched afresh",
                    self._entry.id, self.path)
        self._close_file()
        _set_aside(self.path)
        entry = self._entry
        self._map = PartMap(entry.id, entry.time_utc, Ranges(), None, entry.size)
        self._named, self.saved = None, 0
        try:
            self._file = open(self.path + ".part", "wb")
            save_part_map(self.path, self._map)     # names nothing yet: the set-aside log's ranges are not this one's
        except OSError as exc:
            self.failure = f"{self.path}.part: {exc.strerror or exc}"
            self._wake()

    def _finish(self, end: int, announced: int) -> None:
        """The file cut at ``end`` and closed; DFReader reads it whole, then it is renamed to FILE."""
        if not self.failure:
            try:
                self._file.truncate(end)
            except OSError as exc:
                self._refused(exc)
        self._close_file()
        self._closed.set()
        if self.failure:
            return
        path = self.path
        try:
            checked = check_dataflash(path + ".part", announced)
            os.replace(path + ".part", path)
            os.remove(path + ".part.json")
            self.checked = checked
        except (LogFileError, OSError) as exc:
            self.checked = str(exc)
        except Exception as exc:                # noqa: BLE001 - the check itself broke: told, the .part kept
            log.exception("log %d: checking %s.part", self._entry.id, path)
            self.checked = f"its check failed ({type(exc).__name__}: {exc}); the file is kept as {path}.part"

    def _close_file(self) -> None:
        if self._file is None:
            return
        try:
            self._file.close()
        except OSError as exc:                  # bytes still buffered on a full disk: the map does not name them
            log.info("log %d: %s.part closed without its last bytes (%s)", self._entry.id, self.path, exc)
        self._file = None


def _set_aside(path: str) -> None:
    try:
        os.replace(path + ".part", path + ".part.old")
    except OSError:
        pass


def _disk_words(exc: OSError) -> str:
    if exc.errno in (errno.ENOSPC, errno.EDQUOT):
        return "no space left on the disk"
    if exc.errno == errno.EFBIG:
        return "no room for a larger file"      # the file system's or the process's (RLIMIT_FSIZE) limit
    return "could not write the log"
