"""Vehicle › Setup's logic: builds the pages, gives them each snapshot while the window is open, and runs what a
page asks of ``drone.setup`` (driver/setup/control.py) without waiting: its answer comes back on the UI thread.

A connection without a setup part (a remote Ice drone, no vehicle) answers every action with why not, and every page
says so (:meth:`SetupController.no_setup`). A replayed recording has one, whose every command is refused by the
driver ("replaying a recording: no vehicle to command")."""
from __future__ import annotations

import logging
import time
from concurrent.futures import Future
from typing import Callable

from PyQt5.QtCore import QObject, pyqtSignal
from PyQt5.QtWidgets import QAction, QMainWindow, QMenu

from driver.vehicle.state import CommandResult, CommandStatus

from .dialog import SetupDialog
from .failsafes_page import FailsafesPage
from .frame_page import FramePage
from .modes_page import ModesPage
from .motors_page import MotorsPage
from .power_page import PowerPage
from .radio_page import RadioPage
from .sensors_page import SensorsPage
from .summary_page import SummaryPage

__all__ = ["SetupController"]

log = logging.getLogger(__name__)
NO_SETUP = ("this connection has no vehicle setup: a remote drone's server offers no calibrations, motor test, "
            "radio channels nor banner")
RADIO_PAGES = ("Summary", "Radio", "Flight modes", "Motors")     # the pages that show RC_CHANNELS / outputs


class _Relay(QObject):
    """Carries a finished setup action to the UI thread (parentless: it outlives the dialogs)."""
    done = pyqtSignal(object, object, object)    # the page's callback, CommandResult, the dialog's generation


