"""Live telemetry fan-out: a MAVLinkServer publishes its vehicle on IceStorm, observers subscribe.

One thread per server. Every ``1/rate`` s it publishes the status (link state included), JdeRobot's pose and
navdata on the topic named after the vehicle; between those it watches the driver's snapshot at
``watch_hz`` and publishes an event the moment the mode changes, the vehicle arms or disarms, a message or a
command result arrives. IceStorm (ZeroC's, run by the lab) copies each publication to every subscriber, so
the server's cost does not grow with the audience (bench/bench_fleet.py measures it). Calls are oneway:
publishing never waits for an observer. Without IceStorm it says so once and tries again every few seconds.
"""
from __future__ import annotations

import logging
import threading
import time

import Ice
import IceStorm

from ..vehicle.api import Drone
from ..vehicle.state import CommandStatus, Severity, VehicleState
from . import convert, load_slice
from .payload import payload_to_ice
from .problems import ice_problem

jderobot, mavlinkserver = load_slice()
log = logging.getLogger(__name__)

RATE_HZ = 10.0
WATCH_HZ = 50.0
RETRY_S = 3.0


def topic(com: Ice.Communicator, manager: str, name: str):
    """The topic ``name`` on the TopicManager ``manager`` (a proxy string), created if new."""
    tm = IceStorm.TopicManagerPrx.checkedCast(com.stringToProxy(manager).ice_invocationTimeout(3000))
    if tm is None:
        raise RuntimeError(f"{manager} is not an IceStorm TopicManager")
    try:
        return tm.retrieve(name)
    except IceStorm.NoSuchTopic:
        try:
            return tm.create(name)
        except IceStorm.TopicExists:             # another process made it meanwhile
            return tm.retrieve(name)


def events_between(old: VehicleState | None, new: VehicleState) -> list:
    """``VehicleEvent``s for what changed from ``old`` to ``new`` (nothing for the first snapshot's state)."""
    now = time.time()
    found = []
    if old is not None and new.mode and new.mode != old.mode:
        found.append(mavlinkserver.VehicleEvent(now, "mode", new.mode, int(Severity.INFO)))
    if old is not None and new.armed != old.armed and new.mode:
        found.append(mavlinkserver.VehicleEvent(now, "armed" if new.armed else "disarmed", "", int(Severity.INFO)))
    last_message = old.messages[-1].index if old is not None and old.messages else -1
    for m in new.messages_since(last_message):
        found.append(mavlinkserver.VehicleEvent(m.time, "message", m.text, int(m.severity)))
    last_result = old.results[-1].index if old is not None and old.results else -1
    for r in new.results_since(last_result):
        if r.status is not CommandStatus.IN_PROGRESS:
            severity = Severity.INFO if r.ok else Severity.WARNING
            found.append(mavlinkserver.VehicleEvent(now, "result", str(r), int(severity)))
    return found


class TelemetryPublisher:
    """Publishes ``vehicle`` as ``name`` through the TopicManager ``manager``; ``start()``, ``stop()``."""

    def __init__(self, com: Ice.Communicator, vehicle: Drone, snapshots, name: str, manager: str,
                 rate_hz: float = RATE_HZ, watch_hz: float = WATCH_HZ) -> None:
        """``snapshots``: the servants' :class:`~driver.ice.servants.Snapshots`, so a pose or navdata published
        is the very value Pose3D and Navdata answer (one conversion, one clock)."""
        self._com, self._vehicle, self._snapshots, self.name, self._manager = com, vehicle, snapshots, name, manager
        self._period = 1.0 / rate_hz
        self._watch = 1.0 / max(watch_hz, rate_hz)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name=f"publish-{name}", daemon=True)
        self._publisher = None
        self._said_missing = False

    def start(self) -> "TelemetryPublisher":
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(3.0)

    @property
    def connected(self) -> bool:
        return self._publisher is not None

    def _connect(self) -> bool:
        try:
            t = topic(self._com, self._manager, self.name)
            self._publisher = mavlinkserver.TelemetryPrx.uncheckedCast(t.getPublisher().ice_oneway())
        except (Ice.Exception, RuntimeError) as exc:
            if not self._said_missing:
                self._said_missing = True
                log.warning("not publishing %s on IceStorm (%s): %s; trying again every %g s", self.name,
                            self._manager, _problem(exc), RETRY_S)
            return False
        log.info("publishing %s on IceStorm topic %s", self.name, self.name)
        if self._said_missing:
            log.warning("publishing %s on IceStorm again", self.name)
        self._said_missing = False
        return True

    def _run(self) -> None:
        last: VehicleState | None = None
        last_message = last_result = -1
        next_status = time.monotonic()
        while not self._stop.is_set():
            if self._publisher is None and not self._connect():
                self._stop.wait(RETRY_S)
                continue
            try:
                s = self._vehicle.state()
                if last is not None and s is not last:
                    for e in events_between(last, s):
                        self._publisher.event(self.name, e)
                last = s                              # only once its events are out: a failure sends them again
                now = time.monotonic()
                if now >= next_status:
                    status = convert.status_from_state(mavlinkserver, s, last_message, last_result)
                    self._publisher.status(self.name, status)
                    self._publisher.pose(self.name, time.time(), self._snapshots.pose())
                    self._publisher.navdata(self.name, self._snapshots.navdata())
                    self._publisher.payload(self.name, payload_to_ice(mavlinkserver, s))
                    next_status = max(next_status + self._period, now)
                    if s.messages:                    # published: the next status starts after them
                        last_message = s.messages[-1].index
                    if s.results:
                        last_result = s.results[-1].index
            except Ice.Exception as exc:          # IceStorm went away: find it again, every RETRY_S
                if not self._said_missing:
                    log.warning("publishing %s failed: %s", self.name, _problem(exc))
                self._publisher = None
                self._said_missing = True
                self._stop.wait(RETRY_S)
                continue
            self._stop.wait(min(self._watch, max(0.0, next_status - time.monotonic())))


def _problem(exc: Exception) -> str:
    return ice_problem(exc) if isinstance(exc, Ice.Exception) else str(exc)
