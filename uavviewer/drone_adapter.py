"""The window's only door to the vehicle: snapshots in, commands out, never waiting.

:class:`DroneAdapter` wraps any :class:`driver.api.Drone` (the embedded driver or the Ice client). A ~30 Hz timer
reads ``drone.state()`` (cheap, non-blocking) and emits it. A command is one of the drone's own methods, written in
the code (``adapter.send(adapter.drone.land)``): a method the driver renames fails where it is called, and
tests/test_architecture.py checks every one the viewer names against :class:`~driver.api.Drone`. The drone hands
back a Future at once; its answer comes back to the UI thread through a queued signal, to Messages
(``commandFinished``) and to the caller's own continuation (``then``), so no part routes answers by their wording.
The velocity setpoint is re-sent at 10 Hz while the pilot holds a stick off-centre, so the driver's deadman only
fires when the UI stalls.
"""
from __future__ import annotations

import logging
from concurrent.futures import Future
from typing import Any, Callable

from PyQt5.QtCore import QObject, Qt, QTimer, pyqtSignal

from driver.vehicle.api import Drone
from driver.mission.plan import TransferOutcome
from driver.vehicle.inspector import Inspection
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
    done = pyqtSignal(str, object, object, int)    # the method's name, its Future, ``then`` or None, the drone's turn


#: what the caller is given back: the drone's answer (a CommandResult; a plan transfer's TransferOutcome), or a
#: CommandResult saying why there is none
Then = Callable[[Any], None]


class DroneAdapter(QObject):
    stateChanged = pyqtSignal(object)        # VehicleState
    commandFinished = pyqtSignal(object)     # every command's CommandResult, on the UI thread (for Messages)
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
        self._relay.done.connect(self._answered, Qt.QueuedConnection)     # never inside send(), even when at once
        self._turn = 0                       # one more for every drone flown: answers of the ones before are theirs
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
        self._turn += 1
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
    def send(self, call: Callable[..., Future | CommandResult | None], *args, then: Then | None = None
             ) -> Future | None:
        """``call(*args)``, where ``call`` is one of :attr:`drone`'s methods (``adapter.send(adapter.drone.land)``).

        The answer arrives as ``commandFinished`` and, with it, ``then(answer)`` on the UI thread, after this call
        returned (inside it only from a method that answers without a Future, such as ``use_signing_key``). An
        answer from a drone no longer flown (a fleet's pick, File › Connect) still reaches Messages, but not
        ``then``: what it would update now belongs to another vehicle. Returns the drone's Future (a caller may
        cancel it), if any."""
        name = call.__name__
        self.commandSent.emit(name)
        try:
            answer = call(*args)
        except Exception as exc:             # noqa: BLE001
            log.exception("command %s failed to start", name)
            answer = CommandResult(name, CommandStatus.REJECTED, str(exc))
        if isinstance(answer, Future):
            relay, turn = self._relay, self._turn      # the callback holds the relay, not this adapter (_FutureRelay)
            answer.add_done_callback(lambda f: relay.done.emit(name, f, then, turn))
            return answer
        if isinstance(answer, CommandResult):
            self._deliver(answer, answer, then)
        return None

    def _answered(self, name: str, future: Future, then: Then | None, turn: int) -> None:
        if future.cancelled():
            answer = CommandResult(name, CommandStatus.ABORTED, "cancelled by the pilot")
        else:
            try:
                answer = future.result(timeout=0)
            except Exception as exc:         # noqa: BLE001
                answer = CommandResult(name, CommandStatus.REJECTED, f"{type(exc).__name__}: {exc}")
        result = answer.result if isinstance(answer, TransferOutcome) else answer
        if not isinstance(result, CommandResult):
            answer = result = CommandResult(name, CommandStatus.ACCEPTED, str(result))
        self._deliver(result, answer, then if turn == self._turn else None)

    def _deliver(self, result: CommandResult, answer: Any, then: Then | None) -> None:
        self.commandFinished.emit(result)
        if then is not None:
            then(answer)

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
