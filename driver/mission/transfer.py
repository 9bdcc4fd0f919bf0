"""The transfer part: upload, download and clear missions, fences and rally points (MAVLink's mission protocol),
as MAVSDK's MissionRaw and QGroundControl's PlanManager do, one transfer per plan kind at a time.

Nothing is reported done unless the vehicle said so: an upload is ACCEPTED only once its MISSION_ACK accepted it
and the plan read back means the same (:func:`driver.mission.wire.difference`). If that last ACK is lost the
vehicle cannot send it again (it has left its upload), so the read-back alone decides, and the result says so.

Our side times out and re-asks too: MISSION_COUNT until the first request, MISSION_REQUEST_LIST until the
count, each missing item of a download, and the item last sent while the vehicle's next request does not come
(a lost item costs one re-ask time, not the vehicle's own 1 s; if it was the request that was lost, the
vehicle answers INVALID_SEQUENCE, which does not end an upload and tells us it wants the next item). The re-ask
time follows the link: the timeout of the vehicle's one round-trip estimate (:class:`driver.core.roundtrip.
RoundTrip`, which every message of a transfer answered after being sent once feeds), between :data:`MIN_RETRY`
and :data:`MAX_RETRY`. What the firmware speaks (MISSION_ITEM_INT, fences and rally points in the mission
protocol) is its profile's (:class:`driver.core.firmware.FirmwareProfile`).

MISSION_ACK ERROR proves nothing by itself: ArduPilot sends it for every item that arrives while it is not
receiving that plan (GCS_Common.cpp, GCS_MAVLINK::handle_mission_item, ``if (!prot->receiving)``), so our last
item sent again after the vehicle completed the upload (its ACCEPTED lost on the way), or a duplicate of it,
brings an ERROR for a plan the vehicle holds. In doubt the vehicle's plan decides: an upload or a clear answered
ERROR is read back, and refused (with the vehicle's word) only if the vehicle does not hold it; a download never
takes ERROR for an answer (MISSION_REQUEST_LIST is never answered with it), it keeps asking.

:class:`PlanTransfers` runs on the driver's ticker and reader with the state lock held: ``service`` and
``on_message`` only *return* the messages to send; futures settle on the driver's :class:`Notifier`.
"""
from __future__ import annotations

import logging
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core.firmware import FirmwareProfile
from ..core.results import CommandResult, CommandStatus
from ..core.roundtrip import RoundTrip
from .legacy_rally import LegacyRally
from .readback import READ_PATIENCE, ReadBack
from .plan import Plan, PlanKind, TransferDirection, TransferOutcome, TransferProgress
from .wire import from_wire, home_slot, result_meaning, to_wire

__all__ = ["PlanTransfers", "MIN_RETRY", "MAX_RETRY"]

log = logging.getLogger(__name__)

MIN_RETRY = 0.1              # s: the shortest re-ask time, whatever the link
MAX_RETRY = 1.5              # s: the longest (QGroundControl's ack timeout)
START_ATTEMPTS = 8           # MISSION_COUNT / MISSION_REQUEST_LIST / MISSION_CLEAR_ALL sent this often (the list
                             # for READ_PATIENCE s at the least: readback.py) ...
START_PATIENCE = START_ATTEMPTS * MAX_RETRY   # s ... and for this long: unanswered, each waits twice as long as
                             # the one before (RFC 6298's backoff), so a fast link's 0.1 s re-ask rides out an outage
ITEM_ATTEMPTS = 12           # a download's item asked this often before the transfer fails ...
ITEM_PATIENCE = 8.0          # s ... and for this long since it was first asked (ArduPilot's own item timeout):
                             # on a fast link 12 re-asks take 1.2 s, too short for a loss streak on a radio
WINDOW = 4                   # a download's requests in flight at once (the vehicle answers each at once)
SILENCE = 10.0               # s without a word from the vehicle during an upload (it gives up after 8 s)
FINAL_ACK_WAIT = 3           # re-ask times after the last item before the read-back decides alone ...
FINAL_ACK_MIN = 1.5          # s, and at least this: the vehicle asks a lost last item again after 1 s
REASON_WAIT = 1.0            # s a NO_SPACE refusal waits for the vehicle's text that says why (it follows the ACK:
                             # "Only 0 items are supported" before "ArduPilot Ready")


