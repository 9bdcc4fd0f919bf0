"""Only the pilot flies it (issue 10): Ice off loopback only over TLS with our client certificate, and what
an Ice client may ask is less than what the console may (no forced arm, no forced disarm in flight unless
the server allows the emergency stop, an allow-list of modes, go-to and takeoff limits, small requests).

Real sockets, the real driver and the simulated vehicle; the certificates are made once per session."""
from __future__ import annotations

import fcntl
import ipaddress
import logging
import math
import os
import socket
import stat
import struct
import subprocess
import sys
import time

import Ice
import pytest
from cryptography import x509
from cryptography.hazmat.primitives.serialization import pkcs12

from driver.ice import certs
from driver.ice.client import CLIENT_MESSAGE_KB, IceDrone, viewer_properties
from driver.ice.server import (DEFAULT_PORTS, IceServer, ServeError, check_exposure, default_endpoints,
                               default_properties)
from driver.vehicle.state import CommandStatus

from ice_fixtures import communicator, eventually, free_port, jderobot, mavlinkserver, server_factory  # noqa: F401

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SECURE_HOST = "127.0.0.2"          # a loopback address of its own: TLS there, plain TCP stays on 127.0.0.1


@pytest.fixture(scope="session")
def cert_dir(tmp_path_factory) -> str:
    """The project's CA, a server certificate for SECURE_HOST and the pilot's certificate (EC P-256: ~20 ms)."""
    directory = str(tmp_path_factory.mktemp("certs"))
    certs.make_certs(directory, [SECURE_HOST])
    return directory


@pytest.fixture(scope="session")
def stranger_dir(tmp_path_factory) -> str:
    """Another CA's certificates: a pilot certificate that is not ours."""
    directory = str(tmp_path_factory.mktemp("stranger"))
    certs.make_certs(directory, [SECURE_HOST])
    return directory


@pytest.fixture
def ssl_server(vehicle):
    """The driver served as ``python -m driver --host 127.0.0.2 --certs DIR`` would, on one free port."""
    servers = []

    def make(directory: str, **properties) -> tuple[IceServer, int]:
        port = free_port()
        props = default_properties([f"--MAVLinkServer.Host={SECURE_HOST}", f"--MAVLinkServer.Certs={directory}"]
                                   + [f"--{k}={v}" for k, v in properties.items()])
        props.setProperty("MAVLinkServer.Endpoints", default_endpoints(props, port))
        server = IceServer(vehicle, props).start()
        servers.append(server)
        return server, port

    yield make
    for server in servers:
        server.close()


@pytest.fixture
def clients():
    """Client communicators with the given properties; destroyed after the test."""
    made = []

    def make(**properties) -> Ice.Communicator:
        com = Ice.initialize([f"--{k}={v}" for k, v in properties.items()] + ["--Ice.Default.InvocationTimeout=5000"])
        made.append(com)
        return com

    yield make
    for com in made:
        com.destroy()


def ssl_client_properties(directory: str, with_certificate: bool = True) -> dict[str, str]:
    props = certs.ssl_properties(directory, "client")
    if not with_certificate:
        del props["IceSSL.CertFile"]
    return props


def pilot_drone(directory: str, port: int, **kwargs) -> IceDrone:
    """The viewer's client with --ice-certs, every proxy over ssl to SECURE_HOST only."""
    props = viewer_properties(certs=directory)
    for name in DEFAULT_PORTS:
        props.setProperty(f"UAVViewer.{name}.Proxy", f"{name}:ssl -h {SECURE_HOST} -p {port}")
    return IceDrone(props, **kwargs).start()


def until(vehicle, sim, condition, timeout: float):
    """The simulated vehicle's truth once ``condition(truth)`` holds, else None."""
    if vehicle.wait_for(lambda s: condition(sim.truth()), timeout) is None:
        return None
    return sim.truth()


def refused(call) -> Ice.Exception:
    """The Ice exception ``call()`` ends in: refused, not timed out."""
    with pytest.raises(Ice.LocalException) as caught:
        call()
    assert not isinstance(caught.value, Ice.TimeoutException), caught.value
    return caught.value


