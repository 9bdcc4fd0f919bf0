"""Logs › Flight logs' logic: the vehicle's DataFlash logs listed, downloaded one after another, cancelled, erased,
and opened in the review view when saved.

Everything goes through ``drone.logs`` (driver/logs/control.py), whose calls return a Future at once: its outcome
comes back to the UI thread through a queued signal, and a download's progress is the driver's immutable
``LogProgress`` snapshot, read five times a second while one runs. Nothing here waits on the link, so the window
flies on (Land, Stop) whatever the logs do. One operation runs at a time (the vehicle serves one log transfer at a
time anyway); the others wait here, so Cancel stops exactly the log it is pressed for. A refusal is the vehicle's
own words ("Disarm for log download"). A connection without logs (a replayed recording, a remote drone) says why.

Files go to the logs folder as the vehicle names them (``00000012.BIN``); a cancelled or cut download keeps its
``.part`` and the driver resumes from it, also after a restart.
"""
from __future__ import annotations

import logging
import os
from collections import deque
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Callable

from PyQt5.QtCore import QObject, Qt, QTimer, pyqtSignal
from PyQt5.QtWidgets import QAction

from driver.logs.control import DISARM_TEXT
from driver.logs.ranges import load_part_map
from driver.vehicle.state import LinkStatus, Severity

from ..widgets.menus import menu_named
from .rows import LogRow, RowState, size_text

__all__ = ["FlightLogsController", "NO_LOGS", "NOT_CONNECTED", "REPLAYED"]

log = logging.getLogger(__name__)

NO_LOGS = ("this connection cannot download the vehicle's DataFlash logs (a remote drone: its server holds the "
           "link; run 'log download' in that server's console)")
REPLAYED = "a replayed recording has no vehicle to download DataFlash logs from"
NOT_CONNECTED = "no vehicle to download DataFlash logs from: File › Connect picks one"
PROGRESS_MS = 200


class _Relay(QObject):
    """Carries a finished operation from the driver's thread to the UI thread; parentless, so an answer that comes
    after the window is gone lands nowhere (as the adapter's relay)."""
    done = pyqtSignal(object, object)            # _Op, its Future


@dataclass
class _Op:
    kind: str                                    # "list", "download", "erase"
    log_id: int = 0
    logs: object = None                          # the drone's LogControl it was given to


