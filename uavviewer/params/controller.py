"""The Parameters page's logic: it follows the vehicle's ParameterTable, stages the pilot's changes, writes them
in one go through the adapter (never waiting), compares .param files and opens a parameter from a message.

The table comes from each snapshot (``VehicleState.parameters``); a write is ``Drone.set_parameter``, whose
result (confirmed only by the vehicle's PARAM_VALUE echo) comes back to the write that asked for it.
"""
from __future__ import annotations

import logging
import threading
from typing import Callable, Mapping

from PyQt5.QtCore import QObject, Qt, pyqtSignal
from PyQt5.QtGui import QKeySequence
from PyQt5.QtWidgets import QAction, QMainWindow, QMessageBox, QTreeWidgetItem, QWidget

from driver.vehicle.state import CommandResult, LinkStatus, Severity, VehicleState

from ..widgets.ask import ask
from ..widgets.menus import menu_named
from .compare_dialog import CompareDialog
from .mentions import named_parameter
from .page import ParametersPage
from .review_dialog import ReviewDialog
from .rows import compare_rows, review_rows
from .table_model import ParameterModel, WriteState
from .values import check, meta_attr, parse_value

__all__ = ["ParamsController"]

log = logging.getLogger(__name__)


class _Relay(QObject):
    """Carries metadata read on a worker thread to the UI thread; parentless, like the adapter's relay, so a
    late answer never lands on a deleted controller."""
    arrived = pyqtSignal(object, object, str)    # the drone it is for, ParamMetadata or None, the source or why not


