"""The plan being edited in Plan mode (no Qt): the mission, the fence and the rally points.

The mission is a list of entries, each a :class:`driver.mission.plan.MissionItem` or a survey
(:class:`uavviewer.plan.survey.SurveySpec`, flown as the items its lawnmower gives); :meth:`PlanDocument.plan`
expands it into the :class:`~driver.mission.plan.Plan` the driver uploads. A waypoint's speed is not a field of
its own in ArduPilot: it is a DO_CHANGE_SPEED item before it, and the list shows the speed in force on each leg.

Totals and progress are estimates from the vehicle's own navigation parameters (WPNAV_SPEED, WPNAV_SPEED_UP,
WPNAV_SPEED_DN, LAND_SPEED, RTL_ALT, BATT_CAPACITY) when it has reported them, else ArduCopter's defaults.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Union

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.core.frames import offset_ned
from driver.mission.plan import MissionItem, Plan, PlanKind

from .survey import Survey, SurveySpec, survey

__all__ = ["Entry", "PlanDocument", "FenceShape", "Performance", "Totals", "ITEM_KINDS", "new_item",
           "is_nav", "NAV_COMMANDS"]

C = mavlink
RESERVE = 20.0                # % of the pack a plan should leave (ArduPilot's low-battery failsafe territory)
Entry = Union[MissionItem, SurveySpec]

#: Items that fly somewhere (the vehicle moves on to the next only when it gets there).
NAV_COMMANDS = {C.MAV_CMD_NAV_WAYPOINT, C.MAV_CMD_NAV_TAKEOFF, C.MAV_CMD_NAV_LAND, C.MAV_CMD_NAV_RETURN_TO_LAUNCH,
                C.MAV_CMD_NAV_LOITER_TIME, C.MAV_CMD_NAV_LOITER_UNLIM, C.MAV_CMD_NAV_LOITER_TURNS,
                C.MAV_CMD_NAV_SPLINE_WAYPOINT, C.MAV_CMD_NAV_LOITER_TO_ALT}
_AT_PLACE = {C.MAV_CMD_NAV_WAYPOINT, C.MAV_CMD_NAV_LOITER_TIME, C.MAV_CMD_NAV_LOITER_UNLIM,
             C.MAV_CMD_NAV_LOITER_TURNS, C.MAV_CMD_NAV_SPLINE_WAYPOINT, C.MAV_CMD_NAV_LOITER_TO_ALT}

#: What the pilot can add, by the name the item list shows.
ITEM_KINDS = {
    "Waypoint": C.MAV_CMD_NAV_WAYPOINT,
    "Takeoff": C.MAV_CMD_NAV_TAKEOFF,
    "Land": C.MAV_CMD_NAV_LAND,
    "RTL": C.MAV_CMD_NAV_RETURN_TO_LAUNCH,
    "Change speed": C.MAV_CMD_DO_CHANGE_SPEED,
    "ROI": C.MAV_CMD_DO_SET_ROI,
    "Loiter (time)": C.MAV_CMD_NAV_LOITER_TIME,
}


def is_nav(item: MissionItem) -> bool:
    return item.command in NAV_COMMANDS


def new_item(command: int, lat: float = 0.0, lon: float = 0.0, alt: float = 10.0, speed: float = 5.0
             ) -> MissionItem:
    """An item of ``command`` as the pilot adds it (a place where it has one; DO items in the MISSION frame)."""
    if command == C.MAV_CMD_DO_CHANGE_SPEED:
        return MissionItem(command, frame=C.MAV_FRAME_MISSION, param1=1.0, param2=speed, param3=-1.0)
    if command == C.MAV_CMD_NAV_RETURN_TO_LAUNCH:
        return MissionItem(command, alt=0.0)
    if command == C.MAV_CMD_NAV_TAKEOFF:
        return MissionItem(command, alt=alt)
    if command == C.MAV_CMD_NAV_LAND:
        return MissionItem(command, lat=lat, lon=lon, alt=0.0)
    if command == C.MAV_CMD_NAV_LOITER_TIME:
        return MissionItem(command, param1=10.0, lat=lat, lon=lon, alt=alt)
    return MissionItem(command, lat=lat, lon=lon, alt=alt)


@dataclass(frozen=True)
class FenceShape:
    """One fence area: a polygon (vertices, latitude/longitude) or a circle (centre and radius), inclusion
    (stay inside) or exclusion (stay out)."""
    inclusion: bool
    vertices: tuple[tuple[float, float], ...] = ()
    radius: float = 0.0                        # > 0: a circle about vertices[0]

    @property
    def circle(self) -> bool:
        return self.radius > 0

    @property
    def label(self) -> str:
        return f"{'Inclusion' if self.inclusion else 'Exclusion'} {'circle' if self.circle else 'polygon'}"


@dataclass(frozen=True)
class Performance:
    """What the estimates assume: ArduCopter's defaults until the vehicle reports its own parameters."""
    cruise: float = 5.0                        # m/s, WPNAV_SPEED
    climb: float = 2.5                         # m/s, WPNAV_SPEED_UP
    descent: float = 1.5                       # m/s, WPNAV_SPEED_DN
    land_speed: float = 0.5                    # m/s, LAND_SPEED (the last 10 m; faster above)
    rtl_alt: float = 15.0                      # m, RTL_ALT
    capacity_mah: float = 5200.0               # BATT_CAPACITY (the Solo's pack)
    hover_amps: float = 15.0                   # a Solo hovers on ~15 A: 5.2 Ah in about 20 minutes
    amps_per_ms: float = 0.6                   # ... and draws this much more per m/s of speed
    known: frozenset = frozenset()             # the parameters above the vehicle reported (the rest: defaults)

    @classmethod
    def from_parameters(cls, table, base: "Performance | None" = None) -> "Performance":
        """The vehicle's own values where its parameter table has them."""
        p = base or cls()
        known = set()

        def value(name: str, scale: float, default: float) -> float:
            got = table.get(name) if table is not None else None
            v = getattr(got, "value", None)
            if isinstance(v, (int, float)) and math.isfinite(v) and v > 0:
                known.add(name)
                return v * scale
            return default
        out = replace(p, cruise=value("WPNAV_SPEED", 0.01, p.cruise), climb=value("WPNAV_SPEED_UP", 0.01, p.climb),
                      descent=value("WPNAV_SPEED_DN", 0.01, p.descent),
                      land_speed=value("LAND_SPEED", 0.01, p.land_speed), rtl_alt=value("RTL_ALT", 0.01, p.rtl_alt),
                      capacity_mah=value("BATT_CAPACITY", 1.0, p.capacity_mah))
        return replace(out, known=frozenset(known))

    def cruise_text(self) -> str:
        """The cruise speed and where it comes from, short enough for the totals' three lines beside the list at
        1366×768: "10 m/s (WPNAV_SPEED)" or "5 m/s (assumed)"; :meth:`cruise_source` says it in full."""
        return f"{self.cruise:g} m/s (WPNAV_SPEED)" if "WPNAV_SPEED" in self.known else f"{self.cruise:g} m/s (assumed)"

    def cruise_source(self) -> str:
        if "WPNAV_SPEED" in self.known:
            return f"Cruise {self.cruise:g} m/s: the vehicle's WPNAV_SPEED"
        return (f"Cruise {self.cruise:g} m/s assumed: ArduCopter's default, as the vehicle has not said its "
                "WPNAV_SPEED")