# -- certificates --------------------------------------------------------------------------------
def test_certs_files_modes_names_and_the_ca_is_kept(tmp_path):
    directory = str(tmp_path / "c")
    victim = tmp_path / "victim"
    victim.write_bytes(b"not a key")
    started = time.perf_counter()
    made = certs.make_certs(directory, ["10.1.1.10", "solo.local"])
    elapsed = time.perf_counter() - started
    assert not made.ca_reused and made.hosts == ("10.1.1.10", "solo.local", "127.0.0.1", "localhost")
    modes = {name: stat.S_IMODE(os.lstat(os.path.join(directory, name)).st_mode) for name in os.listdir(directory)}
    assert modes == {"ca.pem": 0o644, "truststore.p12": 0o644, "ca-key.pem": 0o600, "server.p12": 0o600,
                     "client.p12": 0o600, "password.txt": 0o600}, modes
    assert stat.S_IMODE(os.stat(directory).st_mode) == 0o700
    password = certs.read_password(directory).encode()
    server = pkcs12.load_pkcs12(open(os.path.join(directory, "server.p12"), "rb").read(), password)
    sans = server.cert.certificate.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
    assert {str(ip) for ip in sans.get_values_for_type(x509.IPAddress)} == {"10.1.1.10", "127.0.0.1"}
    assert set(sans.get_values_for_type(x509.DNSName)) == {"solo.local", "localhost"}
    ca_pem = open(os.path.join(directory, "ca.pem"), "rb").read()
    ca = x509.load_pem_x509_certificate(ca_pem)
    first_client = pkcs12.load_pkcs12(open(os.path.join(directory, "client.p12"), "rb").read(), password)
    first_client.cert.certificate.verify_directly_issued_by(ca)

    # again, with a symlink planted where a key goes: the CA stays (issued certificates stay valid), the
    # symlink is replaced, never followed
    os.unlink(os.path.join(directory, "client.p12"))
    os.symlink(victim, os.path.join(directory, "client.p12"))
    again = certs.make_certs(directory, ["10.1.1.10"])
    assert again.ca_reused and open(os.path.join(directory, "ca.pem"), "rb").read() == ca_pem
    assert victim.read_bytes() == b"not a key"
    assert stat.S_ISREG(os.lstat(os.path.join(directory, "client.p12")).st_mode)
    assert certs.read_password(directory).encode() == password             # the same password, kept
    client = pkcs12.load_pkcs12(open(os.path.join(directory, "client.p12"), "rb").read(), password)
    client.cert.certificate.verify_directly_issued_by(ca)

    replaced = certs.make_certs(directory, ["10.1.1.10"], new_ca=True)
    assert not replaced.ca_reused and open(os.path.join(directory, "ca.pem"), "rb").read() != ca_pem
    logging.getLogger(__name__).info("three certificates with EC P-256 keys in %.0f ms", elapsed * 1e3)


# -- TLS with client certificates ------------------------------------------------------------------
def test_only_a_client_with_our_certificate_gets_in_and_flies(vehicle, sim, cert_dir, stranger_dir, ssl_server,
                                                               clients):
    server, port = ssl_server(cert_dir)
    assert f"ssl -h {SECURE_HOST} -p {port}" in server.proxy("Pose3D")
    pose_at = f"Pose3D:ssl -h {SECURE_HOST} -p {port}"

    # no certificate, or one from another CA: the handshake is refused
    anonymous = clients(**ssl_client_properties(cert_dir, with_certificate=False))
    refused(lambda: jderobot.Pose3DPrx.uncheckedCast(anonymous.stringToProxy(pose_at)).getPose3DData())
    stranger = clients(**{**ssl_client_properties(cert_dir),
                          "IceSSL.CertFile": os.path.join(stranger_dir, "client.p12"),
                          "IceSSL.Password": certs.read_password(stranger_dir)})
    refused(lambda: jderobot.Pose3DPrx.uncheckedCast(stranger.stringToProxy(pose_at)).getPose3DData())
    # nor plain TCP on the served address: the server waits for a TLS hello that never comes
    plain = clients()
    with pytest.raises(Ice.LocalException):
        jderobot.Pose3DPrx.uncheckedCast(plain.stringToProxy(f"Pose3D:tcp -h {SECURE_HOST} -p {port}")
                                         .ice_invocationTimeout(500)).getPose3DData()

    # JdeRobot clients on this machine keep plain TCP on 127.0.0.1
    local = jderobot.Pose3DPrx.uncheckedCast(plain.stringToProxy(f"Pose3D:tcp -h 127.0.0.1 -p {port}"))
    assert local.getPose3DData().h == 1

    # the pilot's certificate: the pose, then a takeoff through the extension against the simulator
    pilot = clients(**ssl_client_properties(cert_dir))
    pose = jderobot.Pose3DPrx.uncheckedCast(pilot.stringToProxy(pose_at)).getPose3DData()
    assert pose.h == 1 and math.isfinite(pose.z)
    info = jderobot.Pose3DPrx.uncheckedCast(pilot.stringToProxy(pose_at)).ice_getConnection().getInfo()
    assert isinstance(info, Ice.SSLConnectionInfo) and info.cipher and info.certs, info   # (3.7 leaves .verified False)

    drone = pilot_drone(cert_dir, port)
    try:
        assert drone.wait_for(lambda s: s.connected and s.readiness.ready_to_arm, 20), drone.state().messages
        result = drone.takeoff(3.0).result(timeout=60)
        assert result.status is CommandStatus.ACCEPTED, result
        assert until(vehicle, sim, lambda t: t.armed and t.altitude > 2.5, 10), sim.truth()
        landing = drone.land().result(timeout=10)
        assert landing.status is CommandStatus.ACCEPTED, landing
        assert until(vehicle, sim, lambda t: t.mode == "LAND", 5), sim.truth()
    finally:
        drone.close()


