"""The MAVLinkServer's Ice side: JdeRobot identities and ports, configured by Ice properties.

Defaults are the 2017 server's: ``Camera`` 9999, ``Pose3D`` 9998, ``CMDVel``
9997, ``Navdata`` 9996, ``Extra`` 9995, waypoint ``WP`` 9994, plus our extension
``Vehicle`` 9993, each on its own port and bound to 127.0.0.1. Properties
(``config/server.cfg`` is the example):

- ``MAVLinkServer.Host``: the address every default endpoint binds (127.0.0.1)
- ``MAVLinkServer.<Interface>.Endpoints`` / ``.Name``: endpoints and identity of one interface
- ``MAVLinkServer.Endpoints``: if set, every interface on this one adapter (JdeRobot's Gazebo style, port 9000)
- ``MAVLinkServer.TakeoffAltitude``, ``MAVLinkServer.CMDVel.Xmax/Ymax/Zmax/Yawmax/RefuseAbove``,
  ``MAVLinkServer.Navdata.Vehicle``
- ``MAVLinkServer.Camera.*``: handed to the camera servant (see :func:`make_camera_servant`);
  ``Camera.RecordDir`` defaults to :func:`driver.core.files.default_record_dir`
- ``MAVLinkServer.Certs``: a folder made by ``python -m driver certs``; every default endpoint is then
  ``ssl -h <Host>`` (clients must show a certificate from that CA) plus plain ``tcp -h 127.0.0.1`` on the
  same port for JdeRobot clients on this machine
- ``MAVLinkServer.Insecure``: 1 lets plain TCP/UDP endpoints bind a non-loopback address (refused otherwise)
- ``MAVLinkServer.Modes``, ``MaxDistance``, ``MaxAltitude``, ``AllowEmergencyDisarm``: what an Ice client may
  ask (see :func:`settings_from`)
- ``MAVLinkServer.Name`` with ``Ice.Default.Locator`` (``--registry HOST:PORT --name solo-1``): a fleet
  (docs/fleet.md). Every interface on one adapter whose adapter id is the name (port 0 unless
  ``MAVLinkServer.Endpoints``), registered with the IceGrid registry with a well-known object; telemetry
  published on the IceStorm topic of that name (``MAVLinkServer.Publish.Rate``, Hz, default 10; 0: none;
  ``MAVLinkServer.TopicManager.Proxy``)
"""
from __future__ import annotations

import ipaddress
import logging
import os
import re
import shlex
import socket
import sys
from dataclasses import dataclass

import Ice

from ..vehicle.api import Drone
from ..vehicle.rules import COPTER_MODES, MAX_ALTITUDE
from ..core.files import default_record_dir
from . import certs, servants
from .problems import ice_problem
from .servants import ICE_MODES, ServerSettings
from .shots import ShotsI

log = logging.getLogger(__name__)

PREFIX = "MAVLinkServer."
DEFAULT_PORTS = {"Camera": 9999, "Pose3D": 9998, "CMDVel": 9997, "Navdata": 9996, "Extra": 9995, "WP": 9994,
                 "Vehicle": 9993, "Shots": 9992}
ONE_PORT = 9000                                         # JdeRobot's Gazebo drone served everything here
SECURE_TRANSPORTS = ("ssl", "wss")
WILDCARDS = ("", "*", "0.0.0.0", "::", "[::]")
#: KB. The server only receives requests, the largest a setMode name or a Pose3DData (well under 1 KB); a
#: client sending more loses its connection at once and the server goes on (replies, images too, are not limited)
SERVER_MESSAGE_KB = 64


class ServeError(RuntimeError):
    """An interface cannot be served (port taken, bad endpoint, unknown host), said in one line."""


def _where(endpoints: str) -> str:
    """``default -h 127.0.0.1 -p 9000`` → ``127.0.0.1:9000``; other endpoint strings as they are."""
    host = re.findall(r"-h\s+(\S+)", endpoints)
    port = re.findall(r"-p\s+(\d+)", endpoints)
    return f"{host[0]}:{port[0]}" if len(host) == len(port) == 1 else repr(endpoints)


