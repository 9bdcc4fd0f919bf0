"""A simulated ArduCopter in the air and the real driver flying smart shots on it, judged on the simulator's truth.

The driver runs on the simulator's own clock (``Vehicle(clock=...)``): a shot's speeds and times are the
vehicle's, whatever pace the simulator keeps against the wall, so a 3 m/s orbit is 3 m/s in the truth.
"""
from __future__ import annotations

import math
import time

import pytest

from driver.core import frames
from driver.sim import SimConfig, SimVehicle
from driver.vehicle import Vehicle, VehicleConfig

SHOT_SPEEDUP = 4.0
TAKEOFF_SPEEDUP = 16.0


class Flight:
    """The sim, the driver, and the truth sampled while a shot flies."""

    def __init__(self, sim: SimVehicle, vehicle: Vehicle):
        self.sim, self.vehicle = sim, vehicle
        self.home = vehicle.state().home

    def latlon(self, north: float, east: float) -> tuple[float, float]:
        return frames.offset_latlon(self.home.lat, self.home.lon, north, east)

    def fly_for(self, seconds: float, every=None, until=None) -> list:
        """Sample the truth (and the driver's state) every step of the sim for ``seconds`` of sim time, or until
        ``until(truth, state)``; returns [(truth, state)]."""
        out = []
        start = self.sim.truth().time
        last = None
        while self.sim.truth().time - start < seconds:
            truth = self.sim.truth()
            if truth is last:
                time.sleep(0.002)
                continue
            last = truth
            state = self.vehicle.state()
            out.append((truth, state))
            if until is not None and until(truth, state):
                break
        return out


def start_flight(sim_factory, tmp_path, altitude: float = 10.0, **sim_options) -> Flight:
    sim = sim_factory(speedup=TAKEOFF_SPEEDUP, **sim_options)
    vehicle = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{sim.tcp_port}", command_timeout=1.0,
                                    tlog_path=str(tmp_path / "shots.tlog")), clock=lambda: sim.truth().time).start()
    assert vehicle.wait_for(lambda s: s.connected, 10)
    result = vehicle.takeoff(altitude).result(timeout=60)
    assert result.ok, str(result)
    sim.speedup = SHOT_SPEEDUP
    return Flight(sim, vehicle)


@pytest.fixture
def flight_factory(sim_factory, tmp_path):
    made = []

    def make(altitude: float = 10.0, **sim_options) -> Flight:
        f = start_flight(sim_factory, tmp_path, altitude, **sim_options)
        made.append(f)
        return f

    yield make
    for f in made:
        f.vehicle.close()


def rms(values) -> float:
    values = list(values)
    return math.sqrt(sum(v * v for v in values) / len(values))


def angle_between(pitch1: float, yaw1: float, pitch2: float, yaw2: float) -> float:
    """Degrees between two looks (the great circle), as the shots measure their aim."""
    p1, y1, p2, y2 = (math.radians(v) for v in (pitch1, yaw1, pitch2, yaw2))
    c = math.sin(p1) * math.sin(p2) + math.cos(p1) * math.cos(p2) * math.cos(y1 - y2)
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))
