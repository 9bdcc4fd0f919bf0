"""The window's only door to the vehicle: snapshots in, commands out, never waiting.

:class:`DroneAdapter` wraps any :class:`driver.api.Drone` (the embedded
driver today, the Ice client later). A ~30 Hz timer reads ``drone.state()``
(cheap, non-blocking) and emits it; commands are called on the drone, which
hands back a Future at once; its result comes back to the UI thread through a
queued signal. The velocity setpoint is re-sent at 10 Hz while the pilot holds
a stick off-centre, so the driver's deadman only fires when the UI stalls.
"""
from __future__ import annotations

import logging
from concurrent.futures import Future

from PyQt5.QtCore import QObject, QTimer, pyqtSignal

from driver.vehicle.api import Drone
from driver.vehicle.inspector import Inspection
from driver.mission.plan import TransferOutcome
from driver.vehicle.state import CommandResult, CommandStatus, VehicleState

from .input.sticks import VelocityCommand

__all__ = ["DroneAdapter"]

log = logging.getLogger(__name__)


class _FutureRelay(QObject):
    """Carries a finished command from a driver thread to the UI thread.

    It has no parent, so only Python references keep it: a command that finishes after the window (and
    its adapter) was deleted emits into a living object, and the queued connection to the deleted adapter
    is simply gone. Emitting on the adapter itself could race with its deletion on the UI thread.
    """
    done = pyqtSignal(str, object)           # command name, its Future


class DroneAdapter(QObject):
    stateChanged = pyqtSignal(object)        # VehicleState
    transferFinished = pyqtSignal(str, object)   # a plan transfer's name and TransferOutcome (then commandFinished)
    commandFinished = pyqtSignal(object)     # CommandResult, on the UI thread
    commandSent = pyqtSignal(str)            # a command handed to the drone (its name)
    droneChanged = pyqtSignal(object)        # another drone is flown from now on (a fleet's pick, File › Connect)

    def __init__(self, drone: Drone, rate_hz: float = 30.0, refresh_hz: float = 10.0,
                 parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.drone = drone
        self._state: VehicleState | None = None
        self._setpoint = VelocityCommand()
        self._poll = QTimer(self)
        self._poll.setInterval(max(1, int(1000 / rate_hz)))
        self._poll.timeout.connect(self.poll)
        self._refresh = QTimer(self)
        self._refresh.setInterval(max(1, int(1000 / refresh_hz)))
        self._refresh.timeout.connect(self._resend)
        self._relay = _FutureRelay()
        self._relay.done.connect(self._on_future_done)
        self.sent_setpoints = 0              # set_velocity calls made (for tests and the status bar)

    # -- state ----------------------------------------------------------------------------------
    @property
    def state(self) -> VehicleState:
        return self._state if self._state is not None else VehicleState()

    @property
    def description(self) -> str:
        try:
            return self.drone.description
        except Exception:                    # noqa: BLE001 - a remote drone may fail; the UI goes on
            return "?"

    @property
    def replay(self):
        """Play/pause/speed of a recorded flight, or None when flying a vehicle."""
        return self.drone.replay

    def inspection(self) -> Inspection:
        """What the link carries, message by message (Tools › MAVLink inspector); never blocks."""
        try:
            return self.drone.inspection()
        except Exception as e:               # noqa: BLE001 - a remote drone may fail; the UI goes on
            return Inspection.unavailable(f"the drone did not answer ({e})")

    def start(self) -> None:
        self._poll.start()
        self.poll()

    def use(self, drone: Drone) -> None:
        """Fly ``drone`` from now on (a fleet: the pilot picked another vehicle). The previous one was sent zero
        velocity by the window first; nothing more goes to it from here."""
        self._refresh.stop()
        self._setpoint = VelocityCommand()
        self.drone = drone
        self._state = None
        self.droneChanged.emit(drone)
        self.poll()

    def stop(self) -> None:
        self._poll.stop()
        self._refresh.stop()

    def poll(self) -> None:
        try:
            s = self.drone.state()
        except Exception:                    # noqa: BLE001
            log.exception("reading the vehicle state failed")
            return
        if s is not self._state:
            self._state = s
            self.stateChanged.emit(s)

    # -- commands -------------------------------------------------------------------------------
    def command(self, name: str, *args) -> Future | None:
        """Call ``drone.<name>(*args)`` (a dotted name reaches a part: ``shots.orbit``); the result arrives as ``commandFinished`` (at once from a call that
        answers at once, such as ``use_signing_key``). Returns the drone's Future (a caller may cancel it), if any."""
        self.commandSent.emit(name)
        try:
            call = self.drone
            for part in name.split("."):             # "shots.orbit": the drone's smart shots
                call = getattr(call, part)
            future = call(*args)
        except Exception as exc:             # noqa: BLE001
            log.exception("command %s failed to start", name)
            self.commandFinished.emit(CommandResult(name, CommandStatus.REJECTED, str(exc)))
            return None
        if isinstance(future, CommandResult):
            self.commandFinished.emit(future)
        elif isinstance(future, Future):
            relay = self._relay              # the callback holds the relay, not this adapter (see _FutureRelay)
            future.add_done_callback(lambda f, n=name: relay.done.emit(n, f))
            return future
        return None

    def _on_future_done(self, name: str, future: Future) -> None:
        if future.cancelled():
            self.commandFinished.emit(CommandResult(name, CommandStatus.ABORTED, "cancelled by the pilot"))
            return
        try:
            result = future.result(timeout=0)
        except Exception as exc:             # noqa: BLE001
            result = CommandResult(name, CommandStatus.REJECTED, f"{type(exc).__name__}: {exc}")
            if name in ("upload_plan", "download_plan"):
                self.transferFinished.emit(name, TransferOutcome(result))
        if isinstance(result, TransferOutcome):          # a plan transfer: the plan read back goes with it
            self.transferFinished.emit(name, result)
            result = result.result
        if not isinstance(result, CommandResult):
            result = CommandResult(name, CommandStatus.ACCEPTED, str(result))
        self.commandFinished.emit(result)

    # -- velocity -------------------------------------------------------------------------------
    @property
    def setpoint(self) -> VelocityCommand:
        return self._setpoint

    def fly(self, command: VelocityCommand) -> None:
        """Send a new velocity at once; keep refreshing it while it is not zero.

        A return to zero is sent once, explicitly; the driver keeps streaming it.
        """
        changed = command != self._setpoint
        self._setpoint = command
        if changed or not command.is_zero:
            self._send()
        if command.is_zero:
            self._refresh.stop()
        elif not self._refresh.isActive():
            self._refresh.start()

    def _resend(self) -> None:
        if self._setpoint.is_zero:
            self._refresh.stop()
            return
        self._send()

    def _send(self) -> None:
        c = self._setpoint
        try:
            ok = self.drone.set_velocity(c.forward, c.right, c.up, c.yaw_rate)
        except Exception:                    # noqa: BLE001
            log.exception("set_velocity failed")
            return
        self.sent_setpoints += 1
        if ok is False:
            log.warning("the driver refused velocity %s", c)