@dataclass(frozen=True)
class Totals:
    distance: float = 0.0                      # m flown horizontally
    time: float = 0.0                          # s
    mah: float = 0.0
    percent: float = 0.0                       # of the pack
    open_ended: bool = False                   # a LOITER_UNLIM: it never ends by itself

    @property
    def beyond_reserve(self) -> bool:
        """More than the pack gives while keeping a RESERVE of it for the landing and the unexpected."""
        return self.percent > 100.0 - RESERVE

    def text(self) -> str:
        if self.distance == 0 and self.time == 0:
            return "Empty plan"
        minutes, seconds = divmod(int(round(self.time)), 60)
        more = " (then loiters until told)" if self.open_ended else ""
        warn = f" — more than the pack gives with a {RESERVE:.0f} % reserve" if self.beyond_reserve else ""
        return (f"{self.distance / 1000:.2f} km · {minutes}:{seconds:02d} min · battery {self.mah:.0f} mAh "
                f"({self.percent:.0f} %){warn}{more}")


@dataclass
class _Walk:
    north: float = 0.0
    east: float = 0.0
    alt: float = 0.0
    speed: float = 5.0
    totals: Totals = field(default_factory=Totals)


class PlanDocument:
    """The mission, fence and rally points the pilot is editing. Mutable: Plan mode changes it in place and
    redraws; everything leaving it is an immutable :class:`Plan`."""

    def __init__(self) -> None:
        self.entries: list[Entry] = []
        self.fence: list[FenceShape] = []
        self.fence_extra: list[MissionItem] = []     # a return point read from the vehicle, kept as it was
        self.rally: list[MissionItem] = []
        self._surveys: dict[SurveySpec, Survey] = {}   # each spec's lawnmower, made once

    # -- the mission ------------------------------------------------------------------------------
    def survey_of(self, spec: SurveySpec) -> Survey:
        got = self._surveys.get(spec)
        if got is None:
            if len(self._surveys) > 64:
                self._surveys.clear()
            got = self._surveys[spec] = survey(spec)
        return got

    def expanded(self) -> list[tuple[int, MissionItem]]:
        """Each item the vehicle gets, with the entry it comes from."""
        out = []
        for i, entry in enumerate(self.entries):
            if isinstance(entry, SurveySpec):
                out += [(i, item) for item in self.survey_of(entry).items]
            else:
                out.append((i, entry))
        return out

    def plan(self, kind: PlanKind = PlanKind.MISSION) -> Plan:
        if kind is PlanKind.MISSION:
            return Plan(kind, tuple(item for _, item in self.expanded()))
        if kind is PlanKind.FENCE:
            return Plan(kind, tuple(_fence_items(self.fence)) + tuple(self.fence_extra))
        return Plan(kind, tuple(self.rally))

    def load(self, plan: Plan) -> None:
        """Replace the plan of ``plan.kind`` with ``plan`` (downloaded, or opened from a file)."""
        if plan.kind is PlanKind.MISSION:
            self.entries = list(plan.items)
        elif plan.kind is PlanKind.FENCE:
            self.fence, self.fence_extra = _fence_shapes(plan.items)
        else:
            self.rally = list(plan.items)

    def entry_of_seq(self, seq: int) -> int | None:
        """The entry holding the vehicle's item ``seq`` (1 = the first flyable item)."""
        expanded = self.expanded()
        return expanded[seq - 1][0] if 1 <= seq <= len(expanded) else None

    def first_seq(self, index: int) -> int | None:
        """The vehicle's number of the first item of entry ``index``."""
        return next((n + 1 for n, (i, _) in enumerate(self.expanded()) if i == index), None)

    def insert(self, index: int, entry: Entry) -> int:
        index = max(0, min(len(self.entries), index))
        self.entries.insert(index, entry)
        return index

    def delete(self, index: int) -> None:
        if 0 <= index < len(self.entries):
            del self.entries[index]

    def move(self, index: int, lat: float, lon: float) -> None:
        entry = self.entries[index]
        if isinstance(entry, MissionItem) and entry.has_position:
            self.entries[index] = replace(entry, lat=lat, lon=lon)

    def set_item(self, index: int, **fields) -> None:
        entry = self.entries[index]
        self.entries[index] = replace(entry, **fields)

    def set_altitude(self, index: int, alt: float) -> None:
        if math.isfinite(alt):
            self.set_item(index, alt=alt)

    def set_hold(self, index: int, seconds: float) -> None:
        """A waypoint's or a timed loiter's wait (param1), in seconds."""
        entry = self.entries[index]
        if isinstance(entry, MissionItem) and entry.command in (C.MAV_CMD_NAV_WAYPOINT, C.MAV_CMD_NAV_LOITER_TIME):
            self.set_item(index, param1=max(0.0, seconds) if math.isfinite(seconds) else 0.0)

    def set_speed(self, index: int, speed: float | None) -> int:
        """The speed of the leg to entry ``index``: a DO_CHANGE_SPEED right before it (None removes it).
        Returns the entry's index afterwards."""
        before = self.entries[index - 1] if index > 0 else None
        has = isinstance(before, MissionItem) and before.command == C.MAV_CMD_DO_CHANGE_SPEED
        entry = self.entries[index]
        if isinstance(entry, MissionItem) and entry.command == C.MAV_CMD_DO_CHANGE_SPEED:
            if speed is not None and speed > 0:
                self.set_item(index, param2=speed)
            return index
        if speed is None or not (speed > 0 and math.isfinite(speed)):
            if has:
                del self.entries[index - 1]
                return index - 1
            return index
        if has:
            self.entries[index - 1] = replace(before, param2=speed)
            return index
        self.entries.insert(index, new_item(C.MAV_CMD_DO_CHANGE_SPEED, speed=speed))
        return index + 1

    def leg_speeds(self, cruise: float) -> list[float]:
        """The speed in force when each entry is flown (after any DO_CHANGE_SPEED before it)."""
        out, speed = [], cruise
        for entry in self.entries:
            out.append(speed)
            if isinstance(entry, MissionItem) and entry.command == C.MAV_CMD_DO_CHANGE_SPEED and entry.param2 > 0:
                speed = entry.param2
        return out

    def positions(self) -> list[tuple[int, float, float, float]]:
        """(entry index, lat, lon, alt) of each entry drawn on the map: places flown to and ROIs."""
        return [(i, e.lat, e.lon, e.alt) for i, e in enumerate(self.entries)
                if isinstance(e, MissionItem) and e.has_position and (e.lat or e.lon)]

    # -- estimates --------------------------------------------------------------------------------
    def totals(self, home: tuple[float, float] | None, perf: Performance = Performance()) -> Totals:
        """Distance, flight time and battery from take-off at home to the end of the plan."""
        if home is None:
            return Totals()
        walk = _Walk(speed=perf.cruise)
        for _, item in self.expanded():
            _fly(walk, item, home, perf)
        t = walk.totals
        percent = 100.0 * t.mah / perf.capacity_mah if perf.capacity_mah > 0 else 0.0
        return replace(t, percent=percent)

    def path(self, home: tuple[float, float]) -> list[tuple[float, float]]:
        """(lat, lon) of each place flown through, from home, in order (RTL comes home)."""
        out = [home]
        for _, item in self.expanded():
            if item.command == C.MAV_CMD_NAV_RETURN_TO_LAUNCH:
                out.append(home)
            elif item.command in NAV_COMMANDS and (item.lat or item.lon):
                out.append((item.lat, item.lon))
        return out


