"""A fleet on ZeroC's IceGrid: a MAVLinkServer registers its vehicle by name, viewers find vehicles by name.

No registry of our own: the lab runs Debian's ``icegridregistry`` (:mod:`driver.ice.lab`). A server started
with ``--registry HOST:PORT --name solo-1`` serves every interface on one adapter whose adapter id is the
vehicle's name (``Ice.Default.Locator`` and IceGrid's dynamic registration), so any client, JdeRobot's too,
reaches it as ``Pose3D@solo-1``, ``CMDVel@solo-1``... and it adds a well-known object of type
``::mavlinkserver::Vehicle`` (``Vehicle@solo-1`` under the identity ``solo-1``) so viewers can list the fleet
through ``IceGrid::Query`` without an admin session. Stopping the server removes both.
"""
from __future__ import annotations

import logging
import re

import Ice
import IceGrid

from .problems import ice_problem

log = logging.getLogger(__name__)

DEFAULT_PORT = 4061                          # IceGrid's registered port
VEHICLE_TYPE = "::mavlinkserver::Vehicle"
INTERFACES = ("Camera", "Pose3D", "CMDVel", "Navdata", "Extra", "WP", "Vehicle")
#: IceStorm's TopicManager, registered by the lab's IceBox with adapter id IceStorm.TopicManager
TOPIC_MANAGER = "IceStorm/TopicManager@IceStorm.TopicManager"
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,62}$")


class RegistryError(RuntimeError):
    """The registry cannot be reached or refused us, said in one line."""


def registry_address(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (``[::1]:4061``; a bare host takes 4061) → ``(host, port)``; ValueError otherwise."""
    text = text.strip()
    host, _, port = text.rpartition(":") if not text.endswith("]") and ":" in text else (text, "", "")
    host = host.strip("[]")
    if not host:
        raise ValueError(f"{text!r}: expected HOST:PORT of an IceGrid registry")
    try:
        number = int(port) if port else DEFAULT_PORT
    except ValueError:
        raise ValueError(f"{text!r}: the port must be a number") from None
    if not 0 < number < 65536:
        raise ValueError(f"{text!r}: the port must be 1 to 65535")
    return host, number


def vehicle_name_problem(name: str) -> str | None:
    """Why ``name`` cannot be a vehicle's adapter id and topic name, or None."""
    if not _NAME.match(name or ""):
        return (f"{name!r}: a vehicle name is 1 to 63 letters, digits, '-', '_' or '.', starting with a letter or "
                "digit (it becomes the adapter id and the IceStorm topic)")
    if name.startswith("IceStorm") or name.startswith("IceGrid"):
        return f"{name!r}: names starting with IceGrid or IceStorm belong to ZeroC's services"
    return None


def locator(host: str, port: int, secure: bool = False) -> str:
    """The registry's locator proxy (``Ice.Default.Locator``)."""
    h = f'"{host}"' if ":" in host else host
    return f"IceGrid/Locator:{'ssl' if secure else 'tcp'} -h {h} -p {port}"


def client_properties(prefix: str, name: str) -> dict[str, str]:
    """``<prefix>.<Interface>.Proxy`` keys for the vehicle ``name``: indirect proxies through the locator."""
    return {f"{prefix}.{i}.Proxy": f"{i}@{name}" for i in INTERFACES}


def serving_elsewhere(com: Ice.Communicator, name: str) -> str | None:
    """The endpoints of another server registered as ``name`` and answering, or None (free, or a stale entry
    left by a server that crashed, which the new one may take over). IceGrid's dynamic registration would let a
    second server silently take the name: a pilot would then fly another drone than the one named."""
    try:
        found = com.getDefaultLocator().ice_invocationTimeout(3000).findAdapterById(name)
    except Ice.AdapterNotFoundException:
        return None
    except Ice.LocalException as exc:
        raise RegistryError(f"cannot reach the registry: {ice_problem(exc)}") from None
    if found is None:
        return None
    try:
        found.ice_identity(Ice.Identity(name, "")).ice_invocationTimeout(1000).ice_timeout(1000).ice_ping()
    except Ice.ObjectNotExistException:
        return com.proxyToString(found).split(":", 1)[-1]       # something answers there, but not a vehicle
    except Ice.LocalException:
        log.warning("vehicle %s was registered by a server that no longer answers: taking its name over", name)
        return None
    return com.proxyToString(found).split(":", 1)[-1]


def _admin(com: Ice.Communicator):
    """``(session, admin)``: an admin session on the registry the communicator's locator names."""
    try:
        registry = IceGrid.RegistryPrx.checkedCast(
            com.stringToProxy(f"{_instance(com)}/Registry").ice_invocationTimeout(3000))
        if registry is None:
            raise RegistryError("the locator is not an IceGrid registry")
        session = registry.createAdminSession("mavlinkserver", "")
        return session, session.getAdmin()
    except IceGrid.PermissionDeniedException as exc:
        raise RegistryError(f"the registry refused an admin session: {exc.reason}") from None
    except Ice.LocalException as exc:
        raise RegistryError(f"cannot reach the registry: {ice_problem(exc)}") from None


def _instance(com: Ice.Communicator) -> str:
    """The registry's instance name, from the locator proxy (``IceGrid/Locator`` → ``IceGrid``)."""
    loc = com.getDefaultLocator()
    return loc.ice_getIdentity().category if loc is not None else "IceGrid"


def announce(com: Ice.Communicator, name: str, vehicle_proxy: Ice.ObjectPrx) -> None:
    """Add (or replace: a server restarted after a crash) the well-known object ``name`` → ``Vehicle@name``."""
    session, admin = _admin(com)
    try:
        identity = Ice.Identity(name=name, category="")
        try:
            admin.addObjectWithType(vehicle_proxy, VEHICLE_TYPE)
        except IceGrid.ObjectExistsException:
            admin.updateObject(vehicle_proxy)
        log.info("registered vehicle %s as %s", name, com.identityToString(identity))
    except (IceGrid.DeploymentException, Ice.LocalException) as exc:
        raise RegistryError(f"the registry refused vehicle {name}: {exc}") from None
    finally:
        _destroy(session)


def withdraw(com: Ice.Communicator, name: str) -> None:
    """Remove the well-known object ``name``; a registry that is gone already is only logged."""
    try:
        session, admin = _admin(com)
    except RegistryError as exc:
        log.warning("vehicle %s not withdrawn from the registry: %s", name, exc)
        return
    try:
        admin.removeObject(Ice.Identity(name=name, category=""))
    except (IceGrid.ObjectNotRegisteredException, IceGrid.DeploymentException):
        pass
    except Ice.LocalException as exc:
        log.warning("vehicle %s not withdrawn from the registry: %s", name, exc)
    finally:
        _destroy(session)


def _destroy(session) -> None:
    try:
        session.destroy()
    except Ice.LocalException:
        pass


def list_vehicles(com: Ice.Communicator, timeout_ms: int = 2000) -> list[str]:
    """Names of the vehicles the registry knows, sorted; RegistryError if it does not answer."""
    try:
        query = IceGrid.QueryPrx.uncheckedCast(
            com.stringToProxy(f"{_instance(com)}/Query").ice_invocationTimeout(timeout_ms))
        found = query.findAllObjectsByType(VEHICLE_TYPE)
    except Ice.LocalException as exc:
        raise RegistryError(f"cannot reach the registry: {ice_problem(exc)}") from None
    return sorted({p.ice_getIdentity().name for p in found if p is not None})
