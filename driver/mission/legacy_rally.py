"""Rally points on firmware without the mission protocol's mission_type: ArduCopter 3.3, as on the 3DR Solo.

There (3drobotics/ardupilot-solo, ArduCopter/GCS_Mavlink.pde) rally points travel as RALLY_POINT messages, which
the vehicle stores without a word (a bad one gets only "bad rally point message ID/count"), counted by the
RALLY_TOTAL parameter, and are read one by one with RALLY_FETCH_POINT. So an upload here: RALLY_TOTAL set and
confirmed by its PARAM_VALUE echo, every point sent, then every point fetched back and compared; a point that
does not come back as sent is sent again (its message was lost), up to ITEM_ATTEMPTS times. A download: the
RALLY_TOTAL read, then the points fetched. Mixed into :class:`~driver.mission.transfer.PlanTransfers`.
"""
from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core.results import CommandStatus
from .plan import MissionItem, Plan, PlanKind, TransferDirection

__all__ = ["LegacyRally"]

TOTAL = "RALLY_TOTAL"


def _point(m) -> MissionItem:
    return MissionItem(mavlink.MAV_CMD_NAV_RALLY_POINT, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT, lat=m.lat / 1e7,
                       lon=m.lng / 1e7, alt=float(m.alt), autocontinue=False)


class LegacyRally:
    """The RALLY_POINT path; the transfer machinery (``_Transfer``, ``_end``, ``_retry``) is PlanTransfers'."""

    def legacy_rally(self, kind: PlanKind) -> bool:
        return kind is PlanKind.RALLY and not self._firmware.mission_types

    def _legacy_start(self, t, now: float) -> None:
        system, component = self._target()
        if t.direction is not TransferDirection.DOWNLOAD:                  # upload, or clear (0 points)
            msg = self._codec.param_set_encode(system, component, TOTAL.encode(), float(t.count or 0),
                                               mavlink.MAV_PARAM_TYPE_INT8)
        else:
            msg = self._codec.param_request_read_encode(system, component, TOTAL.encode(), -1)
        t.attempts += 1
        t.sent_at = now
        t.next_send = now + self._retry(t)
        self._out.append(msg)

    def _legacy_service(self, t, now: float) -> None:
        if t.stage == "start":
            if now < t.next_send:
                return
            if t.attempts >= 8:
                self._end(t, CommandStatus.TIMED_OUT, f"no PARAM_VALUE {TOTAL} after {t.attempts} attempts")
                return
            self._legacy_start(t, now)
            return
        for seq, entry in list(t.waiting.items()):                  # fetching: re-ask late points
            if now - entry[0] < self._retry(t):
                continue
            if entry[1] >= 12:
                self._end(t, CommandStatus.TIMED_OUT, f"rally point {seq} never came back ({entry[1]} requests)")
                return
            self._fetch(t, seq, now)

    def on_param(self, name: str, value: float, now: float) -> list:
        """A PARAM_VALUE: RALLY_TOTAL set (upload) or read (download)."""
        t = self._running.get(PlanKind.RALLY)
        if name != TOTAL or t is None or not getattr(t, "legacy", False) or t.stage != "start":
            return []
        if t.direction is TransferDirection.CLEAR:
            if int(round(value)) == 0:
                self._end(t, CommandStatus.ACCEPTED, f"cleared ({TOTAL} 0 confirmed)", Plan(PlanKind.RALLY))
            return []
        if t.direction is TransferDirection.UPLOAD:
            if int(round(value)) != t.count:
                return []
            for seq, item in enumerate(t.wire):
                self._send_point(t, seq, item)
        else:
            t.count = int(round(value))
        t.stage = "items"
        self.changed = True
        if not t.count:
            self._legacy_done(t, now)
        else:
            self._fetch_more(t, now)
        out, self._out = self._out, []
        return out

    def _send_point(self, t, seq: int, item: MissionItem) -> None:
        system, component = self._target()
        self._out.append(self._codec.rally_point_encode(
            system, component, seq, t.count, int(round(item.lat * 1e7)), int(round(item.lon * 1e7)),
            int(round(item.alt)), 0, 0, 0))

    def _fetch(self, t, seq: int, now: float) -> None:
        system, component = self._target()
        entry = t.waiting.setdefault(seq, [now, 0])
        entry[0], entry[1] = now, entry[1] + 1
        self._out.append(self._codec.rally_fetch_point_encode(system, component, seq))

    def _fetch_more(self, t, now: float) -> None:
        for seq in range(t.count or 0):
            if len(t.waiting) >= 4:
                return
            if seq not in t.received and seq not in t.waiting:
                self._fetch(t, seq, now)

    def _legacy_point(self, t, m, now: float) -> None:
        if t.stage != "items" or not 0 <= m.idx < (t.count or 0) or m.idx in t.received:
            return
        t.waiting.pop(m.idx, None)
        got = _point(m)
        if t.direction is TransferDirection.UPLOAD:
            sent = t.wire[m.idx]
            if (m.lat, m.lng, m.alt) != (round(sent.lat * 1e7), round(sent.lon * 1e7), round(sent.alt)):
                t.resent = getattr(t, "resent", 0) + 1
                if t.resent > 12 * t.count:
                    self._end(t, CommandStatus.REFUSED, f"rally point {m.idx} does not stay as sent")
                    return
                self._send_point(t, m.idx, sent)                     # its RALLY_POINT was lost: again
                self._fetch(t, m.idx, now)
                return
        t.received[m.idx] = got
        self.changed = True
        if len(t.received) == t.count:
            self._legacy_done(t, now)
        else:
            self._fetch_more(t, now)

    def _legacy_done(self, t, now: float) -> None:
        plan = Plan(PlanKind.RALLY, tuple(t.received[i] for i in range(t.count or 0)))
        if t.direction is TransferDirection.UPLOAD:
            self._end(t, CommandStatus.ACCEPTED, f"{len(plan)} items: RALLY_TOTAL confirmed, every point fetched "
                      "back as sent (RALLY_POINT, ArduCopter 3.3)", plan)
        else:
            self._end(t, CommandStatus.ACCEPTED, f"{len(plan)} items (RALLY_FETCH_POINT)", plan)