def test_the_client_checks_the_servers_name(vehicle, tmp_path, ssl_server, clients):
    """A server certificate that does not name the address dialled is refused by the pilot's client."""
    local_only = str(tmp_path / "local")
    certs.make_certs(local_only)                                 # 127.0.0.1 and localhost only
    _, port = ssl_server(local_only)
    pilot = clients(**ssl_client_properties(local_only))
    error = refused(lambda: jderobot.Pose3DPrx.uncheckedCast(
        pilot.stringToProxy(f"Pose3D:ssl -h {SECURE_HOST} -p {port}")).getPose3DData())
    assert isinstance(error, Ice.SecurityException) and "mismatch" in str(error), error


def _machine_address() -> str | None:
    """An IPv4 address of this machine other than loopback (SIOCGIFADDR), or None."""
    for _, name in socket.if_nameindex():
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            try:
                packed = fcntl.ioctl(s.fileno(), 0x8915, struct.pack("256s", name.encode()[:15]))
            except OSError:
                continue
        address = socket.inet_ntoa(packed[20:24])
        if not ipaddress.ip_address(address).is_loopback:
            return address
    return None


def test_plain_ice_off_loopback_is_refused_unless_insecure(tmp_path, caplog, cert_dir):
    address = _machine_address()
    if address is None:
        pytest.skip("this machine has no address but loopback")
    done = subprocess.run([sys.executable, "-m", "driver", "--sim", "--no-log", "--daemon", "--host", address],
                          cwd=tmp_path, stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=60,
                          env={**os.environ, "PYTHONPATH": ROOT})
    assert done.returncode == 1, done.stderr
    assert done.stderr.splitlines() == [
        f"refusing to serve Camera (and 7 more interfaces) on {address}:9999 over plain tcp: anyone on that network "
        f"could fly the drone; serve it over TLS with --certs DIR (python -m driver certs DIR --host {address}), or "
        "pass --insecure"], done.stderr

    def props(*args: str):
        return default_properties([f"--MAVLinkServer.Host={address}", *args])
    for args in ([], ["--MAVLinkServer.Endpoints=udp -h 0.0.0.0 -p 9000"], ["--MAVLinkServer.Endpoints=tcp -p 9000"],
                 [f"--MAVLinkServer.Certs={cert_dir}", "--IceSSL.VerifyPeer=0"],
                 [f"--MAVLinkServer.Certs={cert_dir}", f"--MAVLinkServer.Camera.Endpoints=tcp -h {address} -p 9999"]):
        with pytest.raises(ServeError, match="refusing to serve"):
            check_exposure(props(*args))
    with pytest.raises(ServeError, match="not 0.0.0.0"):
        check_exposure(default_properties(["--MAVLinkServer.Host=0.0.0.0", f"--MAVLinkServer.Certs={cert_dir}"]))
    check_exposure(props(f"--MAVLinkServer.Certs={cert_dir}"))      # TLS with client certificates: served
    check_exposure(default_properties([]))                          # 127.0.0.1
    with caplog.at_level(logging.WARNING, logger="driver.ice.server"):
        check_exposure(props("--MAVLinkServer.Insecure=1"))
    assert [r.getMessage() for r in caplog.records] == [
        f"serving Ice over plain tcp on {address} (--insecure): anyone who reaches it can fly the drone"]


