"""The mission protocol as ArduCopter serves it: missions, fences and rally points uploaded, read and cleared.

Mixed into :class:`~driver.sim.autopilot.Autopilot`. Follows ArduPilot's MissionItemProtocol
(libraries/GCS_MAVLink/MissionItemProtocol.cpp) and tests/data/recordings/arducopter-4.6-sitl-mission:

* an upload asks item by item with MISSION_REQUEST (not _INT), re-asks after 1 s without the item, and gives up
  8 s after the last item with MISSION_ACK OPERATION_CANCELLED and "Mission upload timeout";
* the last item is answered MISSION_ACK ACCEPTED once (transfer_is_complete): the upload is then over, and a lost
  ACK is never sent again;
* an item with the wrong seq gets INVALID_SEQUENCE without ending the upload; a download (MISSION_REQUEST_LIST,
  MISSION_REQUEST_INT) or another ground station's upload asked meanwhile gets DENIED, while the float
  MISSION_REQUEST is answered all the same (handle_mission_request has no such check) with, once an upload,
  "got MISSION_REQUEST; use MISSION_REQUEST_INT!"; a MISSION_CLEAR_ALL from the uploading ground station ends
  its upload and clears (cancel_upload), from another one gets DENIED and ERROR; an item beyond the end of the
  plan (cleared meanwhile) gets ERROR;
* an item when no upload of its plan runs (the last item sent again after the upload completed, a duplicate)
  gets MISSION_ACK ERROR (GCS_Common.cpp, GCS_MAVLINK::handle_mission_item: ``if (!prot->receiving)``);
* before "ArduPilot Ready" the storage is not there: NO_SPACE and "Only 0 items are supported";
* mission items are written as they arrive (a failed upload leaves what arrived), fences only once complete;
* item 0 of the mission is home (what is uploaded there is replaced); read back, frames and autocontinue are
  ArduPilot's own (GLOBAL_RELATIVE_ALT, DO_ commands frame 0, fence vertices frame 0 autocontinue 0).

The Solo's ArduCopter 3.3 (3drobotics/ardupilot-solo, ArduCopter/GCS_Mavlink.pde and GCS_Common.cpp) knows only
the float MISSION_ITEM / MISSION_REQUEST, no mission_type (MAVLink 1), gives an upload up silently 6 s after its
last item (wp_recv_time + waypoint_receive_timeout), ends it at once on a MISSION_REQUEST_LIST (answered with the
count: ``waypoint_receiving = false``), and has no polygon fence (AC_Fence: ceiling and circle); its rally points
travel as RALLY_POINT with RALLY_TOTAL.
"""
from __future__ import annotations

import logging
import math
import struct
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..mission.limits import fence_shapes

__all__ = ["Missions", "StoredItem", "is_nav"]

log = logging.getLogger("driver.sim.autopilot")

MISSION, FENCE, RALLY = (mavlink.MAV_MISSION_TYPE_MISSION, mavlink.MAV_MISSION_TYPE_FENCE,
                         mavlink.MAV_MISSION_TYPE_RALLY)
REQUEST_AGAIN = 1.0          # s without the asked item before it is asked again (1000 ms + stream slowdown)
UPLOAD_TIMEOUT = 8.0         # s after the last item received before the upload is given up (upload_timeout_ms)
UPLOAD_TIMEOUT_33 = 6.0      # ArduCopter 3.3: 1 s + waypoint_receive_timeout (5000 ms)
MAX_ITEMS = {MISSION: 700, FENCE: 84, RALLY: 10}
_LOCATED_DO = {mavlink.MAV_CMD_DO_SET_HOME, mavlink.MAV_CMD_DO_LAND_START, mavlink.MAV_CMD_DO_SET_ROI,
               mavlink.MAV_CMD_DO_SET_ROI_LOCATION}
_NO_PLACE = {mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH, mavlink.MAV_CMD_NAV_GUIDED_ENABLE, mavlink.MAV_CMD_NAV_DELAY}
_LOITERS = {mavlink.MAV_CMD_NAV_LOITER_UNLIM, mavlink.MAV_CMD_NAV_LOITER_TURNS, mavlink.MAV_CMD_NAV_LOITER_TIME}
_RELATIVE = {mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT}
_TERRAIN = {mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT, mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT}


