"""Plan files: QGroundControl's ``.plan`` (JSON: mission items, geoFence polygons and circles, rallyPoints) and
the ``QGC WPL 110`` text that Mission Planner and MAVProxy save (pymavlink's mavwp.MAVWPLoader reads ours).

A ``.plan`` holds all three plans and the planned home; a WPL file holds one plan, its line 0 the home slot
for a mission. QGroundControl's complex items (survey, corridor scan) are read as the waypoints they carry, and
kept as :class:`ComplexItem` (where their items are, and their own settings) so that a planner can open a survey
as a survey again; written back, they are complex items again, as QGroundControl writes them.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .plan import MissionItem, Plan, PlanKind

__all__ = ["PlanFile", "ComplexItem", "load_plan_file", "save_plan_file", "to_qgc_plan", "from_qgc_plan", "to_wpl",
           "from_wpl", "PlanFileError"]

WPL_HEADER = "QGC WPL 110"
_INCLUSION = mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
_EXCLUSION = mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION
_CIRCLE_IN = mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION
_CIRCLE_OUT = mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION
_FENCE_COMMANDS = {_INCLUSION, _EXCLUSION, _CIRCLE_IN, _CIRCLE_OUT, mavlink.MAV_CMD_NAV_FENCE_RETURN_POINT}


class PlanFileError(ValueError):
    """A file that is not a plan we can read, with the reason."""


@dataclass(frozen=True)
class ComplexItem:
    """A QGroundControl complex item of the mission: its ``count`` items from index ``start`` of the mission's
    items, its ``complexItemType`` ("survey", "CorridorScan") and its own settings (the JSON object as the file
    has it, without the items: polygon, angle, camera ...)."""
    start: int
    count: int
    kind: str
    settings: dict


@dataclass(frozen=True)
class PlanFile:
    plans: tuple[Plan, ...] = ()
    home: tuple[float, float, float] | None = None   # lat, lon, alt above sea level
    complex_items: tuple[ComplexItem, ...] = ()       # a .plan's surveys and corridor scans, in order

    def plan(self, kind: PlanKind) -> Plan | None:
        return next((p for p in self.plans if p.kind is kind), None)


# -- QGroundControl .plan ---------------------------------------------------------------------------------
def _param(value) -> float:
    return math.nan if value is None else float(value)


def _json_param(value: float):
    return None if math.isnan(value) else value


def _simple_json(number: int, item: MissionItem) -> dict:
    return {"type": "SimpleItem", "autoContinue": item.autocontinue, "command": item.command,
            "doJumpId": number, "frame": item.frame,
            "params": [_json_param(v) for v in (*item.params, item.lat, item.lon, item.alt)]}


def to_qgc_plan(plans, home=None, complex_items=()) -> dict:
    """``complex_items``: where the mission's items come from a survey or a corridor scan (written as
    QGroundControl's ComplexItem, its items in its TransectStyleComplexItem)."""
    by_kind = {p.kind: p for p in plans}
    mission = by_kind.get(PlanKind.MISSION, Plan(PlanKind.MISSION))
    groups = {c.start: c for c in complex_items}
    items, i = [], 0
    while i < len(mission.items):
        group = groups.get(i)
        if group is None or group.count < 1 or i + group.count > len(mission.items):
            items.append(_simple_json(i + 1, mission.items[i]))
            i += 1
            continue
        inner = [_simple_json(i + n + 1, item) for n, item in enumerate(mission.items[i:i + group.count])]
        entry = {**group.settings, "type": "ComplexItem", "complexItemType": group.kind}
        if "TransectStyleComplexItem" in group.settings:          # survey, corridor scan
            entry["TransectStyleComplexItem"] = {**group.settings["TransectStyleComplexItem"], "Items": inner}
        else:                                                     # the items at the top (a structure scan)
            entry["Items"] = inner
        items.append(entry)
        i += group.count
    polygons, circles = [], []
    fence = by_kind.get(PlanKind.FENCE, Plan(PlanKind.FENCE)).items
    i = 0
    while i < len(fence):
        item = fence[i]
        if item.command in (_INCLUSION, _EXCLUSION):
            count = max(int(item.param1), 1)
            polygons.append({"inclusion": item.command == _INCLUSION, "version": 1,
                             "polygon": [[v.lat, v.lon] for v in fence[i:i + count]]})
            i += count
            continue
        if item.command in (_CIRCLE_IN, _CIRCLE_OUT):
            circles.append({"inclusion": item.command == _CIRCLE_IN, "version": 1,
                            "circle": {"center": [item.lat, item.lon], "radius": item.param1}})
        i += 1
    rally = by_kind.get(PlanKind.RALLY, Plan(PlanKind.RALLY)).items
    return {
        "fileType": "Plan", "version": 1, "groundStation": "UavViewerPy",
        "mission": {"version": 2, "firmwareType": mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                    "vehicleType": mavlink.MAV_TYPE_QUADROTOR, "cruiseSpeed": 5, "hoverSpeed": 5,
                    "plannedHomePosition": list(home) if home else [0, 0, 0], "items": items},
        "geoFence": {"version": 2, "polygons": polygons, "circles": circles},
        "rallyPoints": {"version": 2, "points": [[p.lat, p.lon, p.alt] for p in rally]},
    }


