"""Guided actions built from the Drone interface's own calls: change altitude, circle a point.

Both work on any :class:`driver.vehicle.api.Drone` (the embedded driver, the Ice client), because they only use its
go-to, yaw, parameter and mode calls, each answered by the vehicle.

Circling a point is done the way ArduCopter allows it from a ground station. Its CIRCLE mode takes no centre
from a GCS: on entering the mode the centre is CIRCLE_RADIUS ahead of the nose (AC_Circle::init projects the
stopping point along the heading). So the vehicle is first flown in GUIDED to the point of the circle nearest
to it, turned to face the wanted centre, CIRCLE_RADIUS is set (in cm) and the mode switched to CIRCLE: the
centre it then computes is the point the pilot picked. Any other mode, a stick or Stop on the way ends it.
"""
from __future__ import annotations

import math
import threading
from concurrent.futures import Future

from ..core import frames
from ..core.results import answered
from .state import CommandResult, CommandStatus, VehicleState

__all__ = ["change_altitude", "circle_point", "circle_start", "MIN_CIRCLE_RADIUS", "MAX_CIRCLE_RADIUS"]

MIN_CIRCLE_RADIUS = 2.0          # m: closer than this a copter's circle is a wobble
MAX_CIRCLE_RADIUS = 200.0        # m: kept well inside line of sight (CIRCLE_RADIUS allows far more)
ARRIVED = 1.0                    # m from the start point
FACING = 8.0                     # degrees from the centre's bearing
STEP_TIMEOUT = 90.0              # s for the flight to the start point, and again for the turn


def change_altitude(drone, altitude: float) -> Future:
    """Climb or descend to ``altitude`` (m above home) where the vehicle is now, in GUIDED: a go-to to its own
    position, so the driver's altitude limits, fence and refusals apply as to any go-to."""
    s = drone.state()
    if s.local is None:
        return answered(CommandResult(f"altitude {altitude:g} m", CommandStatus.REJECTED,
                                           "the vehicle has not sent its position yet"))
    return drone.go_to(s.local.north, s.local.east, altitude)


def circle_start(s: VehicleState, north: float, east: float, radius: float) -> tuple[float, float, float]:
    """(north, east, heading in degrees) where the circle around (north, east) begins for the vehicle in ``s``: the
    point of the circle nearest to it, facing the centre."""
    here_n, here_e = (s.local.north, s.local.east) if s.local is not None else (0.0, 0.0)
    dn, de = here_n - north, here_e - east
    dist = math.hypot(dn, de)
    if dist < 1e-3:                                # over the centre: back away along the present heading
        yaw = math.radians(s.heading_deg)
        dn, de, dist = -math.cos(yaw), -math.sin(yaw), 1.0
    start_n, start_e = north + dn / dist * radius, east + de / dist * radius
    heading = round(math.degrees(math.atan2(east - start_e, north - start_n)) % 360.0, 1)
    return start_n, start_e, heading


def circle_point(drone, north: float, east: float, radius: float, altitude: float | None = None) -> Future:
    """Circle (north, east) (m from home) at ``radius`` m, clockwise at the vehicle's CIRCLE_RATE. Resolves ACCEPTED
    once the vehicle reports CIRCLE; REFUSED/ABORTED with the reason otherwise. ``future.cancel()`` (Stop) ends the
    approach where it is."""
    name = f"circle N{north:.0f} E{east:.0f} r {radius:g} m"
    if not all(map(math.isfinite, (north, east, radius))) or altitude is not None and not math.isfinite(altitude):
        return answered(CommandResult(name, CommandStatus.REJECTED, "coordinates are not finite numbers"))
    if not MIN_CIRCLE_RADIUS <= radius <= MAX_CIRCLE_RADIUS:
        return answered(CommandResult(name, CommandStatus.REJECTED,
                                           f"a circle's radius is {MIN_CIRCLE_RADIUS:g} to {MAX_CIRCLE_RADIUS:g} m"))
    s = drone.state()
    if s.mode != "GUIDED" or not s.flying:
        return answered(CommandResult(name, CommandStatus.REJECTED,
                                           f"needs GUIDED and flying (mode {s.mode or '?'})"))
    if s.local is None:
        return answered(CommandResult(name, CommandStatus.REJECTED, "the vehicle has not sent its position yet"))
    future: Future = Future()
    threading.Thread(target=_fly_circle, args=(drone, name, north, east, radius,
                                               s.altitude if altitude is None else altitude, future),
                     name="circle", daemon=True).start()
    return future


def _fly_circle(drone, name: str, north: float, east: float, radius: float, altitude: float, future: Future) -> None:
    def finish(status: CommandStatus, reason: str) -> None:
        if not future.done():                         # cancelled by the pilot (Stop): nothing more to say
            future.set_result(CommandResult(name, status, reason))

    try:
        start_n, start_e, heading = circle_start(drone.state(), north, east, radius)
        result = drone.go_to(start_n, start_e, altitude).result(timeout=30)
        if not result.ok:
            return finish(result.status, f"flying to the circle: {result.reason or result.status.value}")
        why = _wait(drone, lambda s: s.local is not None and
                    math.hypot(s.local.north - start_n, s.local.east - start_e) < ARRIVED and
                    abs(s.altitude - altitude) < ARRIVED, future)
        if why:
            return finish(CommandStatus.ABORTED, f"on the way to the circle: {why}")
        result = drone.set_yaw(heading).result(timeout=30)
        if not result.ok:
            return finish(result.status, f"turning to the centre: {result.reason or result.status.value}")
        why = _wait(drone, lambda s: abs(frames.wrap_180(s.heading_deg - heading)) < FACING, future)
        if why:
            return finish(CommandStatus.ABORTED, f"turning to the centre: {why}")
        if future.cancelled():
            return
        result = drone.set_parameter("CIRCLE_RADIUS", round(radius * 100.0)).result(timeout=30)
        if not result.ok:
            return finish(result.status, f"setting CIRCLE_RADIUS: {result.reason or result.status.value}")
        result = drone.set_mode("CIRCLE").result(timeout=30)
        if not result.ok:
            return finish(result.status, result.reason or "the vehicle did not switch to CIRCLE")
        finish(CommandStatus.ACCEPTED, f"circling N{north:.0f} E{east:.0f} at {radius:g} m")
    except Exception as exc:                          # noqa: BLE001 - a closed driver, a timeout: said, not raised
        if not future.done():
            finish(CommandStatus.ABORTED, f"{type(exc).__name__}: {exc}")


def _wait(drone, reached, future: Future, timeout: float = STEP_TIMEOUT) -> str:
    """"" once ``reached(state)``; else why the circle was given up: the pilot took over (another mode, a stick,
    Stop cancelling ``future``) or time ran out. Waits with the drone's own ``wait_for``."""
    def why(s: VehicleState) -> str | None:
        if future.cancelled():
            return "cancelled"
        if not s.connected:
            return "the link is down"
        if s.mode != "GUIDED":
            return f"the mode changed to {s.mode}"
        if not s.setpoint.is_zero:
            return "the sticks took over"
        if not s.flying:
            return "the vehicle is no longer flying"
        return "" if reached(s) else None

    s = drone.wait_for(lambda s: why(s) is not None, timeout)
    reason = why(s if s is not None else drone.state())     # None from wait_for: time ran out, or it closed
    return reason if reason is not None else f"not reached in {timeout:g} s"