def is_nav(command: int) -> bool:
    """AP_Mission::is_nav_cmd: MAV_CMDs up to 95 (MAV_CMD_NAV_LAST) are navigation items."""
    return command <= mavlink.MAV_CMD_NAV_LAST


@dataclass(frozen=True)
class StoredItem:
    """One item as the vehicle keeps it (AP_Mission::Mission_Command, AC_PolyFence_loader, AP_Rally)."""
    command: int
    frame: int
    params: tuple[float, float, float, float]
    x: int                     # degE7
    y: int
    z: float
    autocontinue: int = 1

    @property
    def param1(self) -> float:
        return self.params[0]

    @property
    def lat(self) -> float:
        return self.x / 1e7

    @property
    def lon(self) -> float:
        return self.y / 1e7


def _f32(value: float) -> float:
    """As a float32 field carries it."""
    return struct.unpack("<f", struct.pack("<f", value))[0]


def stored_as(kind: int, command: int, frame: int, params, x: int, y: int, z: float) -> StoredItem:
    """What the vehicle keeps of an uploaded item: its frame and autocontinue are ArduPilot's on read-back."""
    params = tuple(_f32(p) for p in params)
    if kind == FENCE:
        return StoredItem(command, mavlink.MAV_FRAME_GLOBAL, params, x, y, 0.0, 0)
    if kind == RALLY:
        return StoredItem(command, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT, params, x, y, _f32(z), 0)
    if command in _LOITERS:                 # the direction is kept as a flag: read back as 1 or -1 (recording)
        params = (params[0], params[1], -1.0 if params[2] < 0 else 1.0, params[3])
    elif command == mavlink.MAV_CMD_NAV_LAND:   # param4 (yaw direction) too: AP_Mission.cpp keeps loiter_ccw from
        params = params[:3] + (-1.0 if params[3] < 0 else 1.0,)   # it, reads back -1 or 1 (NaN: 1); 4.6.3 SITL
    if (is_nav(command) and command not in _NO_PLACE) or command in _LOCATED_DO:
        out = (mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT if frame in _RELATIVE else
               mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT if frame in _TERRAIN else mavlink.MAV_FRAME_GLOBAL)
        return StoredItem(command, out, params, x, y, _f32(z), 1)
    return StoredItem(command, mavlink.MAV_FRAME_GLOBAL, params, 0, 0, 0.0, 1)


@dataclass
class _Upload:
    kind: int
    count: int
    sysid: int
    compid: int
    link: object
    next_seq: int = 0
    last_receive: float = 0.0
    last_request: float = 0.0
    items: list | None = None      # fences: kept aside until complete


