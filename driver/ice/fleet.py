"""IceFleet: the vehicles of a lab's IceGrid registry, each an :class:`~driver.ice.client.IceDrone`.

A thread lists the registry's vehicles (IceGrid::Query, no admin session) every ``refresh`` seconds; each
vehicle asked for becomes an IceDrone reaching ``Vehicle@name`` through the registry and subscribed to the
vehicle's IceStorm topic. Nothing the viewer calls waits on the network.
"""
from __future__ import annotations

import logging
import threading

import Ice

from ..vehicle.api import Drone, Fleet
from .client import IceDrone, fleet_properties
from .registry import RegistryError, list_vehicles, registry_address

log = logging.getLogger(__name__)


class IceFleet(Fleet):
    def __init__(self, registry: str, certs: str | None = None, refresh: float = 1.0, **drone_options) -> None:
        registry_address(registry)                       # ValueError for a bad address, before any thread
        self._registry, self._certs, self._refresh = registry, certs, refresh
        self._drone_options = drone_options
        self._names: tuple[str, ...] = ()
        self._problem = ""
        self._drones: dict[str, IceDrone] = {}
        self._lock = threading.Lock()
        self._closing = threading.Event()
        self._listed = threading.Event()
        self._com: Ice.Communicator | None = None
        self._thread = threading.Thread(target=self._run, name="fleet-registry", daemon=True)

    def start(self) -> "IceFleet":
        init = Ice.InitializationData()
        init.properties = fleet_properties(self._registry, self._certs)
        self._com = Ice.initialize(init)
        self._thread.start()
        return self

    @property
    def description(self) -> str:
        return f"registry {self._registry}"

    def names(self) -> tuple[str, ...]:
        return self._names

    @property
    def problem(self) -> str:
        return self._problem

    @property
    def closed(self) -> bool:
        return self._closing.is_set()

    def wait_listed(self, timeout: float) -> bool:
        """Until the registry has answered once (scripts and the command line, never the UI thread)."""
        return self._listed.wait(timeout)

    def _run(self) -> None:
        while not self._closing.is_set():
            try:
                self._names = tuple(list_vehicles(self._com))
                if self._problem:
                    log.warning("registry %s answering again", self._registry)
                self._problem = ""
            except RegistryError as exc:
                if not self._problem:
                    log.warning("registry %s: %s", self._registry, exc)
                self._problem = str(exc)
            self._listed.set()
            self._closing.wait(self._refresh)

    def drone(self, name: str) -> Drone:
        with self._lock:
            if self._closing.is_set():
                raise RuntimeError("the fleet is closed")
            drone = self._drones.get(name)
            if drone is None:
                drone = self._drones[name] = IceDrone.for_vehicle(self._registry, name, self._certs,
                                                                  **self._drone_options).start()
            return drone

    def close(self) -> None:
        self._closing.set()
        if self._thread.is_alive():
            self._thread.join(3.0)
        with self._lock:
            drones, self._drones = list(self._drones.values()), {}
        for d in drones:
            d.close()
        if self._com is not None:
            self._com.destroy()
            self._com = None
