"""The vehicle's parameters inside the driver: the table, its download and every write, for one vehicle.

:class:`ParameterManager` is the part :class:`~driver.vehicle.vehicle.Vehicle` wires in (as QGroundControl's
ParameterManager is to its Vehicle): every PARAM_VALUE goes to :meth:`on_param_value` (reader thread), the
ticker calls :meth:`service`; both with the state lock held, and :meth:`service` only *returns* the messages
to send. The table is published in ``VehicleState.parameters`` as an immutable
:class:`~driver.params.model.ParameterTable`, rebuilt at most every :data:`PUBLISH_EVERY` while a list streams.
"""
from __future__ import annotations

import logging
import math
from concurrent.futures import Future
from typing import Callable

from ..core.firmware import FirmwareProfile
from ..core.results import CommandStatus, LinkStatus, Severity
from ..core.roundtrip import RoundTrip
from .cache import changed_names
from .download import Download
from .ftp import FtpDownload
from .model import Parameter, ParameterTable, ParameterValues, ParamType
from .setter import SET_RETRY, PendingSet
from .values import as_stored, format_value, type_problem, wire_problem

log = logging.getLogger(__name__)

__all__ = ["ParameterManager", "PUBLISH_EVERY"]

PUBLISH_EVERY = 0.1          # s between tables published while a download streams
NO_INDEX = 65535             # param_index of a reply to a read by name or to a set


def param_name(m) -> str:
    raw = m.param_id
    name = raw if isinstance(raw, str) else bytes(raw).decode("ascii", "replace")
    return name.split("\x00", 1)[0]


