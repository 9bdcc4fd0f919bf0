"""The fleet in the window: which vehicles there are, which one the sticks fly, and commands for all of them.

:class:`FleetController` holds the logic the fleet panel only shows: it reads the :class:`driver.api.Fleet`'s
names and each vehicle's snapshot (never waiting: both are kept fresh in the background), makes the rows,
says what a switch of vehicle leaves behind, and sends Takeoff/Land/Stop to every vehicle. Each vehicle is
seen only as a :class:`driver.api.Drone`.
"""
from __future__ import annotations

import logging
from concurrent.futures import Future
from dataclasses import dataclass, replace
from typing import Callable

from PyQt5.QtCore import QObject, QTimer, pyqtSignal

from driver.vehicle.api import Drone, Fleet
from driver.vehicle.state import CommandResult, CommandStatus, LinkStatus, Severity, VehicleState

from ..flight.phase import flight_phase

__all__ = ["FleetRow", "FleetController", "row_for", "switch_message"]

log = logging.getLogger(__name__)

#: a vehicle whose link has said nothing for this long is shown stale, whatever its server last said
STALE_AFTER_S = 3.0
#: what every vehicle may be asked at once, each the drone's own call
ALL_COMMANDS: dict[str, Callable[..., Future]] = {
    "takeoff": lambda drone, altitude: drone.takeoff(altitude),
    "land": lambda drone: drone.land(),
    "stop": lambda drone: drone.stop(),
}


@dataclass(frozen=True)
class FleetRow:
    name: str
    mode: str            # "" before the first heartbeat
    armed: bool
    battery: str         # "87 %", "15.8 V" or "–"
    link: str            # "0.3 s", "lost 12 s", "waiting", "not in the registry"
    stale: bool          # the vehicle's state may be old: shown greyed
    picked: bool         # the sticks, keys and buttons fly this one
    airborne: bool


def row_for(name: str, s: VehicleState | None, picked: bool, listed: bool) -> FleetRow:
    """One vehicle's line in the fleet panel."""
    if s is None:
        return FleetRow(name, "", False, "–", "waiting" if listed else "not in the registry", True, picked, False)
    b = s.battery
    battery = f"{b.remaining:.0f} %" if b.remaining is not None else f"{b.voltage:.1f} V" if b.voltage else "–"
    age = s.link.heartbeat_age
    status = s.link.status
    if status is LinkStatus.WAITING:
        link = "waiting"
    elif status is LinkStatus.OK and age is not None:
        link = f"{age:.1f} s"
    else:
        link = status.value.lower() + (f" {age:.0f} s" if age is not None else "")
    if not listed:
        link += " · not in the registry"
    stale = status is not LinkStatus.OK or (age is not None and age > STALE_AFTER_S) or not listed
    return FleetRow(name, s.mode, s.armed, battery, link, stale, picked, flight_phase(s).airborne)


def switch_message(previous: str, previous_state: VehicleState | None, picked: str) -> tuple[str, Severity]:
    """What the pilot is told when the sticks move to ``picked``."""
    if previous and previous != picked and previous_state is not None and flight_phase(previous_state).airborne:
        where = f"{previous_state.altitude:.1f} m, {previous_state.mode}" if previous_state.mode else "in the air"
        return (f"{previous} left hovering ({where}, zero velocity): nobody flies it until you pick it again. "
                f"The sticks, keys and buttons now fly {picked}", Severity.WARNING)
    return f"The sticks, keys and buttons now fly {picked}", Severity.NOTICE


class _Relay(QObject):
    """Carries a command's answer from a driver thread to the UI thread (holds no reference to the controller)."""
    done = pyqtSignal(str, str, object)        # vehicle, command, Future


