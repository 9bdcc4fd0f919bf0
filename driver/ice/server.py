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
  ``Camera.RecordDir`` defaults to :func:`default_record_dir`
"""
from __future__ import annotations

import logging
import os
import re
import sys
from dataclasses import dataclass

import Ice

from ..api import Drone
from . import servants
from .servants import ServerSettings

log = logging.getLogger(__name__)

PREFIX = "MAVLinkServer."
DEFAULT_PORTS = {"Camera": 9999, "Pose3D": 9998, "CMDVel": 9997, "Navdata": 9996, "Extra": 9995, "WP": 9994,
                 "Vehicle": 9993}
ONE_PORT = 9000                                         # JdeRobot's Gazebo drone served everything here


class ServeError(RuntimeError):
    """An interface cannot be served (port taken, bad endpoint, unknown host), said in one line."""


def ice_problem(exc: Exception) -> str:
    """An Ice exception in a few words on one line ("address already in use"), not Ice's multi-line dump."""
    if isinstance(exc, Ice.DNSException):
        return f"cannot resolve host {exc.host}"
    if isinstance(exc, Ice.FileException) and exc.path:
        return f"{exc.path}: {os.strerror(exc.error).lower() if exc.error > 0 else 'cannot read'}"
    if isinstance(exc, Ice.SyscallException) and exc.error > 0:
        return os.strerror(exc.error).lower()
    text = getattr(exc, "str", "") or getattr(exc, "reason", "") or str(exc)
    return " ".join(str(text).split())


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
    # Servants never block, but a slow client must not hold up the others.
    if not props.getProperty("Ice.MessageSizeMax"):
        props.setProperty("Ice.MessageSizeMax", "16384")       # KB: a 720p RGB8 picture is 2.7 MB
    if not props.getProperty("Ice.ThreadPool.Server.SizeMax"):
        props.setProperty("Ice.ThreadPool.Server.Size", "2")
        props.setProperty("Ice.ThreadPool.Server.SizeMax", "8")
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

    return ServerSettings(
        takeoff_altitude=number("TakeoffAltitude", d.takeoff_altitude),
        cmdvel_max=(number("CMDVel.Xmax", h), number("CMDVel.Ymax", h), number("CMDVel.Zmax", v),
                    number("CMDVel.Yawmax", y)),
        cmdvel_refuse_above=number("CMDVel.RefuseAbove", d.cmdvel_refuse_above),
        navdata_vehicle=int(number("Navdata.Vehicle", d.navdata_vehicle)),
    )


def default_record_dir() -> str:
    """Where Extra.recordOnUsb writes when ``Camera.RecordDir`` is not set: the per-user data folder
    the viewer also uses (Qt's AppDataLocation, found here without Qt), never the current directory."""
    if sys.platform == "win32":
        base = os.environ.get("APPDATA") or os.path.join(os.path.expanduser("~"), "AppData", "Roaming")
    elif sys.platform == "darwin":
        base = os.path.join(os.path.expanduser("~"), "Library", "Application Support")
    else:
        base = os.environ.get("XDG_DATA_HOME") or os.path.join(os.path.expanduser("~"), ".local", "share")
    return os.path.join(base, "UavViewerPy", "recordings")


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


def planned_endpoints(props: Ice.Properties) -> dict[str, tuple[str, str]]:
    """``{interface: (identity, endpoints)}`` from the properties; equal endpoints share one adapter."""
    host = props.getPropertyWithDefault(PREFIX + "Host", "127.0.0.1")
    shared = props.getProperty(PREFIX + "Endpoints")
    return {name: (props.getPropertyWithDefault(f"{PREFIX}{name}.Name", name),
                   shared or props.getPropertyWithDefault(f"{PREFIX}{name}.Endpoints", f"default -h {host} -p {port}"))
            for name, port in DEFAULT_PORTS.items()}


@dataclass(frozen=True)
class Served:
    name: str            # the interface's role: Pose3D, WP, ...
    identity: str
    proxy: str           # a stringified proxy a client can use


class IceServer:
    """Serves one :class:`~driver.api.Drone` on JdeRobot's interfaces; start(), then close()."""

    def __init__(self, vehicle: Drone, properties: Ice.Properties | None = None, camera=None):
        self.vehicle = vehicle
        self.properties = properties if properties is not None else default_properties()
        self.settings = settings_from(self.properties, getattr(vehicle, "limits", None))
        self.communicator: Ice.Communicator | None = None
        self.camera = camera
        self._adapters: list[Ice.ObjectAdapter] = []
        self._table: dict[str, Ice.Object] = {}
        self.served: dict[str, Served] = {}

    def _servants(self) -> dict[str, Ice.Object]:
        if self.camera is None:
            self.camera = make_camera_servant(self.properties, self.vehicle)
        v, s = self.vehicle, self.settings
        return {"Camera": self.camera, "Pose3D": servants.Pose3DI(v, "Pose3D"), "CMDVel": servants.CMDVelI(v, s),
                "Navdata": servants.NavdataI(v, s), "Extra": servants.ArDroneExtraI(v, s, self.camera),
                "WP": servants.Pose3DI(v, "WP"), "Vehicle": servants.VehicleI(v, s)}

    def start(self) -> "IceServer":
        init = Ice.InitializationData()
        init.properties = self.properties
        self.communicator = Ice.initialize(init)
        self._table = self._servants()
        try:
            self._serve(self._table)
        except Exception:
            self.close()
            raise
        return self

    def _serve(self, table: dict[str, Ice.Object]) -> None:
        com = self.communicator
        adapters: dict[str, Ice.ObjectAdapter] = {}
        planned = planned_endpoints(self.properties)
        for name, (identity, endpoints) in planned.items():
            adapter = adapters.get(endpoints)
            if adapter is None:
                try:
                    adapter = com.createObjectAdapterWithEndpoints(f"MAVLinkServer-{name}", endpoints)
                except Ice.LocalException as exc:
                    sharing = [n for n, (_, e) in planned.items() if e == endpoints]
                    what = name if len(sharing) == 1 else "the Ice interfaces"
                    raise ServeError(f"cannot serve {what} on {_where(endpoints)}: {ice_problem(exc)}") from exc
                adapters[endpoints] = adapter
                self._adapters.append(adapter)
            prx = adapter.add(table[name], Ice.stringToIdentity(identity))
            self.served[name] = Served(name, identity, com.proxyToString(prx))
        for adapter in self._adapters:
            adapter.activate()
        for s in self.served.values():
            log.info("serving %s as %s", s.name, s.proxy)

    def proxy(self, name: str) -> str:
        """``Pose3D:tcp -h 127.0.0.1 -p 9998``-style string for one served interface (actual ports)."""
        return self.served[name].proxy

    def client_properties(self, prefix: str = "UAVViewer") -> dict[str, str]:
        """``<prefix>.<Interface>.Proxy`` keys a viewer config would hold for this server."""
        return {f"{prefix}.{name}.Proxy": s.proxy for name, s in self.served.items()}

    def close(self) -> None:
        extension = self._table.get("Vehicle") if self._table else None
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