class ParameterManager:
    """Parameters of one vehicle; every method runs with the driver's state lock held."""

    def __init__(self, store, notifier, target: Callable[[], tuple[int, int]], firmware: FirmwareProfile,
                 roundtrip: RoundTrip, give_up_after: float = 7.0, set_retry: float = SET_RETRY) -> None:
        self._store = store
        self._firmware = firmware                # whether the vehicle reads its table over FTP
        self._roundtrip = roundtrip              # the link's one round trip: the download's waits
        self._set_retry = set_retry              # s without an echo before a PARAM_SET (or read back) goes again
        self._give_up_after = give_up_after      # s of a lost link before a download ends (it waits until then)
        self._lost_since: float | None = None
        self._losses = 0                         # the link's losses seen (LinkSupervisor.lost_count)
        self._notifier = notifier
        self._target = target
        self._values: dict[str, Parameter] = {}
        self._expected: int | None = None
        self._download: Download | None = None
        self._waiting: list[Future] = []         # fetches that end with this download
        self._sets: dict[str, PendingSet] = {}
        self._dirty = False
        self._published = -math.inf
        self._detail = ""
        self._cached: ParameterTable | None = None   # shown while the vehicle's own list is read
        self._ftp: FtpDownload | None = None         # @PARAM/param.pck on its way (driver.params.ftp)
        self._since_ftp: dict[str, Parameter] = {}   # values the vehicle sent one by one while the file was read
        self._ftp_note = ""                          # why this download reads the list though FTP was offered
        self._ftp_given_up: FtpDownload | None = None   # its TerminateSession goes out on the next tick
        self.use_ftp = True                          # read the whole table over MAVLink FTP where it is offered
        self.on_complete: Callable[[ParameterTable], None] | None = None   # the cache's hook

    # -- what callers ask (any thread, under the lock) ------------------------------------------------
    @property
    def table(self) -> ParameterTable:
        return self._store.view()["parameters"]

    def fetch(self, refresh: bool, now: float, cached: ParameterTable | None = None) -> Future:
        """Download every parameter; without ``refresh`` a complete table is answered at once and a partial one
        only has its missing indexes asked for. ``cached``: this vehicle's table from the cache, shown (and
        compared at the end) while the list is read when nothing is known yet."""
        future: Future = Future()
        if self._download is not None:
            self._waiting.append(future)         # one download at a time: this one ends with it
            return future
        if not refresh and self._expected is not None and self._complete():
            self._settle(future, CommandStatus.ACCEPTED, f"{len(self._values)} parameters (already complete)")
            return future
        download = Download(now, self._roundtrip)
        if refresh:
            self._values = {name: p for name, p in self._values.items() if p.index < 0}
            self._expected = None
        elif self._expected is not None:         # a partial table: ask only for what is missing
            download.expected, download.listing = self._expected, False
            download.have = {p.index for p in self._values.values() if 0 <= p.index < self._expected}
        self._download = download
        self._waiting.append(future)
        self._detail = "asking for the list" if download.listing else f"asking for {download.missing} missing"
        self._ftp_note = ""
        if download.listing and self.use_ftp and self._firmware.ftp:
            self._ftp = FtpDownload(now, self._roundtrip)
            self._since_ftp = {}
            self._detail = "reading @PARAM/param.pck over MAVLink FTP"
        if download.listing and cached is not None and cached.complete and self._expected is None:
            self._cached = cached
            self._detail = "from the cache: checking with the vehicle"
        self._publish(now, force=True)
        return future

    def value_problem(self, name: str, value: float) -> str:
        """Why ``name`` cannot hold ``value`` in the type the vehicle reported ("" when it can, or is not known)."""
        known = self._values.get(name)
        if known is None:
            if not math.isfinite(value):
                return "not a finite number"
            return wire_problem(value) if value == round(value) else ""
        problem = type_problem(known.type, value)
        return f"{format_value(None, value)}: {problem}" if problem else ""

    def set(self, name: str, value: float, now: float) -> Future:
        """PARAM_SET ``name``; the future resolves on the vehicle's echo (driver.params.setter)."""
        future: Future = Future()
        command = f"param {name}={format_value(None, value)}"
        known = self._values.get(name)
        ptype = known.type if known is not None else None
        if ptype is not None:
            problem = type_problem(ptype, value)
            if problem:
                self._settle(future, CommandStatus.REJECTED, f"{format_value(None, value)}: {problem}", command)
                return future
            value = as_stored(ptype, value)
        else:
            problem = self.value_problem(name, value)
            if problem:
                self._settle(future, CommandStatus.REJECTED, problem, command)
                return future
        old = self._sets.pop(name, None)
        if old is not None:
            self._settle(old.future, CommandStatus.ABORTED, f"superseded by {name}={format_value(ptype, value)}",
                         command, old.attempts)
        listed = known is not None and known.index >= 0
        self._sets[name] = PendingSet(name, value, ptype, future, known=known is not None,
                                      listed_complete=self._complete() and not listed)
        return future

    def abort_all(self, reason: str) -> None:
        for pending in list(self._sets.values()):
            self._settle(pending.future, CommandStatus.ABORTED, reason, pending.command, pending.attempts)
        self._sets.clear()
        if self._download is not None:
            self._end_download(CommandStatus.ABORTED, reason)

    def _link_lost(self) -> None:
        """Writes keep their tries for when the link is back (none is spent on a dead link)."""
        for pending in self._sets.values():
            pending.attempts = min(pending.attempts, max(0, pending.tries - 2))
            pending.reads = 0

    @property
    def reasking(self) -> bool:
        """Reads by index are out: each answer frees a place for the next (the ticker is woken for it)."""
        return self._download is not None and not self._download.listing

    # -- the vehicle's word (reader thread) -----------------------------------------------------------
    def on_ftp(self, m, now: float) -> None:
        """A FILE_TRANSFER_PROTOCOL message addressed to us."""
        ftp = self._ftp
        if ftp is None:
            return
        failure = ftp.on_message(m, now)
        if failure:
            self._ftp_failed(failure, now)

    def on_param_value(self, m, name: str, now: float) -> Parameter | None:
        """A PARAM_VALUE from the autopilot, its finite value and its name (:func:`param_name`) checked and
        decoded by the caller: into the table; it may confirm a write or advance the download."""
        try:
            ptype = ParamType(m.param_type)
        except ValueError:
            return None
        old = self._values.get(name)
        index = m.param_index
        if index == NO_INDEX or index >= m.param_count:
            # a read by name (or a set's echo) names no index: keep the one known, from the list or the cache
            known = old if old is not None else (self._cached.values.get(name) if self._cached is not None else None)
            index = known.index if known is not None else -1
        param = Parameter(name, as_stored(ptype, m.param_value), ptype, index)
        self._values[name] = param
        if self._ftp is not None:
            self._since_ftp[name] = param
        if index >= 0:
            if self._expected != m.param_count:
                self._expected = m.param_count
            download = self._download
            if download is not None:
                download.arrived(index, m.param_count, now)
        pending = self._sets.get(name)
        if pending is not None and pending.attempts:
            pending.ptype = ptype                 # the vehicle's own type, whatever we assumed
            confirmed = pending.confirms(ptype, param.value)
            if pending.reading and not confirmed and not pending.known:
                pending.known, pending.reads = True, 0    # it has the name, not our value: a listed name's tries
                pending.next_send = now
            elif confirmed or pending.reading:    # read back: what the vehicle holds is the answer
                del self._sets[name]
                read = f"read back after {pending.attempts} unechoed PARAM_SET" if pending.reading else ""
                self._settle(pending.future, CommandStatus.ACCEPTED if confirmed else CommandStatus.REFUSED,
                             read if confirmed else pending.failure(), pending.command, pending.attempts)
                self._publish(now, force=True)
                return param
        self._dirty = True
        if self._download is not None and self._download.complete:
            self._end_download(CommandStatus.ACCEPTED, f"{len(self._values)} parameters", now)
        elif self._download is None or index < 0:
            self._publish(now, force=True)        # one value changed: the pilot sees it at once
        else:
            self._publish(now)
        return param

    # -- the ticker ---------------------------------------------------------------------------------------
    def service(self, now: float, link: LinkStatus, losses: int) -> list:
        """Messages to send now (the caller sends them after releasing the lock); ``link``: the link's status now,
        ``losses``: how many times it was lost so far (each loss spares the writes' tries)."""
        out: list = []
        if losses != self._losses:
            self._losses = losses
            self._link_lost()
        if link is LinkStatus.LOST or link is LinkStatus.CLOSED:
            # a few lost heartbeats on a bad radio pause the download; a link gone for longer ends it
            self._lost_since = now if self._lost_since is None else self._lost_since
            if self._download is not None and (link is LinkStatus.CLOSED
                                               or now - self._lost_since >= self._give_up_after):
                d = self._download
                got = f"{len(d.have)} of {d.expected}" if d.expected else "none"
                self._end_download(CommandStatus.TIMED_OUT, f"link lost: {got} parameters received", now)
            return out
        self._lost_since = None
        if link is not LinkStatus.OK:
            return out                            # no vehicle yet: its answers would go nowhere
        target = self._target()
        if self._ftp_given_up is not None:           # the vehicle closes the file FTP gave up on
            out.append(self._ftp_given_up.terminate(target))
            self._ftp_given_up = None
        download = self._download
        if download is not None and self._ftp is not None:
            out += self._service_ftp(now, target)
        elif download is not None:
            msgs, failure = download.service(now, target)
            out += msgs
            if failure:
                self._end_download(CommandStatus.TIMED_OUT, failure, now)
            else:
                detail = (f"{len(download.have)} of {download.expected}" if download.listing and download.expected
                          else f"re-asking {download.missing} missing" if download.expected else "asking for the list")
                if self._ftp_note:
                    detail += f" · {self._ftp_note}"
                if detail != self._detail:
                    self._detail = detail
                    self._dirty = True
        for pending in list(self._sets.values()):
            if not pending.due(now) and not pending.answered_otherwise:
                continue
            if pending.attempts >= pending.tries and not pending.answered_otherwise and pending.can_read_back:
                out.append(pending.read_message(target))      # never echoed: what does the vehicle hold?
                pending.reads += 1
                pending.next_send = now + self._set_retry
                continue
            if pending.attempts >= pending.tries or pending.answered_otherwise:
                del self._sets[pending.name]
                self._settle(pending.future, CommandStatus.TIMED_OUT if pending.reported is None
                             else CommandStatus.REFUSED, pending.failure(), pending.command, pending.attempts)
                continue
            out.append(pending.message(target))
            pending.attempts += 1
            pending.next_send = now + self._set_retry
        if self._dirty:
            self._publish(now)
        return out

    # -- inside -------------------------------------------------------------------------------------------
    def _service_ftp(self, now: float, target: tuple[int, int]) -> list:
        ftp = self._ftp
        msgs, failure = ftp.service(now, target)
        if failure:
            self._ftp_failed(failure, now)
            return msgs
        if ftp.done:
            got = ftp.parameters()
            if isinstance(got, str):
                self._ftp_failed(got, now)
                return msgs
            values, count = got
            self._ftp = None
            # the file was packed when it was opened: a value the vehicle sent since (a set's echo, a read by name)
            # is newer than the file's, and stays (a confirmed write must not go back to its old value)
            newer = {n: Parameter(n, p.value, p.type, values[n].index if n in values else p.index)
                     for n, p in self._since_ftp.items()}
            self._since_ftp = {}
            self._values = {**{n: p for n, p in self._values.items() if p.index < 0 and n not in values}, **values,
                            **newer}
            self._expected = count
            self._end_download(CommandStatus.ACCEPTED, f"{len(values)} parameters over MAVLink FTP ({ftp.end:,} bytes "
                               f"in {ftp.frames} frames)", now)
            return msgs
        # the bar's "N of M": the file's real size once known, else the vehicle's estimate (never relied on)
        detail = f"FTP: {ftp.received} of {max(ftp.total, ftp.received)} bytes" if ftp.total else \
            "opening @PARAM/param.pck (FTP)"
        if detail != self._detail and not self._detail.startswith("from the cache"):
            self._detail = detail
            self._dirty = True
        return msgs

    def _ftp_failed(self, reason: str, now: float) -> None:
        """FTP did not work: the classic list from here on (for this vehicle until it says FTP again), and the
        pilot is told why, in the download's progress (the Parameters page), its result and the messages (the
        console prints them)."""
        self._ftp_given_up, self._ftp = self._ftp, None
        self._firmware.ftp_failed()
        self._ftp_note = f"MAVLink FTP {reason}; reading the list instead"
        self._detail = self._ftp_note
        self._store.add_message_locked(Severity.NOTICE, f"Parameters: {self._ftp_note}")
        self._publish(now, force=True)

    def _complete(self) -> bool:
        if self._expected is None:
            return False
        return sum(1 for p in self._values.values() if 0 <= p.index < self._expected) >= self._expected

    def _end_download(self, status: CommandStatus, reason: str, now: float = 0.0) -> None:
        d, self._download = self._download, None
        self._ftp = None
        waiting, self._waiting = self._waiting, []
        cached, self._cached = self._cached, None
        if d is not None and d.reads:
            reason += f" ({d.reads} asked again by index)"
        if self._ftp_note:
            reason += f" ({self._ftp_note.replace('reading the list instead', 'read the list instead')})"
            self._ftp_note = ""
        self._detail = "" if status is CommandStatus.ACCEPTED else reason
        self._publish(now, force=True)
        if cached is not None and status is CommandStatus.ACCEPTED:
            changed = changed_names(cached, self.table)
            names = ", ".join(changed[:8]) + (", ..." if len(changed) > 8 else "")
            self._store.add_message_locked(Severity.INFO, f"Parameters: {len(changed)} changed since this vehicle was "
                                           f"last seen{': ' + names if changed else ''}")
        for future in waiting:
            self._settle(future, status, reason, "parameters")
        if status is CommandStatus.ACCEPTED and self.on_complete is not None:
            try:
                self.on_complete(self.table)
            except Exception:
                log.exception("parameter cache")

    def _publish(self, now: float, force: bool = False) -> None:
        if not force and now - self._published < PUBLISH_EVERY:
            self._dirty = True
            return
        self._dirty = False
        self._published = now
        values, expected = self._values, self._expected
        if self._cached is not None:              # the cache's values until the vehicle's own arrive
            values, expected = {**self._cached.values, **values}, expected or self._cached.expected
        self._store.set(parameters=ParameterTable(ParameterValues(values), expected, self._download is not None,
                                                  self._detail))
        self._store.publish()

    def _settle(self, future: Future, status: CommandStatus, reason: str, command: str = "parameters",
                attempts: int = 0) -> None:
        self._notifier.settle(future, self._store.record_locked(command, status, reason, attempts))