class FlightLogsController(QObject):
    """``folder()``: where logs are saved; ``open_log(path)``: the review view opens a saved one; ``say(text,
    severity)``: how a download or an erase ended, for the window's Messages."""

    rowsChanged = pyqtSignal(object)             # tuple of LogRow, by number
    statusChanged = pyqtSignal(str)              # what runs, what came of it, or why not
    busyChanged = pyqtSignal(bool)               # an operation runs or waits

    def __init__(self, adapter, folder: Callable[[], str], open_log: Callable[[str], object],
                 parent: QObject | None = None, say: Callable[[str, Severity], None] | None = None) -> None:
        super().__init__(parent)
        self.adapter = adapter
        self.folder = folder
        self.open_log = open_log
        self.tell = say or (lambda _text, _severity: None)   # Messages: a download ends with its window closed too
        self.status = ""
        self.dialog = None
        self._rows: dict[int, LogRow] = {}
        self._ops: deque[_Op] = deque()
        self._running: _Op | None = None
        self._timer = QTimer(self)
        self._timer.setInterval(PROGRESS_MS)
        self._timer.timeout.connect(self._show_progress)
        self._relay = _Relay()
        self._relay.done.connect(self._settled, Qt.QueuedConnection)     # never inside _next, even when a
        # future is settled before its callback is added (armed, the refusal is at once)
        adapter.droneChanged.connect(self._vehicle_changed)

    # -- the window ---------------------------------------------------------------------------------------------
    def add_to_menu(self, window) -> QAction:
        """Logs › Flight logs…"""
        action = QAction("&Flight logs…", window)
        action.setObjectName("actionFlightLogs")
        action.setToolTip("The vehicle's DataFlash logs: download, open, erase")
        action.triggered.connect(lambda: self.show(window))
        menu_named(window, "menuLogs", "&Logs").addAction(action)
        return action

    def show(self, parent=None):
        """The Flight logs window (not modal: the pilot flies on); lists the logs the first time."""
        if self.dialog is None:
            from .dialog import FlightLogsDialog
            self.dialog = FlightLogsDialog(self, parent)
        self.dialog.show()
        self.dialog.raise_()
        self.dialog.activateWindow()
        if not self._rows and self._running is None and not self._ops:
            self.refresh()
        return self.dialog

    # -- state ----------------------------------------------------------------------------------------------------
    @property
    def rows(self) -> tuple[LogRow, ...]:
        return tuple(self._rows[n] for n in sorted(self._rows))

    @property
    def busy(self) -> bool:
        return self._running is not None or bool(self._ops)

    def unavailable(self) -> str:
        """Why this connection has no logs to download, or ""."""
        drone = self.adapter.drone
        if drone.replay is not None:
            return REPLAYED
        if drone.logs is None:
            return NOT_CONNECTED if drone.state().link.status is LinkStatus.CLOSED else NO_LOGS
        return ""

    def path(self, log_id: int) -> str:
        return os.path.join(self.folder(), f"{log_id:08d}.BIN")

    # -- what the pilot asks -----------------------------------------------------------------------------------
    def refresh(self) -> None:
        if not any(op.kind == "list" for op in self._ops):     # one list waiting is enough
            self._queue(_Op("list"))

    def download(self, log_ids) -> None:
        """These logs, one after another; a saved one again only when asked for by name (not by Download all)."""
        for log_id in log_ids:
            row = self._rows.get(log_id)
            if row is None or row.running:
                continue
            why = self.unavailable()
            if why:
                self._say(why)
                break
            self._rows[log_id] = row.but(state=RowState.QUEUED, reason="")
            self._queue(_Op("download", log_id))
        self._emit_rows()

    def download_all(self) -> None:
        self.download([r.log_id for r in self.rows if r.state is not RowState.SAVED])

    def cancel(self, log_id: int) -> None:
        """A waiting log is taken off the queue; the running one stops, its .part kept to resume from."""
        for op in list(self._ops):
            if op.kind == "download" and op.log_id == log_id:
                self._ops.remove(op)
                self._rows[log_id] = self._resting(self._rows[log_id])
                self._emit_rows()
        running = self._running
        if running is not None and running.kind == "download" and running.log_id == log_id:
            running.logs.cancel()                    # its future settles "cancelled"
        self.busyChanged.emit(self.busy)

    def erase(self) -> None:
        """LOG_ERASE (the dialog asked the pilot first); a list afterwards confirms it."""
        self._queue(_Op("erase"))

    def open(self, log_id: int) -> None:
        row = self._rows.get(log_id)
        if row is not None and row.openable:
            self._say(f"opening log {log_id} ({row.path})")
            self.open_log(row.path)

    # -- running one operation at a time -------------------------------------------------------------------------
    def _queue(self, op: _Op) -> bool:
        why = self.unavailable()
        if why:
            self._say(why)
            return False
        self._ops.append(op)
        self._next()
        return True

    def _next(self) -> None:
        while self._running is None and self._ops:
            op = self._ops.popleft()
            if op.kind == "download" and op.log_id not in self._rows:
                continue                             # erased, or gone from the list, while it waited
            op.logs = logs = self.adapter.drone.logs
            try:
                if op.kind == "list":
                    future, words = logs.list(), "asking the vehicle for its logs…"
                elif op.kind == "download":
                    path = self.path(op.log_id)
                    future, words = logs.download(op.log_id, path), f"downloading log {op.log_id} to {path}"
                    self._rows[op.log_id] = self._rows[op.log_id].but(state=RowState.DOWNLOADING, reason="")
                else:
                    future, words = logs.erase(), "erasing every log on the vehicle…"
            except Exception as exc:                 # noqa: BLE001 - said in the window, which flies on
                log.exception("log %s failed to start", op.kind)
                self._say(f"log {op.kind}: {exc}")
                if op.kind == "download":
                    self._rows[op.log_id] = self._rows[op.log_id].but(state=RowState.FAILED, reason=str(exc))
                continue
            self._running = op
            self._say(words)
            relay = self._relay                      # the callback holds the relay, not this controller
            future.add_done_callback(lambda f, o=op: relay.done.emit(o, f))
            if op.kind == "download":
                self._timer.start()
            self._emit_rows()
        self.busyChanged.emit(self.busy)

    def _settled(self, op: _Op, future: Future) -> None:
        if op is not self._running:                  # an answer from a vehicle left behind
            return
        self._running = None
        self._timer.stop()
        try:
            outcome = future.result(timeout=0)
        except Exception as exc:                     # noqa: BLE001 - the driver settles LogOutcome, never raises
            log.exception("log %s", op.kind)
            outcome = None
            self._say(f"log {op.kind}: {type(exc).__name__}: {exc}")
            if op.kind == "download" and op.log_id in self._rows:
                self._rows[op.log_id] = self._resting(self._rows[op.log_id], str(exc)).but(state=RowState.FAILED)
        if outcome is not None:
            {"list": self._listed, "download": self._downloaded, "erase": self._erased}[op.kind](op, outcome)
        self._emit_rows()
        self._next()

    def _listed(self, _op: _Op, outcome) -> None:
        if not outcome.ok:
            self._say(outcome.reason)
            return
        self._fill(outcome.entries)
        n = len(outcome.entries)
        self._say(f"{n} log{'s' if n != 1 else ''} on the vehicle" if n else "no logs on the vehicle")

    def _fill(self, entries) -> None:
        """Rows for the vehicle's list; what runs or waits keeps its state, the rest is read from the folder."""
        rows = {}
        for entry in entries:
            old = self._rows.get(entry.id)
            rows[entry.id] = old.but(size=entry.size, time_utc=entry.time_utc) if old is not None and old.running \
                else self._on_disk(LogRow(entry.id, entry.size, entry.time_utc, self.path(entry.id)))
        self._rows = rows

    @staticmethod
    def _on_disk(row: LogRow) -> LogRow:
        """SAVED when the folder holds the file at the vehicle's size, PARTIAL when a .part of this log is kept."""
        try:
            if os.path.getsize(row.path) == row.size:
                return row.but(state=RowState.SAVED, held=row.size, reason="")
        except OSError:
            pass
        part = load_part_map(row.path)
        if part is not None and part.log_id == row.log_id and part.time_utc == row.time_utc \
                and os.path.exists(row.path + ".part"):
            return row.but(state=RowState.PARTIAL, held=part.ranges.total())
        return row.but(state=RowState.ON_VEHICLE, held=0)

    def _resting(self, row: LogRow, reason: str = "") -> LogRow:
        return self._on_disk(row).but(reason=reason, rate=0.0, seconds_left=None)

    def _downloaded(self, op: _Op, outcome) -> None:
        row = self._rows.get(op.log_id)
        if row is None:
            return
        if outcome.ok:
            self._rows[op.log_id] = row.but(state=RowState.SAVED, size=outcome.size, held=outcome.size,
                                            path=outcome.path, rate=0.0, seconds_left=None, reason="")
            self._say(f"log {op.log_id} saved: {outcome.path} ({size_text(outcome.size)} in {outcome.seconds:.1f} s, "
                      f"{size_text(int(outcome.rate))}/s)")
            self.tell(f"Flight log {op.log_id} saved: {outcome.path}", Severity.INFO)
            return
        rest = self._resting(row, outcome.reason)
        if rest.state is RowState.ON_VEHICLE and outcome.reason != "cancelled":
            rest = rest.but(state=RowState.FAILED)
        elif rest.state is RowState.PARTIAL and outcome.reason == "cancelled":
            rest = rest.but(reason=f"cancelled: {size_text(rest.held)} kept to resume from")
        self._rows[op.log_id] = rest
        self._say(f"log {op.log_id}: {rest.reason}")
        if outcome.reason != "cancelled":
            self.tell(f"Flight log {op.log_id} not downloaded: {outcome.reason}", Severity.WARNING)
        if outcome.reason.startswith(DISARM_TEXT):   # the rest would be refused alike: they wait no more
            for waiting in [o for o in self._ops if o.kind == "download"]:
                self._ops.remove(waiting)
                self._rows[waiting.log_id] = self._resting(self._rows[waiting.log_id])

    def _erased(self, _op: _Op, outcome) -> None:
        if outcome.ok:
            self._fill(outcome.entries)
        self._say(outcome.reason if not outcome.ok else
                  f"logs erased on the vehicle; {len(outcome.entries)} there now (the files saved here are kept)")

    def _show_progress(self) -> None:
        """The driver's progress snapshot into the running log's row."""
        op = self._running
        progress = op.logs.progress if op is not None and op.kind == "download" else None
        if progress is None or progress.log_id != op.log_id or op.log_id not in self._rows:
            return
        state = RowState.CHECKING if progress.phase == "checking" else RowState.DOWNLOADING
        row = self._rows[op.log_id]
        new = row.but(state=state, size=max(progress.size, 1), held=progress.held, rate=progress.rate,
                      seconds_left=progress.seconds_left)
        if new != row:
            self._rows[op.log_id] = new
            self._emit_rows()

    def _vehicle_changed(self, _drone) -> None:
        """Another vehicle (a fleet's pick, File › Connect): what ran on the one left behind stops (a download
        keeps its .part), and the list is that vehicle's no more."""
        running, self._running = self._running, None
        self._ops.clear()
        self._timer.stop()
        if running is not None:
            running.logs.cancel()
        self._rows = {}
        self._emit_rows()
        self.busyChanged.emit(False)
        self._say(self.unavailable() or "another vehicle: Refresh lists its logs")

    def _emit_rows(self) -> None:
        self.rowsChanged.emit(self.rows)

    def _say(self, text: str) -> None:
        self.status = text
        self.statusChanged.emit(text)