@dataclass(eq=False)
class _Transfer:
    kind: PlanKind
    direction: TransferDirection
    future: Future
    plan: Plan | None = None                  # upload: what is sent (mission: without the home slot)
    wire: list = field(default_factory=list)  # upload: the items on the wire (mission: home slot first)
    stage: str = "start"                      # start | items | readback | refused (waiting for the reason) | done
    count: int | None = None
    received: dict = field(default_factory=dict)
    asked: int = -1                           # upload: the item the vehicle wants now (its last request)
    top: int = -1                             # upload: the highest item sent
    waiting: dict = field(default_factory=dict)   # download: item -> [last asked, times asked, first asked], in flight
    sends: dict = field(default_factory=dict)     # upload: item -> times sent (an item sent once answers cleanly)
    attempts: int = 0
    next_send: float = 0.0
    heard: float = 0.0                        # the last time the vehicle said something about this transfer
    sent_at: float = 0.0
    acked: bool = False                       # upload: MISSION_ACK ACCEPTED arrived
    last_sent_at: float = 0.0                 # upload: when the last item went out
    upload: "_Transfer | None" = None         # a read-back: the upload it checks
    detail: str = ""
    legacy: bool = False                      # rally points by RALLY_POINT (ArduCopter 3.3: legacy_rally.py)
    probing: int | None = None                # upload: the item sent again unasked (its INVALID_SEQUENCE means
                                              # the vehicle has it); None once the vehicle asked anything
    resent: int = 0
    said: str = ""                            # a MISSION_ACK ERROR the vehicle sent, kept until the plan decides
    first_asked: float | None = None          # when the start message first went out
    verifying: float | None = None            # a read-back going on after its upload's verdict: since when


