"""A fleet on ZeroC's own services: vehicles registered by name with a real IceGrid registry, their telemetry
fanned out by a real IceStorm (IceBox), observers subscribed instead of polling, a stopped server seen."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading

import Ice
import pytest

from driver.ice import load_slice
from driver.ice.client import IceDrone
from driver.ice.publisher import topic
from driver.ice.registry import TOPIC_MANAGER, list_vehicles
from driver.ice.server import IceServer, ServeError, default_properties
from driver.vehicle.state import LinkStatus

from fleet_fixtures import fleet, lab  # noqa: F401  (fixtures)
from ice_fixtures import eventually

jderobot, mavlinkserver = load_slice()
pytestmark = pytest.mark.timeout(90)
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.fixture
def client(lab):
    """A plain client of the lab, as a JdeRobot application would have: only the registry's address."""
    com = Ice.initialize([f"--Ice.Default.Locator={lab.locator}", "--Ice.Default.InvocationTimeout=5000"])
    yield com
    com.destroy()


def solos(com) -> list[str]:
    """The registry's list, without what other tests of this module left (a killed server stays listed)."""
    return [n for n in list_vehicles(com) if n.startswith("solo-")]


@pytest.fixture
def drones():
    made: list[IceDrone] = []
    yield made
    for d in made:
        d.close()


def test_vehicles_register_by_name_and_a_jderobot_client_reaches_each(fleet, client):
    sims, vehicles, servers = fleet(3)
    assert [s.config.system_id for s in sims] == [1, 2, 3]
    assert len({s.config.home[:2] for s in sims}) == 3                  # homes of their own
    assert solos(client) == ["solo-1", "solo-2", "solo-3"]
    for i in (1, 2, 3):
        assert vehicles[i - 1].wait_for(lambda s: s.connected, 10)
        pose = jderobot.Pose3DPrx.checkedCast(client.stringToProxy(f"Pose3D@solo-{i}"))   # JdeRobot's Slice
        assert pose is not None and pose.getPose3DData().h == 1.0
        nav = jderobot.NavdataPrx.checkedCast(client.stringToProxy(f"Navdata@solo-{i}"))
        assert nav.getNavdata().vehicle == 1
        status = mavlinkserver.VehiclePrx.checkedCast(client.stringToProxy(f"Vehicle@solo-{i}")).getStatus(-1, -1)
        assert status.systemId == i                                      # each name reaches its own vehicle
    # steering one by name moves that one only
    extra = jderobot.ArDroneExtraPrx.checkedCast(client.stringToProxy("Extra@solo-2"))
    extra.takeoff()
    assert vehicles[1].wait_for(lambda s: s.armed, 30)
    assert not vehicles[0].state().armed and not vehicles[2].state().armed


def test_a_server_stopped_cleanly_leaves_the_registry_and_names_are_not_taken_over(fleet, lab, client):
    _, vehicles, servers = fleet(2)
    assert solos(client) == ["solo-1", "solo-2"]
    props = default_properties([f"--Ice.Default.Locator={lab.locator}", "--MAVLinkServer.Name=solo-2"])
    with pytest.raises(ServeError, match="already registered and answering"):   # another drone, the same name
        IceServer(vehicles[0], props).start()
    assert vehicles[1].wait_for(lambda s: s.connected, 10)
    assert mavlinkserver.VehiclePrx.checkedCast(client.stringToProxy("Vehicle@solo-2")).getStatus(-1, -1) \
        .systemId == 2                                                   # still the second vehicle
    servers[0].close()
    assert solos(client) == ["solo-2"]
    with pytest.raises(Ice.LocalException):                              # its adapter is gone too
        client.stringToProxy("Pose3D@solo-1").ice_ping()
    client.stringToProxy("Pose3D@solo-2").ice_ping()