class ParamsController(QObject):
    said = pyqtSignal(str, object)               # a line for Messages (text, Severity)

    def __init__(self, adapter, parent: QWidget, say: Callable[[str, Severity], None] | None = None) -> None:
        super().__init__(parent)
        self.adapter = adapter
        self._parent = parent
        self.model = ParameterModel(self)
        self.page: ParametersPage | None = None
        self.review: ReviewDialog | None = None
        self.compare: CompareDialog | None = None
        self.question: QMessageBox | None = None
        self._state = VehicleState()
        self._wanted = ""                        # a parameter to show once the vehicle reports it (Fix…)
        self._recentre = ""                      # ... shown before the list was complete: again once it is
        self._asked = False                      # the download was asked for on this link
        self._fetch_problem = ""
        self._writing: dict[str, float] = {}      # name → the value on its way
        self._confirmed_outside: set[tuple[str, float]] = set()
        self._user_metadata = ""                 # a file the pilot chose with Metadata… (it wins over the driver's)
        self._relay = _Relay()
        self._relay.arrived.connect(self._metadata_arrived)
        if say is not None:
            self.said.connect(say)
        adapter.stateChanged.connect(self.show_state)
        adapter.droneChanged.connect(lambda _drone: self._vehicle_changed())   # a fleet's pick, File › Connect
        self._read_metadata(lambda drone: drone.parameter_metadata)

    # -- wiring ------------------------------------------------------------------------------------
    def add_to_menu(self, window: QMainWindow) -> QAction:
        """Vehicle › Parameters… (the Vehicle menu is made if the window has none yet)."""
        menu = menu_named(window, "menuVehicle", "&Vehicle")
        action = QAction("&Parameters…", window)
        action.setObjectName("actionParameters")
        action.setShortcut(QKeySequence("Ctrl+Shift+P"))
        action.setToolTip("Every parameter of the vehicle: search, change, compare with a file")
        action.triggered.connect(lambda: self.open())
        menu.addAction(action)
        return action

    def offer_fixes(self, messages) -> None:
        """Each new line of ``messages`` (MessagesView) at warning or worse that names a parameter gets Fix…."""
        messages.fixRequested.connect(self.open)
        messages.model().rowsInserted.connect(
            lambda _parent, first, last: [self._offer_fix(messages, messages.topLevelItem(row))
                                          for row in range(first, last + 1)])

    def _offer_fix(self, messages, item: QTreeWidgetItem | None) -> None:
        if item is None or item.data(0, Qt.UserRole) is None or item.data(0, Qt.UserRole) > Severity.WARNING:
            return
        if self.adapter.replay is not None:      # a recording: there is no vehicle to fix
            return
        table = self.model.table
        known = table.values if table.values else self.model.metadata
        name = named_parameter(item.text(2), known, complete=table.complete)
        if name:
            messages.offer_fix(item, name)

    # -- the page ----------------------------------------------------------------------------------
    def open(self, name: str = "") -> ParametersPage:
        """Show the page (downloading the list if it is not here yet), at ``name`` if given."""
        page = self._ensure_page()
        page.show()
        page.raise_()
        page.activateWindow()
        self.fetch_if_needed()
        if name and not page.select(name):
            self._wanted = name                  # shown once the vehicle reports it
        elif name:
            page.editor.focus_value()
            self._recentre = "" if self.model.table.complete else name
        self._show_download()
        return page

    def _ensure_page(self) -> ParametersPage:
        if self.page is None:
            page = ParametersPage(self.model, self._parent)
            page.refreshRequested.connect(lambda: self.fetch(refresh=True))
            page.stageRequested.connect(self.stage_text)
            page.revertRequested.connect(lambda name: self.model.unstage([name]))
            page.discardRequested.connect(lambda: self.model.unstage(self.model.pending))
            page.reviewRequested.connect(self.open_review)
            page.compareFileChosen.connect(self.compare_file)
            page.saveFileChosen.connect(self.save_file)
            page.metadataFileChosen.connect(self.load_metadata)
            self.page = page
        return self.page

    def show_state(self, s: VehicleState) -> None:
        if s.link.status is not LinkStatus.OK:
            self._asked = False                              # a new link: ask again when the page wants it
        self._state = s
        self.model.set_table(s.parameters)
        if self.page is None:
            return
        if self._wanted and self.page.select(self._wanted):
            self._recentre = "" if self.model.table.complete else self._wanted
            self._wanted = ""
            self.page.editor.focus_value()
        elif self._recentre and self.model.table.complete:
            if self.page.current_name() == self._recentre:      # the rest of the list came in around it
                self.page.select(self._recentre)
            self._recentre = ""
        if self.page.isVisible():
            self.fetch_if_needed()
            self._show_download()

    def _vehicle_changed(self) -> None:
        if not self._user_metadata:
            self._read_metadata(lambda drone: drone.parameter_metadata)
        self._asked = False
        self._writing.clear()
        self._confirmed_outside.clear()
        self.model.forget()
        for dialog in (self.review, self.compare):
            if dialog is not None:
                dialog.reject()

    def _show_download(self) -> None:
        if self.page is None:
            return
        self.page.show_download(self.model.table, self._state.connected)
        if self._fetch_problem:
            self.page.status.setText(f"{self.page.status.text()} · {self._fetch_problem}")
        if self._wanted:
            self.page.status.setText(f"Waiting for {self._wanted} from the vehicle… · {self.page.status.text()}")

    def fetch(self, refresh: bool = False) -> None:
        """Ask the driver for every parameter (``refresh``: even those it holds already)."""
        self._asked = True
        self._fetch_problem = ""
        self.adapter.send(self.adapter.drone.fetch_parameters, refresh, then=self._fetched)

    def fetch_if_needed(self) -> None:
        table = self.model.table
        if self._asked or table.complete or table.downloading or not self._state.connected:
            return
        self.fetch()

    # -- changes -----------------------------------------------------------------------------------
    def stage_text(self, name: str, text: str) -> None:
        """A value typed in the editor: refused if the type cannot hold it, asked about if out of bounds."""
        self.stage_values({name: parse_value(text)}, typed=True)

    def stage_values(self, values: Mapping[str, float | None], typed: bool = False) -> None:
        """Stage ``values``; any outside the metadata's bounds are staged only once the pilot confirms them."""
        fine: dict[str, float] = {}
        outside: dict[str, str] = {}
        if typed and self.page is not None:
            self.page.editor.show_error("")
        for name, value in values.items():
            param = self.model.parameter(name)
            if param is None:
                continue
            verdict = check(param, value, self.model.meta(name))
            if not verdict.ok:
                if typed and self.page is not None:
                    self.page.editor.show_error(f"Not staged: {verdict.error}")
                continue
            if verdict.warning and (name, verdict.value) not in self._confirmed_outside:
                outside[name] = verdict.warning
            fine[name] = verdict.value
        if not outside:
            self._stage(fine)
            return
        box = QMessageBox(QMessageBox.Warning, "Outside the bounds",
                          "ArduPilot does not check parameter values: it stores what it is sent.\n\n"
                          + "\n".join(outside.values()) + "\n\nStage anyway?",
                          QMessageBox.Yes | QMessageBox.Cancel, self.page or self._parent)
        box.setObjectName("outsideQuestion")
        box.button(QMessageBox.Yes).setText("Stage anyway")
        box.setDefaultButton(QMessageBox.Cancel)
        self.question = ask(box, lambda b: self._outside_answered(b, fine, outside))

    def propose(self, values: Mapping[str, float]) -> list[str]:
        """Another page's changes (Setup's radio calibration, voltage): checked and staged as typed ones are,
        then shown in the review, written only once the pilot presses Write there and confirmed by the
        vehicle's echo. Returns the names the vehicle has not reported (not staged: its parameters are not read)."""
        self.fetch_if_needed()
        unknown = [name for name in values if self.model.parameter(name) is None]
        self.stage_values({n: v for n, v in values.items() if n not in unknown})
        if self.question is not None:                        # some are outside the bounds: the review after
            self.question.finished.connect(lambda _r: self.open_review())
        else:
            self.open_review()
        return unknown

    def _outside_answered(self, box: QMessageBox, fine: dict[str, float], outside: dict[str, str]) -> None:
        if box.clickedButton() is box.button(QMessageBox.Yes):
            self._confirmed_outside.update((name, fine[name]) for name in outside)
        else:
            fine = {n: v for n, v in fine.items() if n not in outside}
        box.deleteLater()
        if self.question is box:
            self.question = None
        self._stage(fine)

    def _stage(self, values: dict[str, float]) -> None:
        for name, value in values.items():
            self.model.stage(name, value)

    def open_review(self) -> ReviewDialog | None:
        """The review of every pending change (window-modal over the page, never waiting)."""
        pending = self.model.pending
        if not pending:
            return None
        if self.review is not None:
            self.review.reject()
        rows = review_rows(pending, self.model.parameter, self.model.meta)
        review = ReviewDialog(rows, self.page or self._parent, armed=self._state.armed)
        review.setAttribute(Qt.WA_DeleteOnClose)
        review.writeRequested.connect(self.write)
        review.discardRequested.connect(self.model.unstage)
        review.finished.connect(lambda _r, d=review: self._review_closed(d))
        review.setWindowModality(Qt.WindowModal)
        self.review = review
        review.open()
        return review

    def _review_closed(self, dialog: ReviewDialog) -> None:
        if self.review is dialog:
            self.review = None

    def write(self, names: list[str]) -> None:
        """PARAM_SET every one of ``names`` at once; each counts only when the vehicle echoes its new value."""
        pending = self.model.pending
        for name in names:
            param = self.model.parameter(name)
            if name not in pending or param is None:
                continue
            value = pending[name]
            if not check(param, value, self.model.meta(name)).ok:      # never reaches the wire
                self._show_write(name, WriteState.FAILED, "the value does not fit the parameter")
                continue
            self._writing[name] = value
            self._show_write(name, WriteState.WRITING)
            # outside the bounds only as the pilot confirmed exactly this value (the driver refuses it otherwise)
            confirmed = (name, value) in self._confirmed_outside
            self.adapter.send(self.adapter.drone.set_parameter, name, value, confirmed,
                              then=lambda result, n=name, v=value: self._written(n, v, result))

    def _show_write(self, name: str, state: WriteState, reason: str = "", written: float | None = None) -> None:
        self.model.set_write_state(name, state, reason, written)
        if self.review is not None:
            self.review.show_write(name, state, reason)

    def _fetched(self, result: CommandResult) -> None:
        self._fetch_problem = "" if result.ok else f"download: {result.status.value}" + (
            f" ({result.reason})" if result.reason else "")
        self._show_download()

    def _written(self, name: str, written: float, result: CommandResult) -> None:
        """The vehicle's answer to one write: shown unless another value of ``name`` went since (its own answer
        will say)."""
        if self._writing.get(name) != written:
            return
        del self._writing[name]
        if result.ok:
            self._show_write(name, WriteState.CONFIRMED, written=written)
            if meta_attr(self.model.meta(name), "reboot_required", False):
                self.said.emit(f"{name} takes effect after the vehicle reboots", Severity.NOTICE)
        else:
            self._show_write(name, WriteState.FAILED, result.reason or result.status.value)

    # -- files and metadata ------------------------------------------------------------------------
    def save_file(self, path: str, mission_planner: bool = False) -> None:
        """The vehicle's parameters into ``path``, in MAVProxy's format (``NAME VALUE``) or Mission Planner's."""
        from driver.params.files import ParamFormat, write_param_file
        table = self.model.table
        try:
            count = write_param_file(path, table, ParamFormat.MISSION_PLANNER if mission_planner
                                     else ParamFormat.MAVPROXY)
        except OSError as exc:
            self.said.emit(f"Parameters not saved to {path}: {exc.strerror or exc}", Severity.WARNING)
            return
        note = "" if table.complete else f" (incomplete: {table.received} of {table.expected or '?'} read)"
        self.said.emit(f"{count} parameters saved to {path}{note}", Severity.INFO)

    def compare_file(self, path: str) -> CompareDialog | None:
        """List how the file at ``path`` differs from the vehicle; the ticked values are staged for review."""
        from driver.params.files import read_param_file
        try:
            file = read_param_file(path)
        except OSError as exc:
            self.said.emit(f"{path} not read: {exc.strerror or exc}", Severity.WARNING)
            return None
        rows, same, vehicle_only = compare_rows(file, self.model.table, self.model.meta)
        if self.compare is not None:
            self.compare.reject()
        dialog = CompareDialog(path, rows, same, vehicle_only, self.page or self._parent,
                               problems=file.problems, excluded=file.excluded)
        dialog.setAttribute(Qt.WA_DeleteOnClose)
        dialog.applyRequested.connect(self._apply_from_file)
        dialog.finished.connect(lambda _r, d=dialog: self._compare_closed(d))
        self.compare = dialog
        dialog.open()
        return dialog

    def _compare_closed(self, dialog: CompareDialog) -> None:
        if self.compare is dialog:
            self.compare = None

    def _apply_from_file(self, values: dict) -> None:
        self.stage_values(values)
        if self.question is None:
            self.open_review()
        else:                                        # out-of-bounds values are asked about first
            self.question.finished.connect(lambda _r: self.open_review())

    def load_metadata(self, path: str) -> None:
        """ArduPilot's apm.pdef.xml at ``path`` describes the parameters from now on (read off the UI thread)."""
        from driver.params.metadata import load_metadata
        self._user_metadata = path
        self._read_metadata(lambda _drone: load_metadata(path), path)

    def _read_metadata(self, read: Callable, source: str = "") -> None:
        """``read(drone)`` on a worker thread (parsing takes half a second; a remote drone asks its server)."""
        drone, relay = self.adapter.drone, self._relay

        def work() -> None:
            try:
                relay.arrived.emit(drone, read(drone), source)
            except Exception as exc:                     # noqa: BLE001 - a bad file or a remote failure: said
                log.debug("parameter metadata not read", exc_info=True)
                relay.arrived.emit(drone, None, f"{source or 'the driver'}: {exc}")
        threading.Thread(target=work, name="param-metadata", daemon=True).start()

    def _metadata_arrived(self, drone, metadata, source: str) -> None:
        if drone is not self.adapter.drone:
            return                                       # another vehicle was picked meanwhile
        if metadata is None and source:
            self.said.emit(f"Parameter metadata not read from {source}", Severity.WARNING)
            return
        if metadata is None:
            return
        self.set_metadata(metadata)
        if source:
            self.said.emit(f"Parameter metadata: {len(metadata)} parameters described ({source})", Severity.INFO)

    def set_metadata(self, meta: Mapping[str, object]) -> None:
        self.model.set_metadata(meta)
        if self.page is not None:
            self.page.show_current()
            self._show_download()
