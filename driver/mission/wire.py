"""Plans on the wire: :class:`~driver.mission.plan.MissionItem` to and from MISSION_ITEM(_INT), and the
comparison of a plan read back with the plan sent, in meaning rather than bytes.

ArduPilot changes items on read-back (tests/data/recordings/arducopter-4.6-sitl-mission): frames sent as
GLOBAL_RELATIVE_ALT_INT come back GLOBAL_RELATIVE_ALT, DO_ items and fence vertices come back in frame 0 with
autocontinue 0, a float MISSION_ITEM's latitude is a float32 (about a metre at 150 degrees), item 0 is home.
"""
from __future__ import annotations

import math
import struct

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .plan import MissionItem, Plan, PlanKind

__all__ = ["to_wire", "from_wire", "home_slot", "difference", "result_meaning"]

_INT_FRAME = {mavlink.MAV_FRAME_GLOBAL: mavlink.MAV_FRAME_GLOBAL_INT,
              mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT: mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
              mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT: mavlink.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT}
_PLAIN_FRAME = {v: k for k, v in _INT_FRAME.items()}
# MAV_CMDs ArduPilot keeps a place for (navigation items, and these DO_ items); the rest lose it on read-back
_LOCATED_DO = {mavlink.MAV_CMD_DO_SET_HOME, mavlink.MAV_CMD_DO_LAND_START, mavlink.MAV_CMD_DO_SET_ROI,
               mavlink.MAV_CMD_DO_SET_ROI_LOCATION}
_LOITERS = {mavlink.MAV_CMD_NAV_LOITER_UNLIM, mavlink.MAV_CMD_NAV_LOITER_TURNS, mavlink.MAV_CMD_NAV_LOITER_TIME}
_RESULTS = {
    mavlink.MAV_MISSION_ERROR: "the vehicle reported an error",
    mavlink.MAV_MISSION_UNSUPPORTED_FRAME: "a coordinate frame the vehicle does not support",
    mavlink.MAV_MISSION_UNSUPPORTED: "a command or plan type the vehicle does not support",
    mavlink.MAV_MISSION_NO_SPACE: "more items than the vehicle can store",
    mavlink.MAV_MISSION_INVALID: "an invalid parameter",
    mavlink.MAV_MISSION_INVALID_SEQUENCE: "an item out of sequence",
    mavlink.MAV_MISSION_DENIED: "the vehicle is busy with another transfer",
    mavlink.MAV_MISSION_OPERATION_CANCELLED: "the vehicle cancelled the transfer",
}


def result_meaning(result: int) -> str:
    """"NO_SPACE: more items than the vehicle can store" for a MISSION_ACK type."""
    entry = mavlink.enums["MAV_MISSION_RESULT"].get(result)
    name = entry.name.replace("MAV_MISSION_", "") if entry else f"result {result}"
    meaning = _RESULTS.get(result) or (entry.description.rstrip(".") if entry else "")
    return f"{name}: {meaning}" if meaning else name


def home_slot(home) -> MissionItem:
    """Item 0 of an uploaded mission: the vehicle replaces it by its own home; we send the home we know."""
    if home is None:
        return MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_FRAME_GLOBAL)
    return MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_FRAME_GLOBAL, lat=home.lat, lon=home.lon,
                       alt=home.alt)


def to_wire(codec, item: MissionItem, seq: int, kind: PlanKind, target: tuple[int, int], integer: bool,
            mission_type: bool):
    """MISSION_ITEM_INT (``integer``) or the float MISSION_ITEM for ``item`` as item ``seq``."""
    system, component = target
    args = dict(mission_type=int(kind)) if mission_type else {}
    if integer:
        return codec.mission_item_int_encode(
            system, component, seq, _INT_FRAME.get(item.frame, item.frame), item.command, 0, int(item.autocontinue),
            *item.params, int(round(item.lat * 1e7)), int(round(item.lon * 1e7)), float(item.alt), **args)
    return codec.mission_item_encode(system, component, seq, item.frame, item.command, 0, int(item.autocontinue),
                                     *item.params, float(item.lat), float(item.lon), float(item.alt), **args)


def from_wire(m) -> MissionItem:
    """A MISSION_ITEM or MISSION_ITEM_INT as a plan item (frames in their plain form)."""
    integer = m.get_type() == "MISSION_ITEM_INT"
    lat, lon = (m.x / 1e7, m.y / 1e7) if integer else (float(m.x), float(m.y))
    return MissionItem(m.command, _PLAIN_FRAME.get(m.frame, m.frame), m.param1, m.param2, m.param3, m.param4,
                       lat, lon, float(m.z), bool(m.autocontinue))


def _f32(value: float) -> float:
    return struct.unpack("<f", struct.pack("<f", value))[0] if math.isfinite(value) else value


def _same(a: float, b: float, tolerance: float) -> bool:
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return abs(a - b) <= tolerance


def _located(kind: PlanKind, item: MissionItem) -> bool:
    return kind is not PlanKind.MISSION or item.has_position or item.command in _LOCATED_DO


def item_difference(kind: PlanKind, sent: MissionItem, got: MissionItem, integer: bool) -> str:
    """Why ``got`` does not mean ``sent`` ("" when it does)."""
    if sent.command != got.command:
        return f"command {got.name} instead of {sent.name}"
    for i, (a, b) in enumerate(zip(sent.params, got.params), 1):
        if i == 3 and sent.command in _LOITERS and kind is PlanKind.MISSION:
            a = -1.0 if a < 0 else 1.0                # kept as a direction flag (recording: 0 sent, 1 read back)
        if i == 4 and sent.command == mavlink.MAV_CMD_NAV_LAND and kind is PlanKind.MISSION:
            a = -1.0 if a < 0 else 1.0                # the same for LAND's yaw direction (4.6.3 SITL: 0 sent, 1 back)
        if not _same(_f32(a), b, 1e-6 * max(1.0, abs(a))):
            return f"param{i} {b:g} instead of {a:g}"
    if not _located(kind, sent):
        return ""
    degrees = 1.5e-7 if integer else 2e-5            # MISSION_ITEM's float32 latitude: ~1.5e-5 degrees
    if not (_same(sent.lat, got.lat, degrees) and _same(sent.lon, got.lon, degrees)):
        return f"position {got.lat:.7f}, {got.lon:.7f} instead of {sent.lat:.7f}, {sent.lon:.7f}"
    if kind is PlanKind.FENCE:
        return ""
    if _PLAIN_FRAME.get(sent.frame, sent.frame) != got.frame:
        return f"frame {got.frame} instead of {sent.frame}"
    if not _same(sent.alt, got.alt, 0.01):
        return f"altitude {got.alt:g} instead of {sent.alt:g}"
    return ""


def difference(sent: Plan, got: Plan, integer: bool) -> str:
    """Why the plan read back ``got`` is not the plan sent ("" when it means the same)."""
    if len(sent) != len(got):
        return f"{len(got)} items instead of {len(sent)}"
    first = 1 if sent.kind is PlanKind.MISSION else 0
    for i, (a, b) in enumerate(zip(sent.items, got.items)):
        why = item_difference(sent.kind, a, b, integer)
        if why:
            return f"item {i + first}: {why}"
    return ""