class SetupController(QObject):
    def __init__(self, adapter, parent: QMainWindow, params) -> None:
        super().__init__(parent)
        self.adapter = adapter
        self.params = params                         # the Parameters page's controller: the one checked write path
        self._parent = parent
        self.dialog: SetupDialog | None = None
        self._generation = 0                         # the dialog's: its pages are deleted when the vehicle changes
        self._relay = _Relay()
        self._relay.done.connect(self._answer)
        self._banner_asked = False                   # DO_SEND_BANNER sent to this vehicle (once: its board)
        adapter.stateChanged.connect(self.show_state)
        adapter.droneChanged.connect(lambda _drone: self._vehicle_changed())

    def add_to_menu(self, window: QMainWindow) -> QAction:
        """Vehicle › Setup… under Parameters… (the Vehicle menu is made by the params feature)."""
        menu = window.findChild(QMenu, "menuVehicle")
        action = QAction("&Setup…", window)
        action.setObjectName("actionSetup")
        action.setToolTip("Calibrations, radio, motor test: the vehicle on the bench")
        action.triggered.connect(lambda: self.open())
        menu.addAction(action)
        return action

    def open(self, page: str = "") -> SetupDialog:
        if self.dialog is None:
            pages = [SummaryPage(self), FramePage(self), SensorsPage(self), RadioPage(self), ModesPage(self),
                     PowerPage(self), FailsafesPage(self), MotorsPage(self)]
            self.dialog = SetupDialog(pages, self._parent)
            self.dialog.pageShown.connect(lambda _title: self._watch())
            self.dialog.finished.connect(lambda _code: self._watch(closed=True))
        if page:
            self.dialog.turn_to(page)
        self.dialog.show()
        self.dialog.raise_()
        self.dialog.activateWindow()
        self._watch()
        self.params.fetch_if_needed()                # the pages read and write parameters
        self.show_state(self.adapter.state)
        return self.dialog

    def _vehicle_changed(self) -> None:
        """Another vehicle (a fleet's pick, File › Connect): the pages start again from its own reports."""
        self._banner_asked = False
        if self.dialog is None:
            return
        dialog, self.dialog = self.dialog, None
        self._generation += 1                        # answers still on their way belong to deleted pages
        title = dialog.list.currentItem().text() if dialog.isVisible() and dialog.list.currentItem() else ""
        dialog.close()
        dialog.deleteLater()
        if title:
            self.open(title)

    def _watch(self, closed: bool = False) -> None:
        """RC_CHANNELS and SERVO_OUTPUT_RAW while a page shows them, asked off otherwise (not during a motor test:
        its outputs are what the pilot watches, wherever the window is)."""
        setup = self.adapter.drone.setup
        if setup is None or self.dialog is None:
            return
        self._ask_banner(setup, self.adapter.state)
        item = self.dialog.list.currentItem()
        if not closed and item is not None and item.text() in RADIO_PAGES:
            setup.watch_radio()
        elif not setup.motor_test_running:
            setup.unwatch_radio()

    def _ask_banner(self, setup, s) -> None:
        """The board is named only in the banner's id line, which ArduCopter 3.3 sends only on DO_SEND_BANNER
        (4.x also on a parameter download): ask once a connected vehicle has not named it."""
        known = s.autopilot.board or s.autopilot.simulated
        if s.connected and not known and not self._banner_asked:
            self._banner_asked = True
            setup.request_banner()

    def no_setup(self) -> str:
        """Why this connection has no vehicle setup ("" when it has one): every page says it."""
        return "" if self.adapter.drone.setup is not None else NO_SETUP

    def show_state(self, s) -> None:
        if self.dialog is None or not self.dialog.isVisible():
            return
        setup = self.adapter.drone.setup
        if setup is not None:
            self._ask_banner(setup, s)
        why = self.no_setup()
        self.dialog.set_notice(f"Not on this connection: {why}. Parameters are still read and written." if why
                               else "")
        for page in self.dialog.pages.values():
            page.show_state(s)

    # -- what the pages ask ---------------------------------------------------------------------------
    @staticmethod
    def now() -> float:
        return time.time()

    def propose(self, values: dict[str, float]) -> list[str]:
        """Parameters a page wants written: checked, staged and reviewed as on the Parameters page, written only
        when the pilot presses Write there, each confirmed by the vehicle's echo (ParamsController.propose)."""
        return self.params.propose(values)

    def propose_changes(self, wanted: dict[str, float], reported: dict[str, float]) -> str:
        """The values of ``wanted`` that differ from what the vehicle ``reported``, proposed; the page's words."""
        changed = {n: v for n, v in wanted.items() if reported.get(n) != v}
        if not changed:
            return "Nothing changed."
        unknown = self.propose(changed)
        return (f"Not staged: {', '.join(unknown)} not read from the vehicle yet." if unknown else
                "In the Parameters review: written when you press Write there.")

    def open_parameter(self, name: str) -> None:
        self.params.open(name)

    def reboot(self) -> None:
        """The vehicle restarts (a new frame); the answer goes to Messages as every command's."""
        self.adapter.send(self.adapter.drone.reboot)

    def run(self, name: str, call: Callable, done: Callable[[CommandResult], None]) -> None:
        """``call(drone.setup)`` returns a Future of a CommandResult; ``done(result)`` runs on the UI thread."""
        setup = self.adapter.drone.setup
        if setup is None:
            done(CommandResult(name, CommandStatus.REJECTED, NO_SETUP))
            return
        try:
            future = call(setup)
        except Exception as exc:                     # noqa: BLE001 - said on the page, the window goes on
            log.exception("setup action %s failed to start", name)
            done(CommandResult(name, CommandStatus.REJECTED, str(exc)))
            return
        relay, generation = self._relay, self._generation
        future.add_done_callback(lambda f: relay.done.emit(done, _result(name, f), generation))

    def _answer(self, done: Callable[[CommandResult], None], result: CommandResult, generation: int) -> None:
        """An answer for a page of an older dialog is dropped: that page was deleted with its vehicle (its
        verdict is in Messages, as every command's)."""
        if generation != self._generation:
            log.info("dropped the answer of %s: the vehicle changed (%s)", result.command, result)
            return
        done(result)


def _result(name: str, future: Future) -> CommandResult:
    try:
        result = future.result(timeout=0)
    except Exception as exc:                         # noqa: BLE001
        return CommandResult(name, CommandStatus.REJECTED, f"{type(exc).__name__}: {exc}")
    return result if isinstance(result, CommandResult) else CommandResult(name, CommandStatus.ACCEPTED, str(result))