def default_properties(args: list[str] | None = None) -> Ice.Properties:
    """Ice properties from ``--Ice.Config=FILE`` and ``--Ice.*``/``--MAVLinkServer.*`` options in ``args``.

    Options it understands are removed from ``args`` (a list, changed in place).
    """
    args = args if args is not None else []
    props = Ice.createProperties(args)
    rest = props.parseCommandLineOptions("MAVLinkServer", args)
    args[:] = rest
    if not props.getProperty("Ice.MessageSizeMax"):
        props.setProperty("Ice.MessageSizeMax", str(SERVER_MESSAGE_KB))
    # Servants never block (commands are AMD) and Python runs one dispatch at a time anyway: every extra
    # thread only adds contention with the driver's flight threads. One thread, a second one while a dispatch
    # is slow (a camera frame). bench/bench_ice_flood.py: with 2/8 a flood of 4 clients costs the setpoint
    # stream 3 % of its rate and 12 % on the p95 interval; with 1/2 1 % and 5 %, and answers 60 % more calls.
    if not props.getProperty("Ice.ThreadPool.Server.SizeMax"):
        props.setProperty("Ice.ThreadPool.Server.Size", "1")
        props.setProperty("Ice.ThreadPool.Server.SizeMax", "2")
    return props


def settings_from(props: Ice.Properties, limits=None) -> ServerSettings:
    """Servant settings; CMDVel clamps default to the driver's own limits."""
    d = ServerSettings()
    h = limits.horizontal if limits else d.cmdvel_max[0]
    v = limits.vertical if limits else d.cmdvel_max[2]
    y = limits.yaw_rate if limits else d.cmdvel_max[3]

    def number(key: str, default: float) -> float:
        text = props.getProperty(PREFIX + key)
        try:
            return float(text) if text else default
        except ValueError:
            log.warning("%s%s=%r is not a number; using %s", PREFIX, key, text, default)
            return default

    max_altitude = number("MaxAltitude", d.max_altitude)
    if not 0 < max_altitude <= MAX_ALTITUDE:
        log.warning("%sMaxAltitude=%g: must be above 0 and at most %g m; using %g", PREFIX, max_altitude,
                    MAX_ALTITUDE, min(d.max_altitude, MAX_ALTITUDE))
        max_altitude = min(d.max_altitude, MAX_ALTITUDE)
    max_distance = number("MaxDistance", d.max_distance)
    if not max_distance > 0:
        log.warning("%sMaxDistance=%g: must be above 0; using %g", PREFIX, max_distance, d.max_distance)
        max_distance = d.max_distance
    takeoff_altitude = number("TakeoffAltitude", d.takeoff_altitude)
    if takeoff_altitude > max_altitude:
        log.warning("%sTakeoffAltitude=%g is above %sMaxAltitude; taking off to %g m", PREFIX, takeoff_altitude,
                    PREFIX, max_altitude)
        takeoff_altitude = max_altitude
    return ServerSettings(
        takeoff_altitude=takeoff_altitude,
        cmdvel_max=(number("CMDVel.Xmax", h), number("CMDVel.Ymax", h), number("CMDVel.Zmax", v),
                    number("CMDVel.Yawmax", y)),
        cmdvel_refuse_above=number("CMDVel.RefuseAbove", d.cmdvel_refuse_above),
        navdata_vehicle=int(number("Navdata.Vehicle", d.navdata_vehicle)),
        max_altitude=max_altitude,
        max_distance=max_distance,
        allowed_modes=allowed_modes(props.getProperty(PREFIX + "Modes")),
        allow_emergency_disarm=props.getPropertyAsInt(PREFIX + "AllowEmergencyDisarm") > 0,
    )


