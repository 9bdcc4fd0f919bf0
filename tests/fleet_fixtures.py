"""Fixtures for the fleet tests: a real lab (Debian's icegridregistry and IceStorm in IceBox) and vehicles
registered with it, each a simulated ArduCopter, the real driver and its MAVLinkServer.

Imported by the tests/test_fleet*.py files; it holds no tests itself.
"""
from __future__ import annotations

import os

import pytest

from driver.ice.lab import Lab, missing
from driver.ice.server import IceServer, default_properties
from driver.sim import SimConfig, SimVehicle
from driver.sim.fleet import fleet_configs

from conftest import SPEEDUP
from ice_fixtures import free_port


def _debian() -> bool:
    return os.path.exists("/etc/debian_version")


@pytest.fixture(scope="module")
def lab():
    """The lab's registry and IceStorm on a free loopback port; on Debian the packages must be there (the
    bootstrap installs them): only elsewhere, where they cannot be had from apt, is this skipped."""
    absent = missing()
    if absent and not _debian():
        pytest.skip(f"ZeroC's IceGrid/IceStorm 3.7.8 come from Debian packages ({', '.join(absent)}); this is "
                    "not Debian")
    assert not absent, f"run scripts/bootstrap: missing Debian packages {absent}"
    with Lab(port=free_port()) as running:
        yield running


@pytest.fixture
def fleet(lab, vehicle_factory):
    """``fleet(n, prefix="solo")``: n simulated vehicles registered as solo-1..solo-n; ``(sims, vehicles,
    servers)``. Everything is stopped after the test (servers first, withdrawing from the registry)."""
    made: list = []

    def make(count: int, prefix: str = "solo", **server_properties):
        sims, vehicles, servers = [], [], []
        base = SimConfig(tcp_port=0, speedup=SPEEDUP, ready_after=1.0, seed=1)
        for i, config in enumerate(fleet_configs(count, base)):
            sim = SimVehicle(config).start()
            made.append(sim)
            sims.append(sim)
            vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
            vehicles.append(vehicle)
            args = [f"--Ice.Default.Locator={lab.locator}", f"--MAVLinkServer.Name={prefix}-{i + 1}"]
            args += [f"--{k}={v}" for k, v in server_properties.items()]
            server = IceServer(vehicle, default_properties(args)).start()
            made.append(server)
            servers.append(server)
        return sims, vehicles, servers

    yield make
    for thing in reversed(made):
        (thing.close if isinstance(thing, IceServer) else thing.stop)()