def _simple(entry: dict) -> MissionItem:
    params = [_param(v) for v in entry["params"]]
    if len(params) != 7:
        raise PlanFileError("a SimpleItem has 7 params")
    return MissionItem(int(entry["command"]), int(entry.get("frame", mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT)),
                       *params[:4], lat=params[4] if not math.isnan(params[4]) else 0.0,
                       lon=params[5] if not math.isnan(params[5]) else 0.0,
                       alt=params[6] if not math.isnan(params[6]) else 0.0,
                       autocontinue=bool(entry.get("autoContinue", True)))


def _mission_items(entries, groups: list[ComplexItem] | None = None) -> list[MissionItem]:
    out = []
    for entry in entries:
        kind = entry.get("type")
        if kind == "SimpleItem":
            out.append(_simple(entry))
        elif kind == "ComplexItem":       # survey / corridor: the items it generated, and what it is
            transect = entry.get("TransectStyleComplexItem", entry)
            inner = transect.get("Items", [])
            if not inner:
                raise PlanFileError(f"a {entry.get('complexItemType', 'complex')} item without its waypoints")
            items = _mission_items(inner)
            if groups is not None:
                settings = {k: v for k, v in entry.items() if k not in ("type", "complexItemType", "Items")}
                if "TransectStyleComplexItem" in settings:
                    settings["TransectStyleComplexItem"] = {k: v for k, v in transect.items() if k != "Items"}
                groups.append(ComplexItem(len(out), len(items), str(entry.get("complexItemType", "")), settings))
            out += items
        else:
            raise PlanFileError(f"unknown mission item type {kind!r}")
    return out


def from_qgc_plan(data: dict) -> PlanFile:
    if data.get("fileType") != "Plan":
        raise PlanFileError("not a QGroundControl plan (fileType is not \"Plan\")")
    try:
        mission = data.get("mission", {})
        groups: list[ComplexItem] = []
        items = _mission_items(mission.get("items", []), groups)
        fence: list[MissionItem] = []
        for poly in data.get("geoFence", {}).get("polygons", []):
            command = _INCLUSION if poly.get("inclusion", True) else _EXCLUSION
            vertices = poly["polygon"]
            fence += [MissionItem(command, mavlink.MAV_FRAME_GLOBAL, param1=len(vertices), lat=float(lat),
                                  lon=float(lon)) for lat, lon in vertices]
        for circle in data.get("geoFence", {}).get("circles", []):
            command = _CIRCLE_IN if circle.get("inclusion", True) else _CIRCLE_OUT
            lat, lon = circle["circle"]["center"]
            fence.append(MissionItem(command, mavlink.MAV_FRAME_GLOBAL, param1=float(circle["circle"]["radius"]),
                                     lat=float(lat), lon=float(lon)))
        rally = [MissionItem(mavlink.MAV_CMD_NAV_RALLY_POINT, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
                             lat=float(p[0]), lon=float(p[1]), alt=float(p[2]))
                 for p in data.get("rallyPoints", {}).get("points", [])]
        home = mission.get("plannedHomePosition")
    except (KeyError, TypeError, ValueError) as exc:
        raise PlanFileError(f"a malformed plan: {exc}") from None
    home = tuple(float(v) for v in home) if home and any(home) else None
    return PlanFile((Plan(PlanKind.MISSION, tuple(items)), Plan(PlanKind.FENCE, tuple(fence)),
                     Plan(PlanKind.RALLY, tuple(rally))), home, tuple(groups))