def allowed_modes(text: str) -> frozenset[str]:
    """``MAVLinkServer.Modes`` ("GUIDED, LOITER ...") as mode names; LAND is always in (the way down)."""
    if not text.strip():
        return ICE_MODES
    names = {n.upper() for n in re.split(r"[\s,]+", text) if n}
    unknown = sorted(names - set(COPTER_MODES))
    if unknown:
        log.warning("%sModes: unknown mode %s ignored", PREFIX, ", ".join(unknown))
    return frozenset((names & set(COPTER_MODES)) | {"LAND"})


def make_camera_servant(props: Ice.Properties, vehicle: Drone):
    """The Camera servant: ``driver.ice.camera.CameraI(config, vehicle)`` when a source is configured.

    ``config`` is a dict of the ``MAVLinkServer.Camera.*`` properties with the
    prefix removed (``{"Uri": "0", ...}``), with ``RecordDir`` defaulting to
    :func:`default_record_dir`. Without a ``Uri``, without the camera
    module, or if it fails, a servant that answers DataNotExistException saying why.
    """
    prefix = PREFIX + "Camera."
    config = {k[len(prefix):]: v for k, v in props.getPropertiesForPrefix(prefix).items()}
    if not config.get("RecordDir", "").strip():
        config["RecordDir"] = default_record_dir()
    if not config.get("Uri", "").strip():
        return servants.NoCameraI(f"no camera source configured yet (set {prefix}Uri)")
    try:
        from .camera import CameraI
    except ModuleNotFoundError as exc:
        log.warning("camera servant unavailable: %s", exc)
        return servants.NoCameraI(f"camera servant unavailable: {exc}")
    try:
        return CameraI(config, vehicle)
    except Exception as exc:
        log.warning("camera failed to start: %s", exc)
        return servants.NoCameraI(f"camera failed: {exc}")


def default_endpoints(props: Ice.Properties, port: int) -> str:
    """The endpoints of an interface on ``port`` at ``MAVLinkServer.Host``: plain ``default`` without
    ``MAVLinkServer.Certs``; with it ``ssl`` there, plus plain TCP on 127.0.0.1 for JdeRobot clients on this
    machine (unless the host is 127.0.0.1 itself, whose port the ``ssl`` endpoint then holds)."""
    host = props.getPropertyWithDefault(PREFIX + "Host", "127.0.0.1").strip()
    h = f'"{host}"' if ":" in host else host
    if not props.getProperty(PREFIX + "Certs"):
        return f"default -h {h} -p {port}"
    if host in WILDCARDS:
        raise ServeError(f"with --certs, --host names the address remote viewers reach (such as 10.1.1.10), not "
                         f"{host or 'all interfaces'}: that would also take 127.0.0.1's ports, which stay plain TCP "
                         "for JdeRobot clients on this machine")
    ssl = f"ssl -h {h} -p {port}"
    return ssl if host in ("127.0.0.1", "localhost") else f"{ssl}:tcp -h 127.0.0.1 -p {port}"


def fleet_name(props: Ice.Properties) -> str:
    """The vehicle's name in a fleet: ``MAVLinkServer.Name`` when a locator (the lab's registry) is set, else ""."""
    name = props.getProperty(PREFIX + "Name").strip()
    return name if name and props.getProperty("Ice.Default.Locator") else ""


def planned_endpoints(props: Ice.Properties) -> dict[str, tuple[str, str]]:
    """``{interface: (identity, endpoints)}`` from the properties; equal endpoints share one adapter (in a fleet
    all share one, on a port of the system's choosing unless ``MAVLinkServer.Endpoints`` says)."""
    shared = props.getProperty(PREFIX + "Endpoints") or (default_endpoints(props, 0) if fleet_name(props) else "")
    return {name: (props.getPropertyWithDefault(f"{PREFIX}{name}.Name", name),
                   shared or props.getProperty(f"{PREFIX}{name}.Endpoints") or default_endpoints(props, port))
            for name, port in DEFAULT_PORTS.items()}