def _fly(w: _Walk, item: MissionItem, home: tuple[float, float], perf: Performance) -> None:
    cmd = item.command

    def fly_to(north: float, east: float, alt: float, speed: float) -> None:
        d = math.hypot(north - w.north, east - w.east)
        climb = alt - w.alt
        dt = max(d / max(speed, 0.1), climb / perf.climb if climb > 0 else -climb / perf.descent)
        amps = perf.hover_amps + perf.amps_per_ms * (d / dt if dt > 0 else 0.0)
        w.totals = replace(w.totals, distance=w.totals.distance + d, time=w.totals.time + dt,
                           mah=w.totals.mah + amps * dt / 3.6)
        w.north, w.east, w.alt = north, east, alt

    def wait(seconds: float) -> None:
        w.totals = replace(w.totals, time=w.totals.time + seconds, mah=w.totals.mah + perf.hover_amps * seconds / 3.6)

    def land() -> None:
        high = max(0.0, w.alt - 10.0)                 # ArduCopter: WPNAV_SPEED_DN down to 10 m, LAND_SPEED below
        low = w.alt - high
        wait(high / perf.descent + low / perf.land_speed)
        w.alt = 0.0

    def place() -> tuple[float, float]:
        if not (item.lat or item.lon):
            return w.north, w.east                    # 0, 0: where the vehicle is
        return offset_ned(home[0], home[1], item.lat, item.lon)

    if cmd == C.MAV_CMD_DO_CHANGE_SPEED:
        if item.param2 > 0:
            w.speed = item.param2
    elif cmd == C.MAV_CMD_NAV_TAKEOFF:
        fly_to(w.north, w.east, max(w.alt, item.alt), w.speed)
    elif cmd in _AT_PLACE:
        fly_to(*place(), item.alt, w.speed)
        if cmd in (C.MAV_CMD_NAV_WAYPOINT, C.MAV_CMD_NAV_LOITER_TIME):
            wait(max(0.0, item.param1))
        elif cmd == C.MAV_CMD_NAV_LOITER_UNLIM:
            w.totals = replace(w.totals, open_ended=True)
    elif cmd == C.MAV_CMD_NAV_LAND:
        fly_to(*place(), w.alt, w.speed)
        land()
    elif cmd == C.MAV_CMD_NAV_RETURN_TO_LAUNCH:
        up = max(w.alt, perf.rtl_alt)
        fly_to(w.north, w.east, up, w.speed)
        fly_to(0.0, 0.0, up, w.speed)
        land()


