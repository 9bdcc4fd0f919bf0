"""Where a shot may take the vehicle, checked before it starts and at each beat.

The same limits as a go-to (driver.vehicle.rules, driver.mission.limits): the driver's ceiling and distance from
home, the vehicle's own fence (FENCE_ALT_MAX, FENCE_RADIUS, the polygon fence it holds; AC_Fence would ignore a
guided target beyond it and the vehicle would stop short), and a floor of :data:`MIN_ALTITUDE` above home so a
path drawn low never meets the ground. A shot whose path leaves them is refused before it starts, naming where.
"""
from __future__ import annotations

import math

from ..mission.limits import fence_shapes
from ..mission.plan import PlanKind

__all__ = ["Bounds", "MIN_ALTITUDE"]

MIN_ALTITUDE = 2.0          # m above home


class Bounds:
    """The limits for the vehicle in ``state`` (a VehicleState with home known)."""

    def __init__(self, state, max_altitude: float, max_distance: float, min_altitude: float = MIN_ALTITUDE):
        self.max_altitude, self.max_distance, self.min_altitude = max_altitude, max_distance, min_altitude
        self.fence = state.fence
        held = state.mission.vehicle_plan(PlanKind.FENCE)
        home = state.home
        self.shapes = fence_shapes(held.items, home.lat, home.lon) if held is not None and home is not None else None

    def problem(self, north: float, east: float, up: float) -> str | None:
        """Why the vehicle may not be at (north, east, up) m from home, or None."""
        if not all(map(math.isfinite, (north, east, up))):
            return "a point is not a finite number"
        if up > self.max_altitude:
            return f"{up:.0f} m is above the {self.max_altitude:g} m ceiling"
        if up < self.min_altitude:
            return f"{up:.1f} m is below the shots' {self.min_altitude:g} m floor"
        distance = math.hypot(north, east)
        if distance > self.max_distance:
            return f"{distance:.0f} m from home is beyond the {self.max_distance:g} m limit"
        why = self.fence.destination_problem(north, east, up)
        if why:
            return why
        if self.shapes is not None and not self.shapes.empty and self.fence.enabled:
            where = self.shapes.outside(north, east)
            if where:
                return f"{where} of the vehicle's fence"
        return None

    def allowed(self, north: float, east: float, up: float) -> bool:
        return self.problem(north, east, up) is None

    def path_problem(self, points, what: str) -> str | None:
        """Why a path (points (north, east, up), in order) may not be flown: the first point beyond the limits."""
        for i, (n, e, u) in enumerate(points):
            why = self.problem(n, e, u)
            if why:
                return f"{what} leaves the limits at N{n:.0f} E{e:.0f} ({i + 1} of {len(points)} points checked): {why}"
        return None