class Observer(mavlinkserver.Telemetry):
    """A subscriber as a student's program would write it: it only collects what is published."""

    def __init__(self):
        self.statuses, self.poses, self.navdatas, self.events, self.payloads = [], [], [], [], []
        self.lock = threading.Lock()

    def status(self, vehicle, status, current=None):
        with self.lock:
            self.statuses.append((vehicle, status))

    def pose(self, vehicle, published, pose, current=None):
        with self.lock:
            self.poses.append((vehicle, published, pose))

    def navdata(self, vehicle, data, current=None):
        with self.lock:
            self.navdatas.append((vehicle, data))

    def event(self, vehicle, e, current=None):
        with self.lock:
            self.events.append((vehicle, e))

    def payload(self, vehicle, p, current=None):
        with self.lock:
            self.payloads.append((vehicle, p))


def test_observers_subscribe_instead_of_polling(fleet, lab, client, drones):
    _, vehicles, servers = fleet(2)
    extension = servers[0]._table["Vehicle"]
    watchers = [IceDrone.for_vehicle(lab.address, "solo-1").start() for _ in range(3)]
    drones.extend(watchers)
    adapter = client.createObjectAdapterWithEndpoints("Observer", "tcp -h 127.0.0.1")
    observer = Observer()
    t = topic(client, TOPIC_MANAGER, "solo-1")
    t.subscribeAndGetPublisher({}, adapter.addWithUUID(observer).ice_oneway())
    adapter.activate()

    assert eventually(lambda: all(w.publications > 2 and w.state().connected for w in watchers), 20)
    polls = extension.status_calls
    published = min(w.publications for w in watchers)
    assert eventually(lambda: min(w.publications for w in watchers) > published + 10, 10)
    assert extension.status_calls == polls                   # nobody polled the server meanwhile
    assert all(w.state().system_id == 1 for w in watchers)

    assert vehicles[0].set_mode("GUIDED").result(10).ok
    assert eventually(lambda: any(e.kind == "mode" and e.text == "GUIDED" for _, e in observer.events), 10)
    assert all(w.wait_for(lambda s: s.mode == "GUIDED", 5) for w in watchers)
    with observer.lock:
        assert {v for v, *_ in observer.statuses + observer.poses + observer.navdatas} == {"solo-1"}   # its topic
        assert observer.poses and observer.navdatas and observer.statuses
        assert observer.statuses[-1][1].link.status == "OK"
    # the camera on the vehicle rides along (issue 23): the gimbal as the vehicle reports it, straight down
    assert eventually(lambda: observer.payloads and observer.payloads[-1][1].hasPitch, 10)
    assert all(w.wait_for(lambda s: s.gimbal.pitch_deg == -90.0, 10) for w in watchers)