class PlanTransfers(LegacyRally, ReadBack):
    """The transfers of one vehicle. ``record(name, status, reason)`` stores a result (lock held)."""

    def __init__(self, codec, source: tuple[int, int], target: Callable[[], tuple[int, int]],
                 record: Callable[[str, CommandStatus, str], CommandResult], settle, home: Callable[[], object],
                 firmware: FirmwareProfile, roundtrip: RoundTrip):
        self._codec = codec                   # a pymavlink MAVLink used only to build messages
        self._source = source                 # our (system, component): what the vehicle's answers target
        self._target = target
        self._record = record
        self._settle = settle                 # (future, value): settles on the notifier
        self._home = home
        self._firmware = firmware             # what the vehicle's mission protocol carries
        self._roundtrip = roundtrip           # the link's one round trip: every re-ask time
        self._running: dict[PlanKind, _Transfer] = {}
        self._out: list = []
        self.changed = False                  # progress changed since the last look (the driver republishes)
        self.ended: list = []                 # (kind, direction, status, plan) of transfers ended since then

    # -- what the vehicle speaks -----------------------------------------------------------------------
    def _mavlink2(self) -> bool:
        return self._firmware.mavlink2

    @property
    def integer(self) -> bool:
        return self._firmware.integer_items

    def unsupported(self, kind: PlanKind) -> str:
        """Why this vehicle cannot transfer ``kind`` here ("" when it can)."""
        if kind is PlanKind.MISSION:
            return ""
        if not self._firmware.mission_types and kind is PlanKind.FENCE:
            return ("this vehicle's firmware has no polygon fence (ArduCopter 3.3, as on the Solo, fences only with "
                    "FENCE_RADIUS around home and FENCE_ALT_MAX: set those parameters)")
        return ""

    # -- starting (any thread, lock held) ----------------------------------------------------------------
    def busy(self, kind: PlanKind) -> str:
        t = self._running.get(kind)
        return f"a {kind.label} {t.direction.value} is running" if t is not None and t.verifying is None else ""

    def upload(self, plan: Plan, now: float) -> Future:
        wire = list(plan.items)
        if plan.kind is PlanKind.MISSION and wire:
            wire.insert(0, home_slot(self._home()))
        t = _Transfer(plan.kind, TransferDirection.UPLOAD, Future(), plan=plan, wire=wire, count=len(wire))
        return self._begin(t, now)

    def download(self, kind: PlanKind, now: float) -> Future:
        return self._begin(_Transfer(kind, TransferDirection.DOWNLOAD, Future()), now)

    def clear(self, kind: PlanKind, now: float) -> Future:
        return self._begin(_Transfer(kind, TransferDirection.CLEAR, Future(), plan=Plan(kind)), now)

    def _begin(self, t: _Transfer, now: float) -> Future:
        t.heard = now
        t.legacy = self.legacy_rally(t.kind)
        self._running[t.kind] = t
        self.changed = True
        return t.future

    def cancel(self, kind: PlanKind) -> bool:
        t = self._running.get(kind)
        if t is None:
            return False
        self._end(t, CommandStatus.ABORTED, "cancelled by the pilot")
        return True

    def abort_all(self, reason: str) -> None:
        for t in list(self._running.values()):
            self._end(t, CommandStatus.ABORTED, reason)

    def progress(self) -> tuple[TransferProgress, ...]:
        out = []
        for t in self._running.values():
            shown = t.upload or t
            done = len(t.received) if t.direction is not TransferDirection.UPLOAD or t.upload else max(t.top, 0)
            detail = t.detail or ("reading back" if t.upload else "")
            out.append(TransferProgress(shown.kind, shown.direction, done, t.count or 0, True, detail))
        return tuple(out)

    # -- the ticker ------------------------------------------------------------------------------------------
    def service(self, now: float) -> list:
        for t in list(self._running.values()):
            self._service(t, now)
        out, self._out = self._out, []
        return out

    def _retry(self, t: _Transfer) -> float:
        return min(MAX_RETRY, max(MIN_RETRY, self._roundtrip.timeout()))

    def _service(self, t: _Transfer, now: float) -> None:
        if t.legacy:
            self._legacy_service(t, now)
            return
        if t.stage == "refused":
            if now >= t.next_send:
                self._end(t, CommandStatus.REFUSED, t.said)
            return
        if t.stage == "items" and t.direction is TransferDirection.DOWNLOAD:
            for seq, entry in list(t.waiting.items()):
                if now - entry[0] < self._retry(t):
                    continue
                if entry[1] >= ITEM_ATTEMPTS and now - entry[2] >= ITEM_PATIENCE:
                    why = (f"item {seq} never came ({entry[1]} requests in {now - entry[2]:.0f} s); "
                           f"{len(t.received)} of {t.count} received")
                    if t.upload is None:
                        self._end(t, CommandStatus.TIMED_OUT, f"the vehicle answered {t.said}; {why}" if t.said
                                  else why)
                        return
                    if self._unanswered(t, why, now):
                        return
                self._ask_item(t, seq, now)
            return
        if now < t.next_send:
            return
        if t.stage == "start":
            listing = t.direction is TransferDirection.DOWNLOAD
            patience = READ_PATIENCE if listing and not (t.upload is not None and t.upload.acked) else START_PATIENCE
            if t.attempts >= START_ATTEMPTS and now - t.first_asked >= patience:
                what = {TransferDirection.UPLOAD: "MISSION_COUNT", TransferDirection.DOWNLOAD: "MISSION_REQUEST_LIST",
                        TransferDirection.CLEAR: "MISSION_CLEAR_ALL"}[t.direction]
                said = f" (the vehicle answered {t.said})" if t.said else ""
                why = f"no answer to {what} after {t.attempts} attempts in {now - t.first_asked:.0f} s{said}"
                if t.upload is None:
                    self._end(t, CommandStatus.TIMED_OUT, why)
                    return
                if self._unanswered(t, why, now):
                    return
            self._send_start(t, now)
        elif t.stage == "items":                                  # upload: the vehicle leads
            if now - t.heard > SILENCE:
                self._end(t, CommandStatus.TIMED_OUT, f"the vehicle stopped asking for items "
                          f"({t.top + 1} of {t.count} sent)")
                return
            final_wait = max(FINAL_ACK_WAIT * self._retry(t), FINAL_ACK_MIN)
            if t.top == t.count - 1 and not t.acked and now - t.last_sent_at > final_wait:
                t.detail = "the vehicle's MISSION_ACK was lost: reading back"
                self._read_back(t, now)
                return
            if t.asked >= 0:                                      # the next request is late: the item again
                self._send_item(t, t.asked, now, again=True)
                t.probing = t.asked

    def _send_start(self, t: _Transfer, now: float) -> None:
        system, component = self._target()
        kind = int(t.kind)
        args = dict(mission_type=kind) if self._mavlink2() else {}
        c = self._codec
        if t.direction is TransferDirection.UPLOAD:
            msg = c.mission_count_encode(system, component, t.count, **args)
        elif t.direction is TransferDirection.DOWNLOAD:
            msg = c.mission_request_list_encode(system, component, **args)
        else:
            msg = c.mission_clear_all_encode(system, component, **args)
        if t.first_asked is None:
            t.first_asked = now
        t.attempts += 1
        t.sent_at = now
        t.next_send = now + min(MAX_RETRY, self._retry(t) * 2 ** min(t.attempts - 1, 8))   # backing off unanswered
        self._out.append(msg)

    def _ask_item(self, t: _Transfer, seq: int, now: float) -> None:
        system, component = self._target()
        args = dict(mission_type=int(t.kind)) if self._mavlink2() else {}
        c = self._codec
        msg = (c.mission_request_int_encode(system, component, seq, **args) if self.integer else
               c.mission_request_encode(system, component, seq, **args))
        entry = t.waiting.setdefault(seq, [now, 0, now])       # last asked, times asked, first asked
        entry[0], entry[1] = now, entry[1] + 1
        self._out.append(msg)

    def _ask_more(self, t: _Transfer, now: float) -> None:
        """Keep WINDOW requests in flight, lowest missing items first."""
        for seq in range(t.count or 0):
            if len(t.waiting) >= WINDOW:
                return
            if seq not in t.received and seq not in t.waiting:
                self._ask_item(t, seq, now)

    def _send_item(self, t: _Transfer, seq: int, now: float, again: bool = False) -> None:
        item = t.wire[seq]
        self._out.append(to_wire(self._codec, item, seq, t.kind, self._target(), self.integer, self._mavlink2()))
        t.asked = max(t.asked, seq)
        t.sends[seq] = t.sends.get(seq, 0) + 1
        if seq > t.top:
            t.top = seq
            self.changed = True
        if seq == t.count - 1 and (not again or t.last_sent_at == 0.0):
            t.last_sent_at = now
        t.sent_at = now
        t.next_send = now + self._retry(t)

    # -- the reader ----------------------------------------------------------------------------------------
    def on_message(self, m, now: float) -> list:
        """A MISSION_* message from the autopilot; returns what to send at once."""
        if getattr(m, "target_system", 0) not in (0, self._source[0]) or \
                getattr(m, "target_component", 0) not in (0, self._source[1]):
            return []                                             # another ground station's transfer
        if m.get_type() == "RALLY_POINT":
            t = self._running.get(PlanKind.RALLY)
            if t is not None and t.legacy:
                self._legacy_point(t, m, now)
            out, self._out = self._out, []
            return out
        kind = PlanKind(getattr(m, "mission_type", 0)) if getattr(m, "mission_type", 0) in (0, 1, 2) else None
        t = self._running.get(kind) if kind is not None else None
        if t is None:
            return []
        mtype = m.get_type()
        if mtype in ("MISSION_REQUEST", "MISSION_REQUEST_INT"):
            self._on_request(t, m.seq, now)
        elif mtype == "MISSION_COUNT":
            self._on_count(t, m.count, now)
        elif mtype in ("MISSION_ITEM", "MISSION_ITEM_INT"):
            self._on_item(t, m, now)
        elif mtype == "MISSION_ACK":
            self._on_ack(t, m.type, now)
        out, self._out = self._out, []
        return out

    def _measure(self, t: _Transfer, now: float, once: bool) -> None:
        """The vehicle answered what went out at ``t.sent_at``; ``once``: it went out once, so the answer is its own
        (Karn's rule) and times the link."""
        if once:
            self._roundtrip.sample(now - t.sent_at)
        t.heard = now

    def _on_request(self, t: _Transfer, seq: int, now: float) -> None:
        if self._resumable(t):
            t = self._resume_upload(t, now)       # a read-back begun on a lost final ACK, but the vehicle asks
        if t.direction is not TransferDirection.UPLOAD or t.upload is not None or t.stage in ("readback", "refused"):
            return
        if not 0 <= seq < (t.count or 0):
            return
        if t.stage == "start":
            self._measure(t, now, t.attempts == 1)
        elif seq == t.asked + 1:
            self._measure(t, now, t.sends.get(t.asked) == 1)
        t.heard = now
        t.stage = "items"
        t.attempts = 0
        t.probing = None
        t.asked = seq                             # what the vehicle asks for is what it holds up to
        self.changed = True
        self._send_item(t, seq, now)

    @staticmethod
    def _resumable(t: _Transfer) -> bool:
        """A read-back begun while its upload was not acknowledged, still waiting for the count."""
        return (t.upload is not None and t.upload.direction is TransferDirection.UPLOAD and not t.upload.acked
                and t.stage == "start" and t.verifying is None)

    def _resume_upload(self, check: _Transfer, now: float) -> _Transfer:
        """Back from a read-back to its upload: the vehicle is still receiving (our last item was lost)."""
        upload = check.upload
        self._running[upload.kind] = upload
        upload.stage, upload.detail, upload.heard = "items", "", now
        self.changed = True
        return upload

    def _on_count(self, t: _Transfer, count: int, now: float) -> None:
        if t.direction is not TransferDirection.DOWNLOAD or t.stage != "start":
            return
        self._measure(t, now, t.attempts == 1)
        t.count = count
        self.changed = True
        if count == 0:
            self._downloaded(t, now)
            return
        t.stage, t.attempts = "items", 0
        self._ask_more(t, now)

    def _on_item(self, t: _Transfer, m, now: float) -> None:
        if t.direction is not TransferDirection.DOWNLOAD or t.stage != "items" or m.seq in t.received:
            return
        if not 0 <= m.seq < t.count:
            return
        entry = t.waiting.pop(m.seq, None)
        if entry is not None and entry[1] == 1:               # asked once: a clean round-trip sample
            t.sent_at = entry[0]
            self._measure(t, now, True)
        t.received[m.seq] = from_wire(m)
        self.changed = True
        if len(t.received) == t.count:
            self._downloaded(t, now)
            return
        self._ask_more(t, now)

    def _on_ack(self, t: _Transfer, result: int, now: float) -> None:
        if self._resumable(t) and result == mavlink.MAV_MISSION_DENIED:
            # a read-back begun on a lost final ACK, DENIED: the vehicle is still receiving (an item of ours was
            # lost, not its ACK): back to the upload, the last item asked again
            upload = self._resume_upload(t, now)
            self._send_item(upload, upload.asked, now)
            upload.last_sent_at = now
            return
        if result == mavlink.MAV_MISSION_ERROR:
            self._on_error(t, result, now)
            return
        if t.direction is TransferDirection.DOWNLOAD:
            if t.verifying is not None:
                return                    # the vehicle busy with another upload: the verification asks again
            if t.stage == "start" and result != mavlink.MAV_MISSION_ACCEPTED:
                self._end(t, CommandStatus.REFUSED, result_meaning(result))
            elif t.stage == "items" and result not in (mavlink.MAV_MISSION_ACCEPTED,
                                                       mavlink.MAV_MISSION_INVALID_SEQUENCE):
                self._end(t, CommandStatus.REFUSED, result_meaning(result))
            return
        if t.direction is TransferDirection.CLEAR:
            if t.stage != "start" or t.attempts == 0:
                return
            if result == mavlink.MAV_MISSION_ACCEPTED:
                self._end(t, CommandStatus.ACCEPTED, "cleared (MISSION_ACK accepted)", Plan(t.kind))
            else:
                self._end(t, CommandStatus.REFUSED, result_meaning(result))
            return
        # upload
        if result == mavlink.MAV_MISSION_INVALID_SEQUENCE:
            # the item we sent again unasked had arrived: its next request was lost. The vehicle goes on (it
            # asks again in 1 s); it holds the item, so it wants the next one: send it now. Only for that probe:
            # an INVALID_SEQUENCE for anything else (a stale request answered) proves nothing
            t.heard = now
            if t.stage == "items" and t.probing == t.asked and 0 <= t.asked < (t.count or 0) - 1:
                t.probing = None
                self._send_item(t, t.asked + 1, now)
            return
        if result == mavlink.MAV_MISSION_ACCEPTED:
            if (t.count and t.top < t.count - 1) or t.stage == "readback" or (not t.count and t.attempts == 0):
                return                    # not for this upload: items are still to come, or nothing asked yet
            t.acked, t.said = True, ""
            self._read_back(t, now)
            return
        if t.stage in ("start", "items") and result == mavlink.MAV_MISSION_NO_SPACE:
            t.stage, t.said, t.next_send = "refused", result_meaning(result), now + REASON_WAIT
        elif t.stage in ("start", "items"):
            self._end(t, CommandStatus.REFUSED, result_meaning(result))

    def on_text(self, text: str) -> None:
        """A STATUSTEXT (lock held): the reason of a refusal waiting for it ("Only 0 items are supported")."""
        if "items are supported" not in text:
            return
        for t in list(self._running.values()):
            if t.stage == "refused":
                self._end(t, CommandStatus.REFUSED, f"{t.said}; the vehicle says: {text}")

    def _on_error(self, t: _Transfer, result: int, now: float) -> None:
        """MISSION_ACK ERROR: a late answer to a repeated item as often as a failure (see the module's text)."""
        t.said = result_meaning(result)
        if t.direction is TransferDirection.DOWNLOAD:
            return                                # the requests go on; a timeout tells what the vehicle said
        started = t.attempts > 0 if t.direction is TransferDirection.CLEAR else t.asked >= 0
        if started:                               # (an upload not asked for anything yet: a late answer to an
            t.detail = f"the vehicle answered {t.said}: reading back what it holds"   # earlier transfer)
            self._read_back(t, now)

    # -- endings -----------------------------------------------------------------------------------------
    def _read_back(self, upload: _Transfer, now: float) -> None:
        upload.stage = "readback"
        check = _Transfer(upload.kind, TransferDirection.DOWNLOAD, upload.future, upload=upload, heard=now,
                          detail=upload.detail)
        self._running[upload.kind] = check
        self.changed = True
        self._send_start(check, now)

    def _downloaded(self, t: _Transfer, now: float) -> None:
        system, component = self._target()
        args = dict(mission_type=int(t.kind)) if self._mavlink2() else {}
        self._out.append(self._codec.mission_ack_encode(system, component, mavlink.MAV_MISSION_ACCEPTED, **args))
        items = [t.received[i] for i in range(t.count or 0)]
        if t.kind is PlanKind.MISSION and items:
            items = items[1:]                                     # the home slot
        plan = Plan(t.kind, tuple(items))
        if t.upload is None:
            self._end(t, CommandStatus.ACCEPTED, f"{len(plan)} items", plan)
        else:
            self._checked(t, plan)

    def _end(self, t: _Transfer, status: CommandStatus, reason: str, plan: Plan | None = None) -> None:
        if self._running.get(t.kind) is t:
            del self._running[t.kind]
        self.changed = True
        shown = t.upload or t
        name = f"verify {t.kind.label}" if t.verifying is not None else f"{shown.direction.value} {shown.kind.label}"
        result = self._record(name, status, reason)
        if shown.direction is TransferDirection.CLEAR:
            self._settle(t.future, result)
        else:
            self._settle(t.future, TransferOutcome(result, plan))
        self.ended.append((shown.kind, shown.direction, status, plan))
