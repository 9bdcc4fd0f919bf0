"""Closing the window: with the vehicle in the air the pilot is asked first (Land / Quit anyway / Cancel) and the
window stays; an unsaved plan is asked about too. Ctrl+C or kill in the terminal closes at once, even in flight
(said in the log)."""
from __future__ import annotations

import logging

from PyQt5.QtCore import QObject
from PyQt5.QtWidgets import QMessageBox

from driver.vehicle.rules import unattended

from ..flight.phase import flight_phase
from ..widgets.ask import ask

__all__ = ["Closing"]

log = logging.getLogger(__name__)


class Closing(QObject):
    """``window``: the main window (its adapter, flight commands and plan)."""

    def __init__(self, window) -> None:
        super().__init__(window)
        self.window = window
        self.quit_box: QMessageBox | None = None
        self.quitting = False                   # closing without asking (answered, or a signal)

    def quit_without_asking(self) -> None:
        """Ctrl+C or kill in the terminal: close now, even in flight (said in the log)."""
        adapter = self.window.adapter
        if flight_phase(adapter.state).airborne and adapter.replay is None:
            s = adapter.state
            log.warning("closing while the vehicle is in the air: %s", unattended(s.mode, s.gcs_failsafe))
        self.quitting = True
        if self.quit_box is not None:
            self.quit_box.reject()
        self.window.close()

    def keeps_open(self) -> bool:
        """Whether a close must wait for the pilot's answer (the vehicle flies, or a plan is unsaved)."""
        return self._ask_before_leaving_the_air() or (not self.quitting and self.window.plan.ask_before_closing())

    def _ask_before_leaving_the_air(self) -> bool:
        adapter = self.window.adapter
        if self.quitting or adapter.replay is not None or not flight_phase(adapter.state).airborne:
            return False
        if self.quit_box is None:
            s = adapter.state
            box = QMessageBox(QMessageBox.Warning, "The vehicle is flying",
                              f"The vehicle is in the air in {s.mode}. Without this window nobody commands it: "
                              f"{unattended(s.mode, s.gcs_failsafe)}.", QMessageBox.NoButton, self.window)
            box.setObjectName("quitQuestion")
            land = box.addButton("Land", QMessageBox.AcceptRole)
            leave = box.addButton("Quit anyway", QMessageBox.DestructiveRole)
            box.addButton(QMessageBox.Cancel)
            box.setDefaultButton(land)
            self.quit_box = ask(box, lambda box: self._answered(box, land, leave))
        return True

    def _answered(self, box: QMessageBox, land, leave) -> None:
        clicked = box.clickedButton()
        self.quit_box = None
        box.deleteLater()
        if clicked is land:
            self.window.flight.request_land()
        elif clicked is leave:
            self.quit_without_asking()
