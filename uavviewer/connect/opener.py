"""Open a :class:`~uavviewer.connect.choice.Choice` as a flying :class:`driver.api.Drone` (no Qt).

Runs off the UI thread (an Ice server is asked for its proxies; a long .tlog is read whole). The driver gets the
same settings the command line gives it: the flight log folder, signing, the takeoff altitude.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, replace
from pathlib import Path

from driver.vehicle.api import CEILING, Drone, Limits
from driver.vehicle.state import CommandResult, CommandStatus, LinkHealth, LinkStatus, VehicleState

from ..flight.phase import NOT_CONNECTED
from .choice import Choice, Kind

__all__ = ["Opened", "Disconnected", "open_choice", "close_quietly"]


@dataclass
class Opened:
    drone: Drone
    choice: Choice | None
    sim: object = None                    # the built-in simulator started for it, stopped with it
    fleet: object = None                  # a lab's fleet (driver.api.Fleet): ``drone`` is its first vehicle
    first: str = ""                       # ... and that vehicle's name


class Disconnected(Drone):
    """No vehicle: what the window flies after File › Disconnect. Every command is refused with that reason."""

    _REASON = "not connected: File › Connect picks a vehicle"

    def __init__(self) -> None:
        self._state = VehicleState(link=LinkHealth(status=LinkStatus.CLOSED,
                                                   address="not connected — File › Connect picks a vehicle"))
        self._limits = Limits()

    def state(self) -> VehicleState:
        return self._state

    @property
    def description(self) -> str:
        return NOT_CONNECTED                # the title, About and the status bar say it as everything else

    def _refuse(self, name: str):
        from concurrent.futures import Future
        future: Future = Future()
        future.set_result(CommandResult(name, CommandStatus.REJECTED, self._REASON))
        return future

    def takeoff(self, altitude=None):
        return self._refuse("takeoff")

    def land(self):
        return self._refuse("land")

    def stop(self):
        return self._refuse("stop")

    def return_to_launch(self):
        return self._refuse("RTL")

    def arm(self, force=False):
        return self._refuse("arm")

    def disarm(self, force=False, emergency=False):
        return self._refuse("disarm")

    def set_mode(self, name):
        return self._refuse(f"mode {name}")

    def set_velocity(self, forward, right, up, yaw_rate):
        return False

    def go_to(self, north, east, altitude):
        return self._refuse("go to")

    def set_yaw(self, degrees, relative=False, rate_deg_s=30.0):
        return self._refuse("yaw")

    @property
    def limits(self) -> Limits:
        return self._limits

    @property
    def signing_unavailable(self) -> str:
        return "not connected"

    def set_limits(self, limits: Limits) -> Limits:
        self._limits = limits.within(CEILING)        # kept for nothing to fly, so the window's speeds stand
        return self._limits

    def close(self) -> None:
        pass


def open_fleet(registry: str, certs: str | None, wait: float) -> Opened:
    """A lab's fleet, once the registry lists a vehicle (at most ``wait`` s): its first vehicle is flown first."""
    from driver.ice.fleet import IceFleet
    fleet = IceFleet(registry, certs).start()
    try:
        deadline = time.monotonic() + wait
        while not fleet.names():
            if time.monotonic() > deadline:
                raise RuntimeError(f"the registry lists no vehicle after {wait:g} s"
                                   + (f" ({fleet.problem})" if fleet.problem else ""))
            time.sleep(0.2)
        first = fleet.names()[0]
        return Opened(fleet.drone(first), Choice(Kind.REGISTRY, registry), fleet=fleet, first=first)
    except Exception:
        fleet.close()
        raise


def open_choice(choice: Choice, vehicle_config, log_dir: str | None = None, certs: str | None = None,
                speedup: float = 1.0, wait: float = 30.0) -> Opened:
    """Start the drone ``choice`` names. ``vehicle_config``: a :class:`driver.vehicle.VehicleConfig` whose
    signing, limits and takeoff altitude the new link keeps; ``log_dir``: where a live link records its .tlog."""
    problem = choice.problem()
    if problem:
        raise ValueError(problem)
    if choice.kind is Kind.REGISTRY:
        return open_fleet(choice.target, certs, wait)
    if choice.kind is Kind.ICE:
        from driver.ice.client import IceDrone
        config = choice.target if choice.key.startswith("ice-config:") else None
        host = None if config else choice.target
        return Opened(IceDrone.from_config(config, host=host, certs=certs).start(), choice)
    from driver.vehicle import Vehicle
    sim = None
    if choice.kind is Kind.SIM:
        from driver.sim import DEMO_READY_AFTER, SimConfig, SimVehicle
        signing = vehicle_config.signing
        sim = SimVehicle(SimConfig(tcp_port=0, speedup=float(choice.options.get("speedup", speedup)),
                                   ready_after=float(choice.options.get("ready_after", DEMO_READY_AFTER)),
                                   signing_key=signing.key if signing else None))
        sim.start()
        connection = f"tcp:127.0.0.1:{sim.tcp_port}"
    else:
        connection = choice.target
    tlog = None
    if log_dir is not None and choice.kind is not Kind.REPLAY:
        tlog = str(Path(log_dir) / time.strftime("flight-%Y%m%d-%H%M%S.tlog"))
    config = replace(vehicle_config, connection=connection, baud=choice.baud, tlog_path=tlog)
    try:
        return Opened(Vehicle(config).start(), choice, sim)
    except Exception:
        if sim is not None:
            sim.stop()
        raise


def close_quietly(opened: Opened) -> None:
    """Close a drone (and its simulator) the pilot has left; on a worker thread: closing joins the link's threads."""
    try:
        if opened.fleet is not None:
            opened.fleet.close()              # every vehicle's client, the picked one too
        else:
            opened.drone.close()
    finally:
        if opened.sim is not None:
            opened.sim.stop()