def test_a_killed_server_goes_stale(lab, client, drones, tmp_path):
    """A server that dies without a word (kill -9): the registry still lists it, its watchers see it LOST."""
    server = subprocess.Popen([sys.executable, "-m", "driver", "--sim", "--sim-speedup", "4", "--daemon",
                               "--no-log", "--registry", lab.address, "--name", "crash-1"],
                              cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        assert eventually(lambda: "crash-1" in list_vehicles(client), 30), server.stdout.read1() if \
            server.poll() is not None else "not registered"
        watcher = IceDrone.for_vehicle(lab.address, "crash-1").start()
        drones.append(watcher)
        assert eventually(lambda: watcher.publications > 0 and watcher.state().connected, 20)
        server.send_signal(signal.SIGKILL)
        server.wait(10)
        assert eventually(lambda: watcher.state().link.status is LinkStatus.LOST, 10)
        assert "crash-1" in list_vehicles(client)                      # what the registry cannot know
        assert any("lost the server" in m.text for m in watcher.state().messages)
    finally:
        if server.poll() is None:
            server.kill()
            server.wait(10)
        if server.stdout is not None:
            server.stdout.close()


def test_sim_count_gives_vehicles_with_their_own_ids_homes_and_ports(vehicle_factory):
    from driver.sim.__main__ import configure_fleet, parser
    from ice_fixtures import free_port
    port = free_port()
    sims = configure_fleet(parser().parse_args(["--count", "3", "--tcp", f"127.0.0.1:{port}", "--speedup", "4"]))
    try:
        for sim in sims:
            sim.start()
        assert [s.tcp_port for s in sims] == [port, port + 1, port + 2]
        drivers = [vehicle_factory(f"tcp:127.0.0.1:{s.tcp_port}") for s in sims]
        for i, d in enumerate(drivers):
            assert d.wait_for(lambda s: s.connected and s.home is not None, 15)
            assert d.state().system_id == i + 1
        lons = [d.state().home.lon for d in drivers]
        assert lons[0] < lons[1] < lons[2]                                 # in a row, eastwards
    finally:
        for sim in sims:
            sim.stop()
    with pytest.raises(SystemExit):
        parser().parse_args(["--count", "0"])


def test_a_lab_over_tls_serves_only_certificate_holders(tmp_path, vehicle, drones):
    """The registry, IceStorm and the vehicle's server all ask for a certificate from our CA (docs/fleet.md)."""
    from driver.ice import certs
    from driver.ice.fleet import IceFleet
    from driver.ice.lab import Lab
    from driver.ice.registry import RegistryError
    from driver.ice.server import IceServer, default_properties
    from ice_fixtures import free_port
    directory = str(tmp_path / "certs")
    certs.make_certs(directory, ["127.0.0.1"])
    with Lab(port=free_port(), certs=directory) as lab:
        server = IceServer(vehicle, default_properties([
            f"--Ice.Default.Locator={lab.locator}", "--MAVLinkServer.Name=tls-1",
            f"--MAVLinkServer.Certs={directory}"])).start()
        try:
            fleet = IceFleet(lab.address, certs=directory).start()
            try:
                assert fleet.wait_listed(10) and eventually(lambda: fleet.names() == ("tls-1",), 10)
                d = fleet.drone("tls-1")
                assert eventually(lambda: d.publications > 2 and d.state().connected, 20)   # IceStorm over TLS
            finally:
                fleet.close()
            stranger = Ice.initialize([f"--Ice.Default.Locator={lab.locator}", "--Ice.Plugin.IceSSL=IceSSL:createIceSSL",
                                       "--IceSSL.VerifyPeer=0"])
            try:
                with pytest.raises(RegistryError):                      # no certificate: not even the list
                    list_vehicles(stranger)
            finally:
                stranger.destroy()
        finally:
            server.close()


def test_python_m_driver_registry_runs_the_lab_until_sigterm(lab):
    from ice_fixtures import free_port
    port = free_port()
    refused = subprocess.run([sys.executable, "-m", "driver", "registry", "--host", "10.1.1.5", "--port", str(port)],
                             cwd=ROOT, capture_output=True, text=True, timeout=30)
    assert refused.returncode == 1 and "refusing to serve the IceGrid registry on 10.1.1.5" in refused.stderr
    proc = subprocess.Popen([sys.executable, "-m", "driver", "registry", "--port", str(port)], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        assert f"IceGrid registry on 127.0.0.1:{port} with IceStorm" in proc.stdout.readline()
        com = Ice.initialize([f"--Ice.Default.Locator=IceGrid/Locator:tcp -h 127.0.0.1 -p {port}"])
        try:
            assert list_vehicles(com) == []
            com.stringToProxy(TOPIC_MANAGER).ice_ping()                   # IceStorm, found through the registry
        finally:
            com.destroy()
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(15) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
        proc.stdout.close()


def test_without_icestorm_the_registry_still_names_vehicles_and_watchers_poll(vehicle, drones):
    from driver.ice.lab import Lab
    from ice_fixtures import free_port
    with Lab(port=free_port(), icestorm=False) as lab:
        server = IceServer(vehicle, default_properties([f"--Ice.Default.Locator={lab.locator}",
                                                        "--MAVLinkServer.Name=alone-1"])).start()
        try:
            assert server.publisher is not None and not server.publisher.connected   # said once, tries again
            watcher = IceDrone.for_vehicle(lab.address, "alone-1").start()
            drones.append(watcher)
            assert eventually(lambda: watcher.state().connected and watcher.state().system_id == 1, 15)
            calls = server._table["Vehicle"].status_calls
            assert eventually(lambda: server._table["Vehicle"].status_calls > calls + 5, 10)   # it polls
            assert watcher.publications == 0
        finally:
            server.close()