def _endpoint_parts(endpoints: str, props: Ice.Properties) -> list[tuple[str, str, str]]:
    """``[(transport, host, text)]`` of an endpoint list; a part without ``-h`` binds Ice.Default.Host or,
    without it, every interface ("")."""
    parts, current, quoted = [], "", False
    for c in endpoints:
        if c == '"':
            quoted = not quoted
        if c == ":" and not quoted:
            parts.append(current)
            current = ""
        else:
            current += c
    parts.append(current)
    found = []
    for text in (p.strip() for p in parts):
        if not text:
            continue
        try:
            words = shlex.split(text)
        except ValueError:
            words = text.split()
        transport = words[0].lower() if words else ""
        if transport == "default":
            transport = props.getPropertyWithDefault("Ice.Default.Protocol", "tcp").lower()
        host = props.getProperty("Ice.Default.Host")
        for i, word in enumerate(words[:-1]):
            if word == "-h":
                host = words[i + 1]
        found.append((transport, host.strip(), text))
    return found


def is_loopback(host: str) -> bool:
    """Only this machine can reach ``host``: a loopback address, or a name that resolves to nothing else."""
    if host in WILDCARDS:
        return False
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        pass
    try:
        infos = socket.getaddrinfo(host, None)
    except OSError:
        return False
    return bool(infos) and all(ipaddress.ip_address(i[4][0].split("%")[0]).is_loopback for i in infos)


def exposure_problem(what: str, endpoints: str, props: Ice.Properties, warnings: list[str] | None = None) -> str | None:
    """Why serving ``endpoints`` would let anyone on a network fly the drone, or None.

    Off loopback only ``ssl``/``wss`` that ask every client for a certificate from the configured CA
    (IceSSL.VerifyPeer=2 and IceSSL.CAs, not the platform's CAs); plain transports only with
    ``MAVLinkServer.Insecure=1`` (``--insecure``), and then with a warning added to ``warnings``.
    """
    insecure = props.getPropertyAsInt(PREFIX + "Insecure") > 0
    for transport, host, text in _endpoint_parts(endpoints, props):
        if is_loopback(host):
            continue
        where = _where(text) if host else f"every interface ({text})"
        if transport not in SECURE_TRANSPORTS:
            if not insecure:
                return (f"refusing to serve {what} on {where} over plain {transport}: anyone on that network could "
                        f"fly the drone; serve it over TLS with --certs DIR (python -m driver certs DIR --host "
                        f"{'ADDRESS' if host in WILDCARDS else host}), or pass --insecure")
            if warnings is not None:
                warnings.append(f"serving Ice over plain {transport} on {host or 'every interface'} (--insecure): "
                                "anyone who reaches it can fly the drone")
            continue
        verified = props.getPropertyAsIntWithDefault("IceSSL.VerifyPeer", 2) >= 2 and \
            bool(props.getProperty("IceSSL.CAs")) and props.getPropertyAsInt("IceSSL.UsePlatformCAs") <= 0
        if not verified:
            if not insecure:
                return (f"refusing to serve {what} on {where} over {transport} without requiring a client "
                        "certificate from our CA (IceSSL.VerifyPeer=2, IceSSL.CAs): use --certs DIR, or pass "
                        "--insecure")
            if warnings is not None:
                warnings.append(f"serving Ice over {transport} on {host or 'every interface'} without client "
                                "certificates (--insecure): anyone who reaches it can fly the drone")
    return None


def check_exposure(props: Ice.Properties) -> None:
    """ServeError unless every planned endpoint is loopback, authenticated TLS, or allowed by --insecure; with
    ``MAVLinkServer.Certs``, the IceSSL keys are set first. Cheap: callers run it before starting anything."""
    apply_certs(props)
    planned = planned_endpoints(props)
    warnings: list[str] = []
    failing = [name for name, (_, endpoints) in planned.items() if exposure_problem(name, endpoints, props, warnings)]
    if failing:
        first = failing[0]
        shared = len({e for _, e in planned.values()}) == 1
        what = ("the Ice interfaces" if shared else first if len(failing) == 1
                else f"{first} (and {len(failing) - 1} more interfaces)")
        raise ServeError(exposure_problem(what, planned[first][1], props))
    for text in dict.fromkeys(warnings):
        log.warning("%s", text)