# -- what an Ice client may ask --------------------------------------------------------------------
def test_forced_arm_and_modes_outside_the_list_are_refused(vehicle, sim, server_factory, communicator):
    server = server_factory(vehicle)
    narrow = server_factory(vehicle, **{"MAVLinkServer.Modes": "GUIDED, NOSUCH", "MAVLinkServer.MaxAltitude": 10})
    ext = mavlinkserver.VehiclePrx.checkedCast(communicator.stringToProxy(server.proxy("Vehicle")))
    only_guided = mavlinkserver.VehiclePrx.checkedCast(communicator.stringToProxy(narrow.proxy("Vehicle")))
    assert vehicle.wait_for(lambda s: s.connected and s.readiness.ready_to_arm, 15)

    forced = ext.arm(True)
    assert (forced.status, forced.command) == ("REJECTED", "arm (forced)") and "pre-arm" in forced.reason, forced
    assert not sim.truth().armed
    for mode in ("STABILIZE", "ACRO", "AUTO", "alt_hold"):
        answer = ext.setMode(mode)
        assert answer.status == "REJECTED" and "not allowed over Ice" in answer.reason, answer
    assert sim.truth().mode not in ("ACRO", "AUTO", "ALT_HOLD")
    assert ext.setMode("LOITER").status == "ACCEPTED"
    assert until(vehicle, sim, lambda t: t.mode == "LOITER", 5)
    refused_loiter = only_guided.setMode("BRAKE")
    assert refused_loiter.status == "REJECTED" and "GUIDED, LAND" in refused_loiter.reason, refused_loiter
    assert only_guided.setMode("LAND").status == "ACCEPTED"                    # LAND is always allowed
    assert until(vehicle, sim, lambda t: t.mode == "LAND", 5)

    high = only_guided.takeoff(12.0)                                            # MaxAltitude 10
    assert high.status == "REJECTED" and "1 to 10 m" in high.reason, high
    assert only_guided.setTakeoffAltitude(12.0) == -1 and only_guided.setTakeoffAltitude(8.0) == 0
    assert ext.takeoff(121.0).status == "REJECTED"                             # the rules' 120 m by default
    assert not sim.truth().armed


def test_in_flight_forced_disarm_refused_emergency_stop_only_when_allowed(flying, sim, server_factory,
                                                                          communicator):
    plain = server_factory(flying)
    allowing = server_factory(flying, **{"MAVLinkServer.AllowEmergencyDisarm": 1, "MAVLinkServer.MaxDistance": 20})
    ext = mavlinkserver.VehiclePrx.checkedCast(communicator.stringToProxy(plain.proxy("Vehicle")))
    waypoints = jderobot.Pose3DPrx.checkedCast(communicator.stringToProxy(plain.proxy("WP")))

    # go-to limits, while flying: 100 m from home by default, 20 m on the other server
    far = ext.goTo(0.0, 120.0, 5.0)
    assert far.status == "REJECTED" and "at most 100 m" in far.reason, far
    assert waypoints.setPose3DData(jderobot.Pose3DData(120.0, 0.0, 5.0, 1, 1, 0, 0, 0)) == -1   # x east
    assert ext.goTo(0.0, 0.0, 200.0).status == "REJECTED"
    near = ext.goTo(1.0, 0.0, 3.0)
    assert near.status == "ACCEPTED", near
    assert flying.state().mode == "GUIDED"

    for server in (plain, allowing):
        other = mavlinkserver.VehiclePrx.checkedCast(communicator.stringToProxy(server.proxy("Vehicle")))
        answer = other.disarm(True)
        assert answer.status == "REJECTED" and "falls" in answer.reason, answer
    stop = ext.emergencyStop()
    assert stop.status == "REJECTED" and "--allow-emergency-disarm" in stop.reason, stop
    assert sim.truth().armed and sim.truth().altitude > 2.0

    drone = IceDrone(_client_props(allowing)).start()
    try:
        assert drone.wait_for(lambda s: s.connected, 10)
        beyond = drone.go_to(25.0, 0.0, 3.0).result(timeout=10)
        assert beyond.status is CommandStatus.REJECTED and "at most 20 m" in beyond.reason, beyond
        plain_disarm = drone.disarm(force=True).result(timeout=10)
        assert plain_disarm.status is CommandStatus.REJECTED, plain_disarm
        assert sim.truth().armed
        stopped = drone.disarm(force=True, emergency=True).result(timeout=10)
        assert stopped.command == "emergency motor stop" and stopped.status is CommandStatus.ACCEPTED, stopped
        assert until(flying, sim, lambda t: not t.armed, 10), sim.truth()
    finally:
        drone.close()