class FleetController(QObject):
    rowsChanged = pyqtSignal(object)           # tuple[FleetRow, ...]
    vehiclePicked = pyqtSignal(str, object)    # name, Drone: the window flies it from now on
    said = pyqtSignal(str, object)             # text, Severity: a line for the pilot
    resultArrived = pyqtSignal(object)         # CommandResult of a command for all ("solo-2: takeoff")
    vehiclesRead = pyqtSignal(object)          # ((FleetRow, VehicleState | None), ...) on every refresh: the map

    def __init__(self, fleet: Fleet, picked: str, refresh_hz: float = 4.0, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.fleet = fleet
        self._picked = picked
        self._rows: tuple[FleetRow, ...] = ()
        self._seen: set[str] = set()
        self._said_problem = ""
        self._timer = QTimer(self)
        self._timer.setInterval(max(1, int(1000 / refresh_hz)))
        self._timer.timeout.connect(self.refresh)
        self._relay = _Relay()
        self._relay.done.connect(self._answered)

    @property
    def picked(self) -> str:
        return self._picked

    @property
    def rows(self) -> tuple[FleetRow, ...]:
        return self._rows

    @staticmethod
    def camera_uri(name: str) -> str:
        """The vehicle's own camera, served by its MAVLinkServer and found through the registry."""
        return f"ice:Camera@{name}"

    def start(self) -> None:
        self.refresh()
        self._timer.start()

    def stop(self) -> None:
        self._timer.stop()

    def _known(self) -> list[str]:
        """Listed now, plus every vehicle listed before: one whose server left stays, shown stale."""
        self._seen.update(self.fleet.names())
        if self._picked:
            self._seen.add(self._picked)
        return sorted(self._seen)

    def _state(self, name: str) -> VehicleState | None:
        try:
            return self.fleet.drone(name).state()
        except Exception:                      # noqa: BLE001 - a vehicle that cannot be reached stays listed
            log.exception("vehicle %s unavailable", name)
            return None

    def refresh(self) -> None:
        if self.fleet.closed:                  # the program is closing: nothing left to show
            self._timer.stop()
            return
        listed = set(self.fleet.names())
        states = [(n, self._state(n)) for n in self._known()]
        rows = tuple(row_for(n, s, n == self._picked, n in listed) for n, s in states)
        problem = self.fleet.problem
        if problem != self._said_problem:
            self._said_problem = problem
            if problem:
                self.said.emit(f"Fleet list not updated: {problem}", Severity.WARNING)
        if rows != self._rows:
            self._rows = rows
            self.rowsChanged.emit(rows)
        self.vehiclesRead.emit(tuple(zip(rows, (s for _, s in states))))

    def pick(self, name: str) -> None:
        """The sticks, keys and buttons fly ``name`` from now on; the window is told, the pilot too."""
        if name == self._picked:
            return
        previous = self._picked
        before = self._state(previous) if previous else None
        try:
            drone = self.fleet.drone(name)
        except Exception as exc:               # noqa: BLE001
            self.said.emit(f"Cannot fly {name}: {exc}", Severity.ERROR)
            return
        self._picked = name
        self.vehiclePicked.emit(name, drone)
        self.said.emit(*switch_message(previous, before, name))
        self.refresh()

    def command_all(self, command: str, *args, skip: str = "") -> list[str]:
        """``command`` (one of :data:`ALL_COMMANDS`) on every known vehicle but ``skip`` (the window sends that one
        itself, so its answer is shown once); each answer arrives as ``resultArrived``. Returns the names sent to."""
        if command not in ALL_COMMANDS:
            raise ValueError(f"{command} is not a command for all vehicles")
        sent = []
        for name in self._known():
            if name == skip:
                continue
            try:
                drone: Drone = self.fleet.drone(name)
                future = ALL_COMMANDS[command](drone, *args)
            except Exception as exc:           # noqa: BLE001
                self.resultArrived.emit(CommandResult(f"{name}: {command}", CommandStatus.REJECTED, str(exc)))
                continue
            sent.append(name)
            relay = self._relay
            future.add_done_callback(lambda f, n=name, c=command: relay.done.emit(n, c, f))
        return sent

    def _answered(self, name: str, command: str, future: Future) -> None:
        try:
            result = future.result(timeout=0)
        except Exception as exc:               # noqa: BLE001
            result = CommandResult(command, CommandStatus.REJECTED, f"{type(exc).__name__}: {exc}")
        self.resultArrived.emit(replace(result, command=f"{name}: {result.command}", index=0))