# -- QGC WPL 110 ------------------------------------------------------------------------------------------
def _wpl_line(index: int, item: MissionItem, current: bool) -> str:
    values = (index, int(current), item.frame, item.command, *item.params, item.lat, item.lon, item.alt, int(item.autocontinue))
    return "\t".join(f"{v:.8f}" if isinstance(v, float) else str(v) for v in values)


def to_wpl(plan: Plan, home=None) -> str:
    lines = [WPL_HEADER]
    items = list(plan.items)
    if plan.kind is PlanKind.MISSION:
        lat, lon, alt = home if home else (0.0, 0.0, 0.0)
        items.insert(0, MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_FRAME_GLOBAL, lat=lat, lon=lon, alt=alt))
    home_line = plan.kind is PlanKind.MISSION             # MAVProxy marks the home slot current
    lines += [_wpl_line(i, item, home_line and i == 0) for i, item in enumerate(items)]
    return "\n".join(lines) + "\n"


def from_wpl(text: str) -> PlanFile:
    lines = [line for line in text.splitlines() if line.strip()]
    if not lines or not lines[0].startswith("QGC WPL 110"):
        raise PlanFileError("not a QGC WPL 110 file (first line)")
    items = []
    for number, line in enumerate(lines[1:], 2):
        fields = line.split()
        if len(fields) != 12:
            raise PlanFileError(f"line {number}: {len(fields)} fields, a WPL line has 12")
        try:
            _, _, frame, command = (int(float(v)) for v in fields[:4])
            p1, p2, p3, p4, lat, lon, alt = (float(v) for v in fields[4:11])
            autocontinue = bool(int(float(fields[11])))
        except ValueError as exc:
            raise PlanFileError(f"line {number}: {exc}") from None
        items.append(MissionItem(command, frame, p1, p2, p3, p4, lat, lon, alt, autocontinue))
    kind = (PlanKind.FENCE if items and items[0].command in _FENCE_COMMANDS else
            PlanKind.RALLY if items and items[0].command == mavlink.MAV_CMD_NAV_RALLY_POINT else PlanKind.MISSION)
    home = None
    if kind is PlanKind.MISSION and items:
        first = items.pop(0)
        home = (first.lat, first.lon, first.alt) if (first.lat or first.lon) else None
    return PlanFile((Plan(kind, tuple(items)),), home)


# -- either, by name -------------------------------------------------------------------------------------
def load_plan_file(path) -> PlanFile:
    """A .plan (JSON) or a WPL file (anything else: .waypoints, .txt, .mission), by its content."""
    text = Path(path).read_text(encoding="utf-8")
    if text.lstrip().startswith("{"):
        try:
            return from_qgc_plan(json.loads(text))
        except json.JSONDecodeError as exc:
            raise PlanFileError(f"not valid JSON: {exc}") from None
    return from_wpl(text)


def save_plan_file(path, plans, home=None, complex_items=()) -> None:
    """``.plan``: every plan given, as QGroundControl writes it (``complex_items``: its surveys); any other name:
    WPL of the one plan given."""
    path = Path(path)
    plans = tuple(plans)
    if path.suffix.lower() == ".plan":
        text = json.dumps(to_qgc_plan(plans, home, complex_items), indent=4)
    else:
        if len(plans) != 1:
            raise PlanFileError("a WPL file holds one plan: save a mission, a fence or rally points")
        text = to_wpl(plans[0], home)
    path.write_text(text, encoding="utf-8")
