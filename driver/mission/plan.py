"""The plan model every layer shares: what a mission, a fence or a set of rally points is, independent of the
wire (MISSION_ITEM_INT / MISSION_ITEM / FENCE_POINT / RALLY_POINT) and of the file format (.plan, WPL 110).

Immutable: a plan is built, then passed between threads, the viewer and Ice as it is.

Numbering follows the vehicle. A :class:`Plan` of kind MISSION holds the flyable items only; on the wire the
vehicle's item 0 is its home slot, so ``plan.items[0]`` is the vehicle's item 1. Fence and rally plans have
no home slot: ``items[0]`` is the vehicle's item 0.
"""
from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from pymavlink.dialects.v20 import ardupilotmega as mavlink

if TYPE_CHECKING:
    from ..core.results import CommandResult

__all__ = ["PlanKind", "MissionItem", "Plan", "TransferDirection", "TransferProgress", "TransferOutcome",
           "MissionRunState", "MissionProgress"]


class PlanKind(enum.IntEnum):
    """MAV_MISSION_TYPE: the three plans a vehicle holds."""
    MISSION = mavlink.MAV_MISSION_TYPE_MISSION
    FENCE = mavlink.MAV_MISSION_TYPE_FENCE
    RALLY = mavlink.MAV_MISSION_TYPE_RALLY

    @property
    def label(self) -> str:
        return {PlanKind.MISSION: "mission", PlanKind.FENCE: "fence", PlanKind.RALLY: "rally points"}[self]


@dataclass(frozen=True)
class MissionItem:
    """One item as MISSION_ITEM_INT carries it; latitude and longitude in degrees (not 1e7), altitude in metres
    in ``frame`` (MAV_FRAME: GLOBAL_RELATIVE_ALT for waypoints, MISSION for DO_ commands)."""
    command: int                                 # MAV_CMD
    frame: int = mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT
    param1: float = 0.0
    param2: float = 0.0
    param3: float = 0.0
    param4: float = 0.0
    lat: float = 0.0                             # degrees (x)
    lon: float = 0.0                             # degrees (y)
    alt: float = 0.0                             # metres (z)
    autocontinue: bool = True

    @property
    def name(self) -> str:
        """ArduPilot's short name: "WAYPOINT", "TAKEOFF", "DO_CHANGE_SPEED", ..."""
        entry = mavlink.enums["MAV_CMD"].get(self.command)
        return entry.name.replace("MAV_CMD_NAV_", "").replace("MAV_CMD_", "") if entry else str(self.command)

    @property
    def has_position(self) -> bool:
        """True for items that fly to, or mark, a place (their lat/lon mean something)."""
        return self.command in _POSITIONAL

    @property
    def params(self) -> tuple[float, float, float, float]:
        return (self.param1, self.param2, self.param3, self.param4)

    def finite(self) -> bool:
        """Position finite; params finite or NaN (MAVLink's "leave unchanged"), never infinite."""
        return (all(math.isfinite(v) for v in (self.lat, self.lon, self.alt))
                and not any(math.isinf(v) for v in self.params))


_POSITIONAL = {
    mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_CMD_NAV_LOITER_UNLIM, mavlink.MAV_CMD_NAV_LOITER_TURNS,
    mavlink.MAV_CMD_NAV_LOITER_TIME, mavlink.MAV_CMD_NAV_LAND, mavlink.MAV_CMD_NAV_TAKEOFF,
    mavlink.MAV_CMD_NAV_SPLINE_WAYPOINT, mavlink.MAV_CMD_NAV_LOITER_TO_ALT, mavlink.MAV_CMD_DO_SET_ROI,
    mavlink.MAV_CMD_DO_SET_ROI_LOCATION, mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
    mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION, mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION,
    mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION, mavlink.MAV_CMD_NAV_FENCE_RETURN_POINT,
    mavlink.MAV_CMD_NAV_RALLY_POINT,
}


@dataclass(frozen=True)
class Plan:
    """A mission, fence or set of rally points (see the module's note on numbering)."""
    kind: PlanKind = PlanKind.MISSION
    items: tuple[MissionItem, ...] = ()

    def __len__(self) -> int:
        return len(self.items)


class TransferDirection(enum.Enum):
    UPLOAD = "upload"
    DOWNLOAD = "download"
    CLEAR = "clear"


@dataclass(frozen=True)
class TransferProgress:
    """One transfer of one plan kind, as it goes."""
    kind: PlanKind
    direction: TransferDirection
    done: int = 0                                # items sent or received so far
    total: int = 0                               # items in the transfer (0 until the count is known)
    active: bool = True
    detail: str = ""                             # "re-asking item 4", "reading back", "DENIED: ..."


@dataclass(frozen=True)
class TransferOutcome:
    """What a transfer ended with: the driver's verdict and, where there is one, the plan the vehicle holds
    (downloaded, or read back after an upload)."""
    result: "CommandResult"
    plan: Plan | None = None


class MissionRunState(enum.IntEnum):
    """MISSION_CURRENT.mission_state (MISSION_STATE)."""
    UNKNOWN = 0
    NO_MISSION = 1
    NOT_STARTED = 2
    ACTIVE = 3
    PAUSED = 4
    COMPLETE = 5


@dataclass(frozen=True)
class MissionProgress:
    """The mission as the vehicle reports it (MISSION_CURRENT, MISSION_ITEM_REACHED, "Mission: N ..." texts),
    and the transfers running now. ``current`` and ``last_reached`` are the vehicle's item numbers (1 is the
    first flyable item); ``count`` excludes the home slot, as MISSION_CURRENT.total does."""
    count: int | None = None                     # None until the vehicle says
    current: int | None = None
    state: MissionRunState = MissionRunState.UNKNOWN
    last_reached: int | None = None
    current_name: str = ""                       # from "Mission: 3 WP", when the vehicle says it
    transfers: tuple[TransferProgress, ...] = field(default_factory=tuple)
    on_vehicle: tuple[Plan, ...] = ()            # the last plans known to be on the vehicle (read back/downloaded)
    limit_problems: tuple[str, ...] = ()         # the driver's limits on the mission the vehicle holds: each item
                                                 # beyond them, or not checked (no home yet); it is not started then
    flown: bool = False                          # flown to its end: the vehicle landed on its last item and
                                                 # disarmed (it then rewinds to item 1 and calls that active)

    def transfer(self, kind: PlanKind) -> TransferProgress | None:
        return next((t for t in self.transfers if t.kind is kind), None)

    def vehicle_plan(self, kind: PlanKind) -> Plan | None:
        return next((p for p in self.on_vehicle if p.kind is kind), None)