class Missions:
    """The vehicle's three plans and their transfers; the rest of the state belongs to the Autopilot."""

    def _missions_init(self) -> None:
        self.plans: dict[int, list[StoredItem]] = {MISSION: [], FENCE: [], RALLY: []}
        self.uploads: dict[int, _Upload] = {}
        self.warned_float_item = False
        self.warned_float_request = False   # mission_request_warning_sent: again after each upload's start
        self._fence_shapes = None      # (the fence plan, its FenceShapes): a fence is only ever replaced whole

    # -- what the profile speaks -------------------------------------------------------------------
    @property
    def _mission_types(self) -> bool:
        """MAVLink 2's mission_type (fence and rally through the mission protocol): 4.x only."""
        return self.profile.mavlink2

    def _kind(self, msg) -> int | None:
        kind = getattr(msg, "mission_type", MISSION) if self._mission_types else MISSION
        return kind if kind in self.plans else None

    def _ack(self, msg, result: int, kind: int, link=None) -> None:
        ack = self.factory.mission_ack_encode(msg.get_srcSystem(), msg.get_srcComponent(), result, kind)
        self.emit_to(ack, link if link is not None else self.sender)

    def mission_home_item(self) -> StoredItem:
        """Item 0: home (0, 0 before it is set), in frame GLOBAL at its altitude above sea level."""
        if not self.home_set:
            return StoredItem(mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_FRAME_GLOBAL, (0.0,) * 4, 0, 0, 0.0, 1)
        return StoredItem(mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_FRAME_GLOBAL, (0.0,) * 4,
                          int(round(self.home_lat * 1e7)), int(round(self.home_lon * 1e7)),
                          _f32(self.home_alt), 1)

    def plan_items(self, kind: int) -> list[StoredItem]:
        """The items as read back (the mission's item 0 is home)."""
        items = list(self.plans[kind])
        if kind == MISSION and items:
            items[0] = self.mission_home_item()
        return items

    # -- upload -------------------------------------------------------------------------------------
    def _on_mission_count(self, msg) -> None:
        kind = self._kind(msg)
        if kind is None:
            return
        upload = self.uploads.get(kind)
        if upload is not None and (msg.get_srcSystem(), msg.get_srcComponent()) != (upload.sysid, upload.compid):
            self._ack(msg, mavlink.MAV_MISSION_DENIED, kind)
            return
        limit = MAX_ITEMS[kind] if self.initialised else 0
        if msg.count > limit:
            self._ack(msg, mavlink.MAV_MISSION_NO_SPACE, kind)
            self._text(mavlink.MAV_SEVERITY_WARNING, f"Only {limit} items are supported")
            return
        self.uploads.pop(kind, None)
        if kind != FENCE:
            del self.plans[kind][msg.count:]           # truncate(): what is beyond the new count goes now
        upload = _Upload(kind, msg.count, msg.get_srcSystem(), msg.get_srcComponent(), self.sender,
                         last_receive=self.t, last_request=self.t, items=[] if kind == FENCE else None)
        if msg.count == 0:
            self._upload_complete(upload, msg)
            return
        self.warned_float_request = False              # init_send_requests
        self.uploads[kind] = upload
        self._request_item(upload)

    def _request_item(self, upload: _Upload) -> None:
        upload.last_request = self.t
        self.emit_to(self.factory.mission_request_encode(upload.sysid, upload.compid, upload.next_seq,
                                                         upload.kind), upload.link)

    def _on_mission_item_int(self, msg) -> None:
        if not self.profile.mavlink2:
            return                                  # 3.3 has no MISSION_ITEM_INT (message 73 is not handled)
        self._mission_item(msg, msg.x, msg.y)

    def _on_mission_item(self, msg) -> None:
        self._float_item(msg)
        if self.profile.mavlink2 and not self.warned_float_item:
            self.warned_float_item = True           # 4.x converts it and asks, once, for the _INT form (its text
            self._text(mavlink.MAV_SEVERITY_WARNING,   # is queued: it follows the next request, as recorded)
                       "got MISSION_ITEM; GCS should send MISSION_ITEM_INT")

    def _float_item(self, msg) -> None:
        if not (math.isfinite(msg.x) and math.isfinite(msg.y)):
            kind = self._kind(msg)
            if kind in self.uploads:
                self._ack(msg, mavlink.MAV_MISSION_INVALID, kind)
            return
        # AP_Mission::convert_MISSION_ITEM_to_MISSION_ITEM_INT: x * 1.0e7f in float32 (recording: y 1491655552)
        self._mission_item(msg, int(_f32(_f32(msg.x) * _f32(1e7))), int(_f32(_f32(msg.y) * _f32(1e7))))

    def _mission_item(self, msg, x: int, y: int) -> None:
        kind = self._kind(msg)
        upload = self.uploads.get(kind) if kind is not None else None
        if upload is None:
            # GCS_MAVLINK::handle_mission_item (GCS_Common.cpp): an item while that plan is not being received -
            # a repeat of the last item after the upload completed, a duplicate, a late one - gets MISSION_ACK
            # ERROR for its mission_type (3.3: the same, "if (!waypoint_receiving)")
            if kind is not None:
                self._ack(msg, mavlink.MAV_MISSION_ERROR, kind)
            return
        if msg.seq != upload.next_seq:
            self._ack(msg, mavlink.MAV_MISSION_INVALID_SEQUENCE, kind, upload.link)
            return
        if (msg.get_srcSystem(), msg.get_srcComponent()) != (upload.sysid, upload.compid):
            self._ack(msg, mavlink.MAV_MISSION_DENIED, kind, upload.link)
            return
        if not math.isfinite(msg.z) or not all(math.isfinite(p) or math.isnan(p) for p in
                                               (msg.param1, msg.param2, msg.param3, msg.param4)):
            self._ack(msg, mavlink.MAV_MISSION_INVALID, kind, upload.link)
            self.uploads.pop(kind, None)
            return
        item = stored_as(kind, msg.command, msg.frame, (msg.param1, msg.param2, msg.param3, msg.param4),
                         x, y, msg.z)
        if upload.items is not None:
            upload.items.append(item)
        else:
            plan = self.plans[kind]
            if msg.seq > len(plan):          # beyond the end (cleared meanwhile): ERROR, and 4.x stops receiving
                self._ack(msg, mavlink.MAV_MISSION_ERROR, kind, upload.link)
                if self.profile.mavlink2:
                    self.uploads.pop(kind, None)
                return
            if msg.seq < len(plan):
                plan[msg.seq] = item
            else:
                plan.append(item)
        upload.last_receive = self.t
        upload.next_seq += 1
        if upload.next_seq >= upload.count:
            self.uploads.pop(kind, None)
            self._upload_complete(upload, msg)
        else:
            self._request_item(upload)

    def _upload_complete(self, upload: _Upload, msg) -> None:
        kind = upload.kind
        if upload.items is not None:
            self.plans[kind] = upload.items
        self._ack(msg, mavlink.MAV_MISSION_ACCEPTED, kind, upload.link)
        if kind == RALLY:
            self.params["RALLY_TOTAL"] = len(self.plans[RALLY])      # AP_Rally keeps its count there
        if kind == MISSION:
            self._text(mavlink.MAV_SEVERITY_INFO,
                       "Flight plan received" if self.profile.mavlink2 else "flight plan received")
            self._mission_changed()
        elif kind == FENCE:
            self._text(mavlink.MAV_SEVERITY_DEBUG, "Fence Indexed OK")

    def _missions_step(self) -> None:
        """MissionItemProtocol::update(): re-ask the item every second, give up 8 s after the last one (3.3: 6 s)."""
        timeout = UPLOAD_TIMEOUT if self.profile.mavlink2 else UPLOAD_TIMEOUT_33
        for kind, upload in list(self.uploads.items()):
            if self.t - upload.last_receive > timeout:
                self.uploads.pop(kind, None)
                if self.profile.mavlink2:           # 3.3 stopped receiving without a word
                    self.emit_to(self.factory.mission_ack_encode(
                        upload.sysid, upload.compid, mavlink.MAV_MISSION_OPERATION_CANCELLED, kind), upload.link)
                    if kind == MISSION:
                        self._text(mavlink.MAV_SEVERITY_WARNING, "Mission upload timeout")
                if kind == MISSION:
                    self._mission_changed()
            elif self.t - upload.last_request > REQUEST_AGAIN:
                self._request_item(upload)

    # -- download ---------------------------------------------------------------------------------
    def _readable(self, msg) -> int | None:
        """The plan kind a download message asks for; None (DENIED sent on 4.x) while it is being uploaded."""
        kind = self._kind(msg)
        if kind is not None and kind in self.uploads and self.profile.mavlink2:
            self._ack(msg, mavlink.MAV_MISSION_DENIED, kind)
            return None
        return kind

    def _on_mission_request_list(self, msg) -> None:
        kind = self._readable(msg)
        if kind is None:
            return
        if kind in self.uploads:            # 3.3 (4.x denied it above): the list asked for ends the upload
            self.uploads.pop(kind)
            self._mission_changed()
        self.emit_to(self.factory.mission_count_encode(msg.get_srcSystem(), msg.get_srcComponent(),
                                                       len(self.plans[kind]), kind), self.sender)

    def _on_mission_request_int(self, msg) -> None:
        if not self.profile.mavlink2:
            return                                  # 3.3: no MISSION_REQUEST_INT
        self._send_item(msg, integer=True)

    def _on_mission_request(self, msg) -> None:
        if self._send_item(msg, integer=False) and self.profile.mavlink2 and not self.warned_float_request:
            self.warned_float_request = True
            self._text(mavlink.MAV_SEVERITY_WARNING, "got MISSION_REQUEST; use MISSION_REQUEST_INT!")

    def _send_item(self, msg, integer: bool) -> bool:
        """The item asked for, or MISSION_ACK why not; True when the item went."""
        kind = self._readable(msg) if integer else self._kind(msg)   # the float request: answered even then
        if kind is None:
            return False
        items = self.plan_items(kind)
        if not 0 <= msg.seq < len(items):
            self._ack(msg, mavlink.MAV_MISSION_INVALID_SEQUENCE, kind)
            return False
        item = items[msg.seq]
        sysid, compid = msg.get_srcSystem(), msg.get_srcComponent()
        if integer:
            out = self.factory.mission_item_int_encode(sysid, compid, msg.seq, item.frame, item.command, 0,
                                                       item.autocontinue, *item.params, item.x, item.y, item.z,
                                                       kind)
        else:
            out = self.factory.mission_item_encode(sysid, compid, msg.seq, item.frame, item.command, 0,
                                                   item.autocontinue, *item.params, item.x / 1e7, item.y / 1e7,
                                                   item.z, kind)
        self.emit_to(out, self.sender)
        return True

    # -- clear ------------------------------------------------------------------------------------------
    def _on_mission_clear_all(self, msg) -> None:
        kind = self._kind(msg)
        if kind is None:
            return
        upload = self.uploads.get(kind)
        if upload is not None and self.profile.mavlink2:     # MissionItemProtocol::cancel_upload
            if (msg.get_srcSystem(), msg.get_srcComponent()) != (upload.sysid, upload.compid):
                self._ack(msg, mavlink.MAV_MISSION_DENIED, kind)
                self._ack(msg, mavlink.MAV_MISSION_ERROR, kind)
                return
            del self.uploads[kind]
        if kind == MISSION and self.mission_running():
            self._ack(msg, mavlink.MAV_MISSION_ERROR, kind)   # AP_Mission::clear() refuses a running mission
            return
        self.plans[kind] = []
        if kind == RALLY:
            self.params["RALLY_TOTAL"] = 0
        self._ack(msg, mavlink.MAV_MISSION_ACCEPTED, kind)
        if kind == MISSION:
            self._mission_changed()

    # -- Solo: rally points by RALLY_POINT / RALLY_FETCH_POINT and the RALLY_TOTAL parameter --------------
    def _on_rally_point(self, msg) -> None:
        if self._mission_types:
            return                                  # 4.x: rally points travel as mission_type RALLY
        total = int(self.params.get("RALLY_TOTAL", 0))
        if msg.idx >= total or msg.idx >= MAX_ITEMS[RALLY] or msg.count != total:
            self._text(1, "bad rally point message ID" if msg.idx >= total else "bad rally point message count")
            return
        plan = self.plans[RALLY]
        del plan[total:]
        while len(plan) <= msg.idx:
            plan.append(StoredItem(mavlink.MAV_CMD_NAV_RALLY_POINT, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                                   (0.0,) * 4, 0, 0, 0.0, 0))
        plan[msg.idx] = StoredItem(mavlink.MAV_CMD_NAV_RALLY_POINT, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                                   (0.0,) * 4, msg.lat, msg.lng, float(msg.alt), 0)

    def _on_rally_fetch_point(self, msg) -> None:
        if self._mission_types:
            return
        total = int(self.params.get("RALLY_TOTAL", 0))
        plan = self.plans[RALLY]
        if msg.idx >= total or msg.idx >= len(plan):
            self._text(1, "bad rally point index")
            return
        item = plan[msg.idx]
        self.emit_to(self.factory.rally_point_encode(msg.get_srcSystem(), msg.get_srcComponent(), msg.idx, total,
                                                     item.x, item.y, int(item.z), 0, 0, 0), self.sender)

    # -- geometry the AUTO part and the fence use ------------------------------------------------------
    def polygon_fence_breach(self, north: float, east: float) -> str:
        """AC_PolyFence_loader: outside an inclusion shape or inside an exclusion ("" inside the fence)."""
        fence = self.plans[FENCE]
        if self._fence_shapes is None or self._fence_shapes[0] is not fence:
            self._fence_shapes = (fence, fence_shapes(fence, self.home_lat, self.home_lon))
        return self._fence_shapes[1].outside(north, east)

    def ned_of(self, item: StoredItem) -> tuple[float, float] | None:
        """North/east metres from home of an item's place; None for 0, 0 (ArduPilot: here)."""
        if item.x == 0 and item.y == 0:
            return None
        return self.ned_from(item.lat, item.lon)

    def down_of(self, item: StoredItem) -> float:
        """NED down of an item's altitude (relative frames above home, GLOBAL above sea level)."""
        if item.frame == mavlink.MAV_FRAME_GLOBAL:
            return -(item.z - self.home_alt)
        return -item.z

