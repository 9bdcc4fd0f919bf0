"""Arm: asked first, and never asked in a mode ArduCopter refuses to arm in.

In RTL, SMART_RTL, LAND (and the other modes of :data:`driver.rules.NOT_ARMABLE_MODES`) the vehicle answers an arm
with "Mode not armable". Asking "Arm?" there only to be refused is a wasted confirmation at the worst moment; the
window says so before asking, and offers the switch to a mode that arms (GUIDED or LOITER) instead.
"""
from __future__ import annotations

from PyQt5.QtWidgets import QMessageBox

from driver.vehicle.rules import ARM_IN, arming_consequence, arming_refusal

from ..widgets.ask import ask
from .questions import arm_question
from .phase import flight_phase

__all__ = ["Arming"]


class Arming:
    """``window``: the main window (its adapter, and ``window.flight``: the flight commands)."""

    def __init__(self, window) -> None:
        self.window = window
        self.box: QMessageBox | None = None          # the open question, if any

    def request(self) -> None:
        if self.box is not None and self.box.isVisible():
            return
        mode = self.window.adapter.state.mode
        refusal = arming_refusal(mode)
        if refusal is not None:
            self.box = ask(self._switch_question(mode, refusal), self._switch_answered)
            return
        self.box = ask(arm_question(self.window, mode, arming_consequence(mode)), self._arm_answered)

    def _switch_question(self, mode: str, refusal: str) -> QMessageBox:
        box = QMessageBox(QMessageBox.Information, "Arm the motors",
                          f"ArduCopter does not arm in {mode} (\"Mode not armable\"): {refusal}.\n\n"
                          "Switching arms nothing: Arm again afterwards, or use Take off (it arms in GUIDED).",
                          QMessageBox.NoButton, self.window)
        box.setObjectName("armSwitchQuestion")
        for name in ARM_IN:
            box.addButton(f"Switch to {name}", QMessageBox.AcceptRole).setProperty("mode", name)
        box.addButton(QMessageBox.Cancel)
        box.setDefaultButton(QMessageBox.Cancel)
        return box

    def _switch_answered(self, box: QMessageBox) -> None:
        clicked = box.clickedButton()
        mode = clicked.property("mode") if clicked is not None else None
        if mode:
            self.window.flight.request_mode(mode)
        self._done(box)

    def _arm_answered(self, box: QMessageBox) -> None:
        if box.clickedButton() is box.button(QMessageBox.Yes):
            s = self.window.adapter.state
            if s.connected and not s.armed and not flight_phase(s).airborne:
                self.window.adapter.send(self.window.adapter.drone.arm)
        self._done(box)

    def _done(self, box: QMessageBox) -> None:
        box.deleteLater()
        if self.box is box:
            self.box = None
