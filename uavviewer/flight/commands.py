"""The flight buttons and the mode list: what each asks of the vehicle, and the question asked first.

Takeoff, arm, a mode that needs an RC transmitter and a disarm in the air are confirmed first (window-modal,
never waited on: the window keeps flying meanwhile). A question that no longer fits the vehicle as it now
reports itself is withdrawn (a takeoff once it is no longer on the ground with a link; the emergency stop once
the motors have stopped). Land, Stop and RTL go at once; they end a go-to and centre the sticks first.
"""
from __future__ import annotations

from PyQt5.QtCore import QObject
from PyQt5.QtWidgets import QMessageBox

from driver.vehicle.rules import mode_refusal, mode_warning
from driver.vehicle.state import LinkStatus, Severity, VehicleState

from ..widgets.ask import ask
from .arming import Arming
from .phase import FlightPhase, flight_phase, takeoff_cancellable, takeoff_progress
from .questions import emergency_stop_question, mode_question, takeoff_question

__all__ = ["FlightCommands", "may_take_off"]


def may_take_off(s: VehicleState) -> bool:
    """What the takeoff question assumes: on the ground with the link up."""
    return flight_phase(s) is FlightPhase.ON_GROUND and s.link.status is LinkStatus.OK


class FlightCommands(QObject):
    """``window``: the main window (its adapter, flight controls, mode list, sticks, map, log, takeoff altitude)."""

    def __init__(self, window) -> None:
        super().__init__(window)
        self.window = w = window
        self.adapter = w.adapter                    # the buttons send the drone's own methods through it
        self.arming = Arming(window)
        self.takeoff_box: QMessageBox | None = None
        self.mode_box: QMessageBox | None = None
        self.emergency_box: QMessageBox | None = None
        fc = w.flightControls
        fc.takeoffRequested.connect(self.request_takeoff)
        fc.landRequested.connect(self.request_land)
        fc.stopRequested.connect(self.request_stop)
        fc.rtlRequested.connect(self.request_rtl)
        fc.armRequested.connect(self.arming.request)
        fc.cancelTakeoffRequested.connect(self.request_cancel_takeoff)
        fc.disarmRequested.connect(self.request_disarm)
        w.modeSelector.modeRequested.connect(self.request_mode)


    def show_state(self, s: VehicleState) -> None:
        """The buttons and the mode list follow the vehicle; questions that no longer fit it are withdrawn."""
        if self.emergency_box is not None and not s.armed:
            self.emergency_box.reject()             # the motors have stopped: nothing left to ask
        phase = flight_phase(s)
        progress = takeoff_progress(s) if phase is FlightPhase.TAKING_OFF else None
        detail = s.takeoff.phase.value if s.takeoff.active else ""
        self.window.flightControls.set_vehicle(phase, s.armed, s.connected, progress, detail,
                                               waiting_for=s.readiness.missing if s.connected else (),
                                               cancellable=takeoff_cancellable(s))
        if self.takeoff_box is not None and not may_take_off(s):
            self.takeoff_box.reject()               # the question no longer fits the vehicle: withdraw it
        self.window.modeSelector.set_mode(s.mode)
        self.window.modeSelector.setEnabled(s.connected)
        self.window.modeSelector.refuse({name: mode_refusal(name, s.may_be_airborne) for name in
                                         self.window.modeSelector.modes()})

    @property
    def arm_box(self) -> QMessageBox | None:
        """The arm question (uavviewer/flight/arming.py) while open."""
        return self.arming.box

    def request_mode(self, name: str) -> None:
        """Switch at once, or ask first when the driver says the mode needs an RC transmitter in flight."""
        warning = mode_warning(name, self.window.adapter.state.flying)
        if warning is None:
            self.adapter.send(self.adapter.drone.set_mode, name)
            return
        self.mode_box = ask(mode_question(self.window, name, warning), lambda box: self._mode_answered(box, name))

    def _mode_answered(self, box: QMessageBox, name: str) -> None:
        if box.clickedButton() is box.button(QMessageBox.Yes):
            self.adapter.send(self.adapter.drone.set_mode, name)
        box.deleteLater()
        if self.mode_box is box:
            self.mode_box = None

    def request_takeoff(self) -> None:
        """Ask once, showing the altitude; the answer comes back without blocking."""
        if self.takeoff_box is not None and self.takeoff_box.isVisible():
            return
        w = self.window
        altitude = w.takeoff_altitude
        waiting = w.adapter.state.readiness.missing
        config = self.adapter.drone.config             # the embedded driver's own wait; a remote one's is not known
        wait_limit = config.ready_timeout if config is not None else 60.0
        self.takeoff_box = ask(takeoff_question(w, altitude, waiting, wait_limit),
                               lambda box: self._takeoff_answered(box, altitude))

    def _takeoff_answered(self, box: QMessageBox, altitude: float) -> None:
        if box.clickedButton() is box.button(QMessageBox.Yes):
            self.take_off_if_still_fits(altitude)
        box.deleteLater()
        if self.takeoff_box is box:
            self.takeoff_box = None

    def take_off_if_still_fits(self, altitude: float) -> None:
        """A takeoff the pilot confirmed, sent only if the vehicle is still on the ground with a link."""
        if may_take_off(self.window.adapter.state):
            self.adapter.send(self.adapter.drone.takeoff, altitude)
        else:
            self.window.log_message("Takeoff not sent: the vehicle is no longer on the ground with a link",
                                    Severity.WARNING)

    def request_cancel_takeoff(self) -> None:
        """Cancel a takeoff that has not left the ground: the driver gives the vehicle back as it was."""
        self.window.sticks.centre()
        self.adapter.send(self.adapter.drone.cancel_takeoff)

    def request_disarm(self) -> None:
        """On the ground, a disarm. In the air, disarming stops the motors and the drone falls: the pilot is
        asked every time, and only a confirmed emergency stop is sent."""
        if not self.window.adapter.state.flying:
            self.adapter.send(self.adapter.drone.disarm)
            return
        if self.emergency_box is not None and self.emergency_box.isVisible():
            return
        self.emergency_box = ask(emergency_stop_question(self.window), self._emergency_answered)

    def _emergency_answered(self, box: QMessageBox) -> None:
        if box.clickedButton() is box.button(QMessageBox.Yes):
            self.window.sticks.centre()
            self.adapter.send(self.adapter.drone.disarm, True, True)   # force, emergency: the motors stop, even aloft
        box.deleteLater()
        if self.emergency_box is box:
            self.emergency_box = None

    def request_land(self) -> None:
        self.window.sticks.centre()
        self.window.map.cancel()
        self.adapter.send(self.adapter.drone.land)

    def request_stop(self) -> None:
        """Stop (button, Space, Escape): hover where it is; a go-to in progress ends there."""
        self.window.sticks.centre()
        self.window.map.cancel()
        self.adapter.send(self.adapter.drone.stop)

    def request_rtl(self) -> None:
        self.window.map.cancel()
        self.adapter.send(self.adapter.drone.return_to_launch)