def _client_props(server: IceServer):
    props = viewer_properties()
    for key, value in server.client_properties().items():
        props.setProperty(key, value)
    return props


def test_oversized_request_refused_without_harming_the_server(vehicle, sim, server_factory, communicator):
    server = server_factory(vehicle)
    drone = IceDrone(_client_props(server)).start()
    try:
        assert drone.wait_for(lambda s: s.connected, 10)
        mode = sim.truth().mode
        ext = mavlinkserver.VehiclePrx.checkedCast(communicator.stringToProxy(server.proxy("Vehicle")))
        refused(lambda: ext.setMode("GUIDED" + " " * 100_000))                   # > 64 KB: the connection goes
        assert ext.getStatus(-1, -1).mode == mode                                  # a new one is served
        answered = drone.state().time
        assert drone.wait_for(lambda s: s.connected and s.time > answered, 5)   # the pilot's client never noticed
        assert sim.truth().mode == mode
    finally:
        drone.close()


def test_client_takes_a_full_hd_frame_and_refuses_a_larger_one(vehicle, server_factory, clients):
    """The viewer's Ice.MessageSizeMax: a 1920x1080 RGB8 frame fits; a larger one fails that call only."""
    frames = {}
    for width, height in ((1920, 1080), (2048, 1152)):
        server = server_factory(vehicle, **{"MAVLinkServer.Camera.Uri": "sim", "MAVLinkServer.Camera.Width": width,
                                            "MAVLinkServer.Camera.Height": height})
        frames[width] = server.proxy("Camera")
    props = viewer_properties()
    assert props.getPropertyAsInt("Ice.MessageSizeMax") == CLIENT_MESSAGE_KB
    init = Ice.InitializationData()
    init.properties = props
    viewer = Ice.initialize(init)
    try:
        full_hd = jderobot.CameraPrx.uncheckedCast(viewer.stringToProxy(frames[1920]).ice_invocationTimeout(5000))
        image = eventually(lambda: _image(full_hd), 15)
        assert image is not None and len(image.pixelData) == 1920 * 1080 * 3
        larger = jderobot.CameraPrx.uncheckedCast(viewer.stringToProxy(frames[2048]).ice_invocationTimeout(5000))
        with pytest.raises(Ice.MemoryLimitException):
            eventually(lambda: _image(larger), 15)
        assert len(full_hd.getImageData("RGB8").pixelData) == 1920 * 1080 * 3       # the same client goes on
    finally:
        viewer.destroy()


def _image(camera):
    """The camera's image, or None while it has none yet."""
    try:
        return camera.getImageData("RGB8")
    except jderobot.DataNotExistException:
        return None


def test_the_viewer_reaches_the_servers_camera_over_tls_with_the_pilots_certificate(cert_dir, ssl_server,
                                                                                     monkeypatch):
    """main.py --ice-certs puts the IceSSL properties where every ``ice:`` camera of the viewer finds them."""
    from driver.camera import open_source
    from driver.ice import camera_source as ice_source
    server, port = ssl_server(cert_dir, **{"MAVLinkServer.Camera.Uri": "sim"})
    monkeypatch.setattr(ice_source, "client_properties", {})
    src = open_source(f"ice:Camera:ssl -h {SECURE_HOST} -p {port}")
    try:
        assert eventually(lambda: src.status().attempts >= 2 and src.status().reason, 10), src.status()
        assert "unreachable" in src.status().reason and src.latest() is None
    finally:
        src.close(wait=3)
    monkeypatch.setattr(ice_source, "client_properties", ssl_client_properties(cert_dir))
    src = open_source(f"ice:Camera:ssl -h {SECURE_HOST} -p {port}")
    try:
        frame = eventually(src.latest, 10)
        assert frame is not None and frame.width > 0, src.status()
    finally:
        src.close(wait=3)