# -- fences ---------------------------------------------------------------------------------------------
_VERTEX = {True: C.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION, False: C.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION}
_CIRCLE = {True: C.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, False: C.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION}


def _fence_items(shapes: list[FenceShape]):
    """MAV_CMD_NAV_FENCE_* items: each polygon vertex carries the vertex count (param1), a circle its radius."""
    for shape in shapes:
        if shape.circle:
            lat, lon = shape.vertices[0]
            yield MissionItem(_CIRCLE[shape.inclusion], frame=C.MAV_FRAME_GLOBAL, param1=shape.radius, lat=lat,
                              lon=lon)
        elif len(shape.vertices) >= 3:
            for lat, lon in shape.vertices:
                yield MissionItem(_VERTEX[shape.inclusion], frame=C.MAV_FRAME_GLOBAL,
                                  param1=float(len(shape.vertices)), lat=lat, lon=lon)


def _fence_shapes(items) -> tuple[list[FenceShape], list[MissionItem]]:
    shapes, extra, polygon, kind, left = [], [], [], None, 0
    for item in items:
        cmd = item.command
        if cmd in _CIRCLE.values():
            shapes.append(FenceShape(cmd == _CIRCLE[True], ((item.lat, item.lon),), item.param1))
        elif cmd in _VERTEX.values():
            inclusion = cmd == _VERTEX[True]
            if not polygon:
                kind, left = inclusion, max(1, int(item.param1))
            polygon.append((item.lat, item.lon))
            left -= 1
            if left <= 0:
                shapes.append(FenceShape(kind, tuple(polygon)))
                polygon = []
        else:
            extra.append(item)
    if polygon:
        shapes.append(FenceShape(bool(kind), tuple(polygon)))
    return shapes, extra
