"""The driver on a simulated vehicle of either profile, ready to arm: what the setup tests share."""
from __future__ import annotations

import pytest

PROFILES = ("copter-4", "solo")


@pytest.fixture(params=PROFILES)
def bench(request, sim_factory, vehicle_factory):
    """(sim, vehicle) on the bench, for each firmware profile; ``request.param`` names it."""
    def make(**sim_options):
        sim = sim_factory(profile=request.param, **sim_options)
        vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
        assert vehicle.wait_for(lambda s: s.connected and s.readiness.prearm_ok, 30), "vehicle not ready"
        return sim, vehicle
    make.profile = request.param
    return make


def texts(vehicle) -> list[str]:
    return [m.text for m in vehicle.state().messages]
