"""Fixtures shared by the tests/test_ice_*.py files: a real Ice server on loopback in front of the real driver.

Imported by those files (``from ice_fixtures import ...``); it holds no tests itself.
"""
from __future__ import annotations

import os
import socket
import time

import Ice
import pytest

from driver.ice import load_slice
from driver.ice.client import IceDrone, viewer_properties
from driver.ice.server import IceServer, default_properties
from patience import patient, patient_waits

jderobot, mavlinkserver = load_slice()


def _port_block() -> range:
    """Ports a test may hand to a server it starts later: below the kernel's ephemeral range (32768 and up,
    which every socket bound to port 0 draws from, in every xdist worker at once) and one block per worker,
    so no other test's socket can take a port between this choice and its use."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    index = int(worker[2:]) if worker[2:].isdigit() else 0
    start = 20000 + 500 * (index % 24)
    return range(start, start + 500)


_next_port = iter(())


def free_port() -> int:
    """A free TCP port on 127.0.0.1 from this worker's own block."""
    global _next_port
    for _ in range(2):
        for port in _next_port:
            with socket.socket() as s:
                try:
                    s.bind(("127.0.0.1", port))
                except OSError:
                    continue
                return port
        _next_port = iter(_port_block())          # wrap around: the block's first ports are free again by now
    raise RuntimeError("no free port in this worker's block")


def eventually(condition, timeout: float, interval: float = 0.05):
    """Poll ``condition()`` until it returns something truthy; that value, or None at the deadline (``timeout``
    stretched by PATIENCE: tests/patience.py)."""
    deadline = time.monotonic() + patient(timeout)
    while True:
        value = condition()
        if value:
            return value
        if time.monotonic() > deadline:
            return None
        time.sleep(interval)


@pytest.fixture
def server_factory():
    """Start Ice servers for drivers; every interface on one loopback port unless told otherwise."""
    servers = []

    def make(vehicle, port: int = 0, **properties) -> IceServer:
        args = [f"--MAVLinkServer.Endpoints=tcp -h 127.0.0.1 -p {port}"] if port is not None else []
        args += [f"--{k}={v}" for k, v in properties.items()]
        server = IceServer(vehicle, default_properties(args)).start()
        servers.append(server)
        return server

    yield make
    for server in servers:
        server.close()


@pytest.fixture
def ice_server(vehicle, server_factory) -> IceServer:
    return server_factory(vehicle)


@pytest.fixture
def communicator():
    """A plain client communicator, as a JdeRobot application would have."""
    com = Ice.initialize(["--Ice.Default.InvocationTimeout=5000"])
    yield com
    com.destroy()


@pytest.fixture
def jde(ice_server, communicator):
    """JdeRobot proxies to the server, by interface role."""
    casts = {"Pose3D": jderobot.Pose3DPrx, "WP": jderobot.Pose3DPrx, "CMDVel": jderobot.CMDVelPrx,
             "Navdata": jderobot.NavdataPrx, "Extra": jderobot.ArDroneExtraPrx, "Camera": jderobot.CameraPrx,
             "Vehicle": mavlinkserver.VehiclePrx}

    class Proxies:
        def __getattr__(self, name):
            return casts[name].checkedCast(communicator.stringToProxy(ice_server.proxy(name)))
    return Proxies()


@pytest.fixture
def drone_factory():
    """IceDrone clients; closed after the test."""
    drones = []

    def make(server: IceServer | None = None, host: str | None = None, **kwargs) -> IceDrone:
        props = viewer_properties(host=host)
        if server is not None:
            for key, value in server.client_properties().items():
                props.setProperty(key, value)
        drone = patient_waits(IceDrone(props, **kwargs).start())
        drones.append(drone)
        return drone

    yield make
    for drone in drones:
        drone.close()