def apply_certs(props: Ice.Properties) -> None:
    """``MAVLinkServer.Certs=DIR``: IceSSL with the server's certificate, every client must show one of ours.
    Keys already set (an Ice.Config file, --IceSSL.*) win."""
    directory = props.getProperty(PREFIX + "Certs").strip()
    if not directory:
        return
    try:
        wanted = certs.ssl_properties(directory, "server")
    except certs.CertError as exc:
        raise ServeError(str(exc)) from None
    for key, value in wanted.items():
        if not props.getProperty(key):
            props.setProperty(key, value)


@dataclass(frozen=True)
class Served:
    name: str            # the interface's role: Pose3D, WP, ...
    identity: str
    proxy: str           # a stringified proxy a client can use


class IceServer:
    """Serves one :class:`~driver.vehicle.api.Drone` on JdeRobot's interfaces; start(), then close()."""

    def __init__(self, vehicle: Drone, properties: Ice.Properties | None = None, camera=None):
        self.vehicle = vehicle
        self.properties = properties if properties is not None else default_properties()
        self.settings = settings_from(self.properties, getattr(vehicle, "limits", None))
        self.communicator: Ice.Communicator | None = None
        self.camera = camera
        self._adapters: list[Ice.ObjectAdapter] = []
        self._table: dict[str, Ice.Object] = {}
        self.served: dict[str, Served] = {}
        self.name = fleet_name(self.properties)       # in a fleet: the vehicle's adapter id and topic
        self.publisher = None
        self._announced = False
        # each snapshot converted once for every servant and the IceStorm publisher
        self.snapshots = servants.Snapshots(self.vehicle, self.settings)

    def _servants(self) -> dict[str, Ice.Object]:
        if self.camera is None:
            self.camera = make_camera_servant(self.properties, self.vehicle)
        v, s, shared = self.vehicle, self.settings, self.snapshots
        return {"Camera": self.camera, "Pose3D": servants.Pose3DI(v, "Pose3D", s, shared),
                "CMDVel": servants.CMDVelI(v, s), "Navdata": servants.NavdataI(v, s, shared),
                "Extra": servants.ArDroneExtraI(v, s, self.camera), "WP": servants.Pose3DI(v, "WP", s, shared),
                "Vehicle": servants.VehicleI(v, s), "Shots": ShotsI(v)}

    def start(self) -> "IceServer":
        check_exposure(self.properties)
        init = Ice.InitializationData()
        init.properties = self.properties
        try:
            self.communicator = Ice.initialize(init)
        except Ice.LocalException as exc:                     # IceSSL: a wrong password, an unreadable file
            raise ServeError(f"cannot start Ice: {ice_problem(exc)}") from exc
        try:
            self._table = self._servants()
            self._serve(self._table)
            if self.name:
                self._join_fleet()
        except Exception:
            self.close()
            raise
        return self

    def _join_fleet(self) -> None:
        """Announce the vehicle to the registry and publish it on IceStorm (docs/fleet.md)."""
        from .publisher import TelemetryPublisher
        from .registry import TOPIC_MANAGER, RegistryError, announce
        adapter = self._adapters[0]
        try:
            announce(self.communicator, self.name, adapter.createProxy(Ice.Identity(self.name, "")))
        except RegistryError as exc:
            raise ServeError(f"cannot register {self.name}: {exc}") from None
        self._announced = True
        rate = self.properties.getPropertyWithDefault(PREFIX + "Publish.Rate", "10")
        try:
            hz = float(rate)
        except ValueError:
            raise ServeError(f"{PREFIX}Publish.Rate={rate!r} is not a number") from None
        if hz > 0:
            manager = self.properties.getPropertyWithDefault(PREFIX + "TopicManager.Proxy", TOPIC_MANAGER)
            self.publisher = TelemetryPublisher(self.communicator, self.vehicle, self.snapshots, self.name, manager,
                                                min(hz, 50.0)).start()

    def _serve(self, table: dict[str, Ice.Object]) -> None:
        com = self.communicator
        if self.name:           # before any adapter has the id: destroying one would unregister the name
            from .registry import RegistryError, serving_elsewhere
            try:
                other = serving_elsewhere(com, self.name)
            except RegistryError as exc:
                raise ServeError(f"cannot register {self.name}: {exc}") from None
            if other:
                raise ServeError(f"a vehicle named {self.name} is already registered and answering ({other}): "
                                 "give this one another --name")
        adapters: dict[str, Ice.ObjectAdapter] = {}
        planned = planned_endpoints(self.properties)
        for name, (identity, endpoints) in planned.items():
            adapter = adapters.get(endpoints)
            if adapter is None:
                if self.name:                       # a fleet: one adapter, the vehicle's name as its adapter id
                    com.getProperties().setProperty(f"MAVLinkServer-{name}.AdapterId", self.name)
                try:
                    adapter = com.createObjectAdapterWithEndpoints(f"MAVLinkServer-{name}", endpoints)
                except Ice.LocalException as exc:
                    sharing = [n for n, (_, e) in planned.items() if e == endpoints]
                    what = name if len(sharing) == 1 else "the Ice interfaces"
                    raise ServeError(f"cannot serve {what} on {_where(endpoints)}: {ice_problem(exc)}") from exc
                adapters[endpoints] = adapter
                self._adapters.append(adapter)
            adapter.add(table[name], Ice.stringToIdentity(identity))
            prx = adapter.createDirectProxy(Ice.stringToIdentity(identity))
            self.served[name] = Served(name, identity, com.proxyToString(prx))
        if self.name:                               # what the registry lists: identity = the vehicle's name
            self._adapters[0].add(table["Vehicle"], Ice.Identity(self.name, ""))
        if self.name and self.properties.getProperty(PREFIX + "Certs"):
            # the registry hands these to clients on other machines: only the TLS ones, never 127.0.0.1's
            adapter = self._adapters[0]
            adapter.setPublishedEndpoints([e for e in adapter.getEndpoints() if e.getInfo().secure()])
        for adapter in self._adapters:
            try:
                adapter.activate()                  # in a fleet: registers its endpoints under the adapter id
            except Ice.LocalException as exc:
                raise ServeError(f"cannot register {self.name} with the registry "
                                 f"{self.properties.getProperty('Ice.Default.Locator')}: {ice_problem(exc)}") from exc
        for s in self.served.values():
            log.info("serving %s as %s", s.name, s.proxy)

    def proxy(self, name: str) -> str:
        """``Pose3D:tcp -h 127.0.0.1 -p 9998``-style string for one served interface (actual ports)."""
        return self.served[name].proxy

    def client_properties(self, prefix: str = "UAVViewer") -> dict[str, str]:
        """``<prefix>.<Interface>.Proxy`` keys a viewer config would hold for this server."""
        return {f"{prefix}.{name}.Proxy": s.proxy for name, s in self.served.items()}

    def indirect_proxy(self, name: str) -> str:
        """In a fleet: ``Pose3D@solo-1``, what any client of the registry uses."""
        return f"{self.served[name].identity}@{self.name}"

    def close(self) -> None:
        if self.publisher is not None:
            self.publisher.stop()
        if self._announced and self.communicator is not None:
            from .registry import withdraw
            withdraw(self.communicator, self.name)      # the adapter's endpoints go with destroy()
            self._announced = False
        for extension in (self._table.get(name) for name in ("Vehicle", "Shots")) if self._table else ():
            if extension is not None:
                extension.abort_pending("server shutting down")   # AMD answers would hold destroy() back
        com, self.communicator = self.communicator, None
        if com is not None:
            com.destroy()
        close_camera = getattr(self.camera, "close", None)
        if callable(close_camera):
            try:
                close_camera()
            except Exception:
                log.exception("closing the camera servant failed")

    def wait(self) -> None:
        """Block until the communicator shuts down (daemon mode)."""
        if self.communicator is not None:
            self.communicator.waitForShutdown()
