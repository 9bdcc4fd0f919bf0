"""The flight timer: time armed, as every ground station shows it (QGroundControl's "Flight time")."""
from __future__ import annotations

import time

from driver.vehicle.state import VehicleState

__all__ = ["FlightTimer", "clock_text"]


def clock_text(seconds: float | None) -> str:
    """``754`` -> "12:34", ``3725`` -> "1:02:05", None -> "--:--"."""
    if seconds is None or seconds != seconds or seconds < 0:
        return "--:--"
    whole = int(seconds)
    hours, rest = divmod(whole, 3600)
    return f"{hours}:{rest // 60:02d}:{rest % 60:02d}" if hours else f"{rest // 60:02d}:{rest % 60:02d}"


class FlightTimer:
    """Runs while the vehicle reports armed; keeps the last flight's time once disarmed, restarts at the next arm.
    A motor test arms the vehicle too, but is no flight: an arming that comes while one runs leaves the last
    flight's time as it was. A reconnection to the same vehicle (same link and system id) that finds it still armed
    goes on with the flight it left. ``clock``: a monotonic clock (tests may pass their own)."""

    def __init__(self, clock=time.monotonic) -> None:
        self._clock = clock
        self._since: float | None = None       # the clock when the vehicle armed, None while disarmed
        self._previous_flight = 0.0                        # the previous flight's seconds, shown while disarmed
        self.started = False                    # armed at least once
        self._vehicle: tuple = ()               # (link address, system id) of the vehicle timed
        self._left: tuple | None = None         # (vehicle, since) of a flight under way when the window left it
        self._testing = False                   # armed by a motor test (setup.motor_test_running): no flight
        self._started_before = False            # ``started`` before the arming under way

    def update(self, s: VehicleState) -> float:
        """The flight time now, following ``s.armed`` (never a flag of ours)."""
        now = self._clock()
        if s.system_id:
            self._vehicle = (s.link.address, s.system_id)
        if s.armed and s.setup.motor_test_running and not self._testing and s.in_air is not True:
            self._testing = True                # until it disarms, whatever the test says meanwhile
            if self._since is not None:         # the arming was heard before the test's acceptance: no flight
                self._since, self.started = None, self._started_before
        if s.armed and self._since is None and not self._testing:
            left, self._left = self._left, None
            self._since = left[1] if left is not None and left[0] == self._vehicle else now
            self._started_before, self.started = self.started, True
        elif not s.armed:
            self._testing = False
            if self._since is not None:
                self._previous_flight, self._since = now - self._since, None
        return self.seconds

    def reset(self) -> None:
        """Another connection: its time starts anew at its arm, unless it is the same vehicle still flying."""
        if self._since is not None:
            self._left = (self._vehicle, self._since)
        self._since, self._previous_flight, self.started = None, 0.0, False

    @property
    def seconds(self) -> float:
        return self._clock() - self._since if self._since is not None else self._previous_flight
