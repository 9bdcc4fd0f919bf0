"""Every item checked against the driver's flight limits before it is uploaded: distance from home, the
ceiling, and the fence (the vehicle's FENCE_RADIUS / FENCE_ALT_MAX and the polygon fence it holds). Each
refusal names the item (the vehicle's numbering) and the reason.

Before the vehicle has a home (no GPS fix yet) a distance cannot be checked, but a mission may still go up, as
ArduPilot, QGroundControl and MAVProxy allow (ArduPilot puts its home in item 0 anyway): the items wait, and
:func:`held_mission_problems` checks the mission the vehicle holds as soon as home is known; until then, and
while an item is beyond the limits, the mission is not started (:class:`driver.vehicle.missions.MissionControl`).

The fence's shapes (:func:`fence_shapes`, :meth:`FenceShapes.outside`) are also what the simulated vehicle
enforces, as AC_Fence does: outside every inclusion polygon or circle, or inside an exclusion, is a breach.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core import frames
from .plan import MissionItem, Plan, PlanKind

__all__ = ["plan_problems", "held_mission_problems", "unchecked", "UNCHECKED", "fence_shapes", "FenceShapes",
           "inside_polygon"]

_GLOBAL = {mavlink.MAV_FRAME_GLOBAL, mavlink.MAV_FRAME_GLOBAL_INT}
UNCHECKED = "its items are not checked against the distance limits: the vehicle has not sent its home yet"


def inside_polygon(point: tuple[float, float], polygon: list[tuple[float, float]]) -> bool:
    """Even-odd rule (AP_Math's Polygon_outside, inverted)."""
    x, y = point
    inside = False
    j = len(polygon) - 1
    for i in range(len(polygon)):
        xi, yi = polygon[i]
        xj, yj = polygon[j]
        if (yi > y) != (yj > y) and x < (xj - xi) * (y - yi) / (yj - yi) + xi:
            inside = not inside
        j = i
    return inside


@dataclass(frozen=True)
class FenceShapes:
    """A fence plan's shapes in metres from home (north, east)."""
    inclusions: tuple[tuple[tuple[float, float], ...], ...] = ()
    exclusions: tuple[tuple[tuple[float, float], ...], ...] = ()
    circles_in: tuple[tuple[float, float, float], ...] = ()     # north, east, radius
    circles_out: tuple[tuple[float, float, float], ...] = ()
    problems: tuple[str, ...] = ()

    @property
    def empty(self) -> bool:
        return not (self.inclusions or self.exclusions or self.circles_in or self.circles_out)

    def outside(self, north: float, east: float) -> str:
        """Why a point breaches the fence ("" inside it)."""
        p = (north, east)
        for poly in self.inclusions:
            if not inside_polygon(p, list(poly)):
                return "outside an inclusion polygon"
        for n, e, r in self.circles_in:
            if math.hypot(north - n, east - e) > r:
                return "outside an inclusion circle"
        for poly in self.exclusions:
            if inside_polygon(p, list(poly)):
                return "inside an exclusion polygon"
        for n, e, r in self.circles_out:
            if math.hypot(north - n, east - e) < r:
                return "inside an exclusion circle"
        return ""


def fence_shapes(items, home_lat: float, home_lon: float) -> FenceShapes:
    """The shapes of a fence plan's items (MissionItem, or anything with command/param1/lat/lon)."""
    inc, exc, cin, cout, problems = [], [], [], [], []
    i = 0
    items = list(items)
    while i < len(items):
        item = items[i]
        command = item.command
        if command in (mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                       mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION):
            count = int(item.param1)
            vertices = items[i:i + count]
            if count < 3 or len(vertices) < count or any(v.command != command for v in vertices):
                problems.append(f"item {i}: a polygon needs its {count} vertices in a row (at least 3)")
                i += 1
                continue
            poly = tuple(frames.offset_ned(home_lat, home_lon, v.lat, v.lon) for v in vertices)
            (inc if command == mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION else exc).append(poly)
            i += count
            continue
        if command in (mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION):
            n, e = frames.offset_ned(home_lat, home_lon, item.lat, item.lon)
            if not item.param1 > 0:
                problems.append(f"item {i}: a circle needs a radius above 0 m")
            else:
                (cin if command == mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION else cout).append((n, e, item.param1))
        i += 1
    return FenceShapes(tuple(inc), tuple(exc), tuple(cin), tuple(cout), tuple(problems))


def _altitude_above_home(item: MissionItem, home) -> float:
    return item.alt - home.alt if item.frame in _GLOBAL else item.alt


def _placed(item: MissionItem) -> bool:
    """An item at a place (0, 0 is ArduPilot's "here")."""
    return item.has_position and not (item.lat == 0 and item.lon == 0)


def unchecked(plan: Plan, home) -> bool:
    """Whether items of ``plan`` wait for the vehicle's home before their distance can be checked."""
    return home is None and plan.kind is PlanKind.MISSION and any(_placed(item) for item in plan.items)


def held_mission_problems(state, config) -> tuple[str, ...]:
    """What the limits say of the mission the vehicle holds (as read back): one line per item beyond them, or
    :data:`UNCHECKED` before home is known; empty when it may be flown or is not known."""
    plan = state.mission.vehicle_plan(PlanKind.MISSION)
    if plan is None:
        return ()
    if unchecked(plan, state.home):
        return (UNCHECKED,)
    return tuple(plan_problems(plan, state, config))


def plan_problems(plan: Plan, state, config) -> list[str]:
    """Why ``plan`` may not go to the vehicle: one line per item refused (empty: it may). Before home is known
    the distances are not checked here (:func:`unchecked`)."""
    first = 1 if plan.kind is PlanKind.MISSION else 0
    home = state.home
    problems: list[str] = []
    fence = state.fence
    held = state.mission.vehicle_plan(PlanKind.FENCE)
    shapes = fence_shapes(held.items, home.lat, home.lon) if held is not None and home is not None else None
    if plan.kind is PlanKind.FENCE:                  # its shapes' structure; any reference point will do for it
        problems += list(fence_shapes(plan.items, *((home.lat, home.lon) if home is not None else (0.0, 0.0)))
                         .problems)
    for index, item in enumerate(plan.items, first):
        label = f"item {index} ({item.name})"
        if not item.finite():
            problems.append(f"{label}: a value is not a finite number")
            continue
        if not _placed(item):
            if plan.kind is PlanKind.MISSION and item.has_position and item.alt > config.max_altitude:
                problems.append(f"{label}: {item.alt:g} m is above the {config.max_altitude:g} m ceiling")
            continue
        if not (-90 <= item.lat <= 90 and -180 <= item.lon <= 180):
            problems.append(f"{label}: latitude/longitude out of range")
            continue
        if home is None:
            continue                         # checked once home is known (held_mission_problems)
        north, east = frames.offset_ned(home.lat, home.lon, item.lat, item.lon)
        distance = math.hypot(north, east)
        if plan.kind is PlanKind.FENCE:
            continue                         # a fence may reach beyond where the vehicle may fly
        if distance > config.max_distance:
            problems.append(f"{label}: {distance:.0f} m from home, beyond the {config.max_distance:g} m limit")
        up = _altitude_above_home(item, home)
        if up > config.max_altitude:
            problems.append(f"{label}: {up:g} m above home, above the {config.max_altitude:g} m ceiling")
        why = fence.destination_problem(north, east, up)
        if why:
            problems.append(f"{label}: {why}")
        elif shapes is not None and not shapes.empty and fence.enabled:
            where = shapes.outside(north, east)
            if where:
                problems.append(f"{label}: {where} of the vehicle's fence")
    return problems
