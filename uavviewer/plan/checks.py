"""What is wrong with a mission as planned, said on the item (no Qt).

ArduCopter ends a mission at an RTL or a LAND: RTL lands at home, LAND lands where it is, and either disarms on
the ground (mode_auto.cpp: a landed vehicle's mission is complete), so the items after them are never flown.

A waypoint outside the plan's inclusion zones or inside one of its exclusion zones, and a survey leg that crosses
out of them anywhere along it, would breach the fence (the vehicle then acts by FENCE_ACTION, or flies on if the
fence is off): each is marked before the upload, by the same shapes the driver and the simulated vehicle use
(:class:`driver.mission.limits.FenceShapes`, AC_Fence's rules).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.core.frames import offset_ned
from driver.mission.limits import fence_shapes
from driver.mission.plan import MissionItem, PlanKind

from .survey import SurveySpec

__all__ = ["unreachable", "FenceCheck", "outside_fence", "LEG_STEP"]

LEG_STEP = 5.0             # m between the points a leg is checked at
LEG_POINTS_MAX = 400       # ... at most, however long the leg

_ENDS = {mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH: "RTL", mavlink.MAV_CMD_NAV_LAND: "LAND"}


def unreachable(entries, numbers: list[int]) -> dict[int, str]:
    """``{entry index: why}`` for each entry after the mission's first RTL or LAND; ``numbers``: each entry's
    item number on the vehicle (the words name it)."""
    out: dict[int, str] = {}
    end = None
    for i, entry in enumerate(entries):
        if end is not None:
            out[i] = (f"Never flown: item {end[1]} ({end[0]}) lands and ends the mission before it; "
                      "move it before, or delete it")
        elif isinstance(entry, MissionItem) and entry.command in _ENDS:
            end = (_ENDS[entry.command], numbers[i])
    return out


@dataclass(frozen=True)
class FenceCheck:
    """What of the mission breaches the plan's own fence: each entry's why, and what to mark on the map."""
    rows: dict[int, str] = field(default_factory=dict)          # entry index → why
    points: tuple[tuple[float, float], ...] = ()                 # waypoints (lat, lon) outside it
    legs: tuple[tuple[tuple[float, float], tuple[float, float]], ...] = ()   # survey legs leaving it


def outside_fence(doc, numbers: list[int], home: tuple[float, float] | None = None) -> FenceCheck:
    """The mission of ``doc`` (a PlanDocument) against its own fence; ``numbers``: each entry's first item number
    on the vehicle (the words name it)."""
    items = doc.plan(PlanKind.FENCE).items
    if not items:
        return FenceCheck()
    ref = home if home is not None else (items[0].lat, items[0].lon)
    shapes = fence_shapes(items, *ref)
    if shapes.empty:
        return FenceCheck()

    def why(lat: float, lon: float) -> str:
        return shapes.outside(*offset_ned(ref[0], ref[1], lat, lon))
    rows, points, legs = {}, [], []
    for i, entry in enumerate(doc.entries):
        if isinstance(entry, SurveySpec):
            places = [(it.lat, it.lon) for it in doc.survey_of(entry).items if it.has_position]
            bad = [(a, b) for a, b in zip(places, places[1:]) if _leg_outside(a, b, why)]
            if bad:
                legs += bad
                rows[i] = (f"{len(bad)} of its {len(places) - 1} legs leave the fence "
                           f"({_leg_outside(*bad[0], why)}): it would breach it")
        elif isinstance(entry, MissionItem) and entry.has_position and (entry.lat or entry.lon):
            where = why(entry.lat, entry.lon)
            if where:
                points.append((entry.lat, entry.lon))
                rows[i] = f"Item {numbers[i]} is {where} of the plan's fence: the vehicle would breach it there"
    return FenceCheck(rows, tuple(points), tuple(legs))


def _leg_outside(a: tuple[float, float], b: tuple[float, float], why) -> str:
    """Why the straight leg from ``a`` to ``b`` leaves the fence somewhere along it ("" when it never does)."""
    north, east = offset_ned(a[0], a[1], b[0], b[1])
    steps = min(LEG_POINTS_MAX, max(1, math.ceil(math.hypot(north, east) / LEG_STEP)))
    for k in range(steps + 1):
        f = k / steps
        where = why(a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f)
        if where:
            return where
    return ""
