"""Plan mode: the Plan dock and the plan on the map, edited by :class:`~uavviewer.plan.editor.PlanEditor`;
here the plans move to and from the vehicle and the mission is flown (docs/missions-viewer.md).

Everything about the vehicle comes from its snapshots: what it holds (the plan read back after an upload, or
downloaded), its transfers' progress, the mission's state and current item. A plan is shown as uploaded, and a
mission as started, paused or resumed, only when the driver says the vehicle confirmed it.
"""
from __future__ import annotations

import logging

from PyQt5.QtCore import QObject, Qt, pyqtSignal
from PyQt5.QtGui import QKeySequence
from PyQt5.QtWidgets import QAction, QDockWidget, QMenu, QMessageBox, QScrollArea, QToolButton, QWidget

from driver.mission.plan import MissionRunState, Plan, PlanKind, TransferDirection
from driver.mission.wire import difference
from driver.vehicle.state import CommandResult, LinkStatus, Severity, VehicleState

from ..widgets.ask import ask, cautious_question
from .editor import PlanEditor
from .files import PlanFiles
from .layer import PlanLayer
from .model import Performance, PlanDocument
from .notices import UploadNotices, fence_off_words
from .room import make_room_for_plan
from .panel import PlanPanel
from .progress import progress_text
from .survey_file import complex_items, mission_entries

__all__ = ["PlanController"]

log = logging.getLogger(__name__)

KINDS = {"mission": PlanKind.MISSION, "fence": PlanKind.FENCE, "rally": PlanKind.RALLY}
_TITLES = {PlanKind.MISSION: "Mission", PlanKind.FENCE: "Fence", PlanKind.RALLY: "Rally"}
_DIRECTION = {TransferDirection.UPLOAD: "Uploading", TransferDirection.DOWNLOAD: "Downloading",
              TransferDirection.CLEAR: "Clearing"}


def mission_start_question(parent: QWidget, text: str) -> QMessageBox:
    """Confirm a mission start (from the ground it arms and takes off); like the takeoff question, Cancel is the
    default."""
    return cautious_question(parent, "Start mission", text, "Start mission", "missionStartQuestion")


class PlanController(QObject):
    startAsked = pyqtSignal(object)           # the Start mission question, open (tests answer it)

    def __init__(self, map_controller, adapter, window, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.map = map_controller
        self.view = map_controller.view
        self.adapter = adapter
        self._window = window
        self.doc = PlanDocument()
        self.layer = PlanLayer(self.doc, self)
        self.layer.attach(self.view)
        self.panel = PlanPanel()
        self.dock = self._dock(window)
        self.plan_button = self._map_button(map_controller.panel)
        self.editor = PlanEditor(self.doc, self.layer, self.panel, self.view, self)
        self.history = self.editor.history
        self.discard_question: QMessageBox | None = None    # "edits not saved" (tests answer it)
        self.remove_question: QMessageBox | None = None     # "Remove the mission from the vehicle?"
        self._may_close = False                              # the pilot said their edits may go
        self.on_vehicle: dict[PlanKind, Plan] = {}      # what each transfer last confirmed the vehicle holds
        self._sending: dict[PlanKind, Plan] = {}        # each kind's upload under way
        self._synced: dict[PlanKind, tuple[Plan, Plan]] = {}   # (here, there) the driver last found the same
        self._outcome: dict[PlanKind, str] = {}         # each kind's last transfer, in words
        self._failed: dict[PlanKind, bool] = {}         # ... and whether the driver refused or failed it
        self._restarts: int | None = None               # the vehicle's restarts seen (VehicleState.boot)
        self._reread: set[PlanKind] = set()             # read again after a restart: into what it holds only
        self._reread_due = False                        # ... asked once the link is up
        self._left_behind: set[PlanKind] = set()        # none here: read to see whether the vehicle keeps one
        self.notices = UploadNotices(window, self)      # the fence off, a fence left from before: asked
        self.notices.said.connect(window.log_message)
        self.notices.removeRequested.connect(lambda kind: self.transfer("clear", confirmed=kind))
        self._state = VehicleState()
        self._shown: tuple | None = None                # what the flying part last showed (redrawn on change)
        adapter.droneChanged.connect(self._vehicle_changed)     # a fleet's pick, File › Connect
        self._question: QMessageBox | None = None
        p = self.panel
        p.editToggled.connect(self.set_editing)
        p.transferRequested.connect(self.transfer)
        p.cancelRequested.connect(lambda: self.adapter.drone.cancel_transfer(KINDS[p.layer]))
        p.startRequested.connect(self.ask_start)
        p.pauseRequested.connect(lambda: self.adapter.command("pause_mission"))
        p.resumeRequested.connect(lambda: self.adapter.command("resume_mission"))
        p.skipRequested.connect(self.skip_to)
        self.layer.contextRequested.connect(self._context)
        adapter.stateChanged.connect(self.show_state)
        adapter.transferFinished.connect(self._transfer_finished)
        adapter.commandFinished.connect(self.command_finished)
        self.editor.refreshed.connect(self._edited)
        self.files = PlanFiles(window, self)
        self.files.loaded.connect(self._file_loaded)
        self.files.said.connect(window.log_message)
        self.files.saved.connect(lambda _path: self.history.mark_saved())
        p.openRequested.connect(self.ask_open)
        p.saveRequested.connect(self.ask_save)
        p.newRequested.connect(self.ask_new)
        p.clearListRequested.connect(self.editor.clear_layer)
        self._file_menu(window)
        self._plan_menu(window)
        self.editor.refresh()

    # -- the dock and the map's button -----------------------------------------------------------
    def _dock(self, window) -> QDockWidget:
        """The Plan dock takes Telemetry's place while it is shown (tabbed with it, but only one of the two shown
        at a time, so no tab bar costs the window height: it still fits a 768-pixel-high laptop screen)."""
        dock = QDockWidget("Plan", window)
        dock.setObjectName("planDock")
        scroll = QScrollArea()
        scroll.setWidgetResizable(True)
        scroll.setFrameShape(QScrollArea.NoFrame)
        scroll.setWidget(self.panel)
        dock.setWidget(scroll)
        dock.setTitleBarWidget(QWidget())       # no title bar: its height goes to the list (the map's Plan button
        dock.hide()                             # and View › Plan show and hide it)
        # tabbed with Telemetry when first shown (show_plan): tabbed now, the window would lay out for a tab bar
        window.addDockWidget(Qt.RightDockWidgetArea, dock)
        window.menuView.addAction(dock.toggleViewAction())
        self._tabbed = False
        # closed or opened as a dock (its close button, View › Plan), not merely behind another tab: the
        # toggle action follows isHidden(), where visibilityChanged also fires for a tab going to the back
        dock.toggleViewAction().toggled.connect(self._dock_shown)
        return dock

    def _map_button(self, panel) -> QToolButton:
        button = QToolButton(text="Plan")
        button.setObjectName("planButton")
        button.setCheckable(True)
        button.setFocusPolicy(Qt.NoFocus)
        button.setToolTip("Plan: the mission's list, transfers and controls in place of Telemetry; on the map a "
                          "click adds a waypoint and a drag moves it")
        panel.mapBar.insertWidget(panel.mapBar.count() - 1, button)
        button.toggled.connect(self.show_plan)
        return button

    def _file_menu(self, window) -> None:
        """File › Open plan… / Save plan…, above Quit."""
        menu = window.menuFile
        # Ctrl+O is File › Replay a flight's (the pilot's tools): the plan's is Ctrl+Shift+O
        self.new_action = QAction("New plan", window, shortcut=QKeySequence.New, triggered=self.ask_new)
        self.open_action = QAction("Open plan…", window, shortcut=QKeySequence("Ctrl+Shift+O"),
                                   triggered=self.ask_open)
        self.save_action = QAction("Save plan…", window, shortcut=QKeySequence.Save, triggered=self.ask_save)
        quit_action = window.actionQuit
        menu.insertAction(quit_action, self.new_action)
        menu.insertAction(quit_action, self.open_action)
        menu.insertAction(quit_action, self.save_action)
        menu.insertSeparator(quit_action)

    def _plan_menu(self, window) -> None:
        """Plan: undo and redo (Ctrl+Z, Ctrl+Shift+Z) of every edit, the list's own actions, and Remove from
        vehicle, which is not an edit of the list."""
        menu = window.menuPlan = QMenu("&Plan", window)
        menu.setObjectName("menuPlan")
        stack = self.history.stack
        self.undo_action = stack.createUndoAction(window, "Undo")
        self.undo_action.setShortcut(QKeySequence("Ctrl+Z"))
        self.redo_action = stack.createRedoAction(window, "Redo")
        self.redo_action.setShortcuts([QKeySequence("Ctrl+Shift+Z"), QKeySequence("Ctrl+Y")])
        for action in (self.undo_action, self.redo_action):
            action.setShortcutContext(Qt.WindowShortcut)
            window.addAction(action)                    # the keys work with the menu closed
            menu.addAction(action)
        menu.addSeparator()
        menu.addAction(self.new_action)
        p = self.panel
        menu.addAction("Clear the list", lambda: self.editor.clear_layer(p.layer))
        menu.addAction("Move up", lambda: self.editor.move_selected(-1))
        menu.addAction("Move down", lambda: self.editor.move_selected(1))
        menu.addSeparator()
        menu.addAction("Remove from vehicle…", lambda: self.transfer("clear"))
        window.menuBar().insertMenu(window.menuSettings.menuAction(), menu)

    def ask_save(self) -> None:
        h = self._state.home
        self.files.ask_save([self.doc.plan(k) for k in PlanKind], (h.lat, h.lon, h.alt) if h is not None else None,
                            complex_items(self.doc))

    def ask_open(self) -> None:
        self._unless_losing_edits("Open another plan", self.files.ask_open)

    def ask_new(self) -> None:
        self._unless_losing_edits("Start a new plan", self._new)

    def _new(self) -> None:
        self.editor.new_plan()
        self.history.mark_saved()                # nothing to lose in an empty plan (Undo brings the old one back)

    def _unless_losing_edits(self, what: str, then) -> None:
        """``then()`` at once when every edit is saved; else ask: Save…, Discard edits, or Cancel (the default)."""
        if not self.history.modified:
            then()
            return
        if self.discard_question is not None:
            self.discard_question.reject()
        box, (save, discard) = self._warning("planDiscardQuestion", "Edits not saved",
                                             f"The plan has edits not saved to a file. {what} and lose them?",
                                             ("Save…", QMessageBox.AcceptRole),
                                             ("Discard edits", QMessageBox.DestructiveRole))

        def answered(b: QMessageBox) -> None:
            if self.discard_question is b:
                self.discard_question = None
            b.deleteLater()
            if b.clickedButton() is discard:
                then()
            elif b.clickedButton() is save:
                self.ask_save()
        self.discard_question = ask(box, answered)

    def _warning(self, name: str, title: str, text: str, *buttons) -> tuple[QMessageBox, list]:
        """A question whose default (Enter, Escape) is Cancel: nothing is lost by a key pressed too soon."""
        box = QMessageBox(QMessageBox.Warning, title, text, QMessageBox.NoButton, self._window)
        box.setObjectName(name)
        added = [box.addButton(label, role) for label, role in buttons]
        box.addButton(QMessageBox.Cancel)
        box.setDefaultButton(QMessageBox.Cancel)
        box.setEscapeButton(QMessageBox.Cancel)
        return box, added

    def ask_before_closing(self) -> bool:
        """Quitting with edits not saved: ask, and keep the window (True) until the pilot lets them go."""
        if self._may_close or not self.history.modified:
            return False

        def close() -> None:
            self._may_close = True
            self._window.close()
        self._unless_losing_edits("Quit", close)
        return True

    def _file_loaded(self, got) -> None:
        """An opened file replaces the plans it holds (a WPL file: one; a .plan: all three, its surveys kept)."""
        for plan in got.plans:
            if plan.kind is PlanKind.MISSION:
                entries, notes = mission_entries(got)
                self.editor.load_entries(entries)
                for note in notes:
                    self._window.log_message(f"Plan opened: {note}", Severity.NOTICE)
            else:
                self.editor.load(plan)
        self.history.mark_saved()
        if not self.dock.isVisible():
            self.show_plan(True)

    def show_plan(self, on: bool) -> None:
        """Plan mode: the Plan dock in Telemetry's place, editing on the map; off: Telemetry back."""
        if on == self.dock.isVisible() and on == self.plan_button.isChecked():
            return
        if on and not self._tabbed and self._window.dockWidgetArea(self.dock) == Qt.RightDockWidgetArea:
            self._window.tabifyDockWidget(self._window.telemetryDock, self.dock)
        self._tabbed = True
        leaving, coming = (self._window.telemetryDock, self.dock) if on else (self.dock, self._window.telemetryDock)
        leaving.hide()                          # first: never both shown, so never a tab bar's height more
        coming.show()
        coming.raise_()                         # the front tab where others share the place (Preflight on main)
        make_room_for_plan(self._window, self.dock, on)
        self.set_editing(on)

    def _dock_shown(self, shown: bool) -> None:
        """The dock closed or opened by itself (its close button, View › Plan): the map's button follows."""
        if self.plan_button.isChecked() != shown:
            self.plan_button.blockSignals(True)
            self.plan_button.setChecked(shown)
            self.plan_button.blockSignals(False)
            if not shown:
                self.set_editing(False)
                self._window.telemetryDock.setVisible(True)

    def set_editing(self, on: bool) -> None:
        """Clicks on the map add, drags move (the panel's "Edit on map")."""
        self.layer.editing = on
        if self.panel.editCheck.isChecked() != on:
            self.panel.editCheck.setChecked(on)
        if not on:
            self.layer.draft = []
        self.view.update()

    @property
    def home(self) -> tuple[float, float] | None:
        h = self._state.home
        return (h.lat, h.lon) if h is not None else None

    def _edited(self) -> None:
        self._shown = None
        self._show_vehicle(self._state)

    def sync(self, kind: PlanKind) -> str:
        """Why the plan here differs from the vehicle's ("" when it is the same, or neither has one)."""
        mine, theirs = self.doc.plan(kind), self.vehicle_plan(kind)
        if theirs is None:
            return f"the vehicle's {kind.label} is not known yet (Download reads it)" if mine.items else ""
        if self._synced.get(kind) == (mine, theirs):
            return ""                           # sent and read back, or downloaded: the driver compared them
        why = difference(mine, theirs, integer=True)
        return f"{len(theirs)} items there, {len(mine)} here" if why.endswith(f"instead of {len(mine)}") else why

    def vehicle_plan(self, kind: PlanKind) -> Plan | None:
        """What the vehicle holds, as the driver last confirmed it (read back, downloaded or cleared)."""
        known = self._state.mission.vehicle_plan(kind)
        return known if known is not None else self.on_vehicle.get(kind)

    # -- the vehicle ------------------------------------------------------------------------------------
    def _vehicle_changed(self, _drone) -> None:
        """Another vehicle is flown: nothing is known of its plans yet."""
        for known in (self.on_vehicle, self._sending, self._synced, self._outcome, self._failed, self._reread):
            known.clear()
        self._restarts, self._reread_due = None, False

    def _follow_restarts(self, s: VehicleState) -> None:
        """A vehicle that started again may hold other plans than before (wiped, or changed by another ground
        station meanwhile): what was known of them goes, and each is read again, into what the vehicle holds,
        never into the plan being edited here. A recording is only watched: its restarts are not read."""
        restarts = s.boot.restarts
        if self._restarts is None or restarts < self._restarts or self.adapter.replay is not None:
            self._restarts = restarts
            return
        if restarts > self._restarts:
            self._restarts = restarts
            for known in (self.on_vehicle, self._sending, self._synced):
                known.clear()
            self._reread, self._reread_due = set(PlanKind), True
            self._shown = None
        if self._reread_due and s.link.status is LinkStatus.OK:
            self._reread_due = False
            for kind in self._reread:
                self._outcome[kind] = f"The vehicle restarted: reading its {kind.label} again…"
                self.adapter.command("download_plan", kind)

    def show_state(self, s: VehicleState) -> None:
        old_home = self.home
        self._state = s
        self._follow_restarts(s)
        self.layer.home = self.editor.home = self.home
        perf = Performance.from_parameters(s.parameters)
        if perf != self.editor.perf or self.home != old_home:
            self.editor.perf = perf
            self.editor.refresh()
            self.view.update()
        else:
            self._show_vehicle(s)

    def _show_vehicle(self, s: VehicleState) -> None:
        m = s.mission
        kind = KINDS[self.panel.layer]
        key = (m, kind, self._doc_version(), s.mode, s.link.status, s.flying, self._outcome.get(kind), s.fence.enabled,
               s.camera.photos,
               tuple(self.on_vehicle.items()), _rounded(s))
        if key == self._shown:
            return
        self._shown = key
        p = self.panel
        transfer = m.transfer(kind)
        if transfer is not None and transfer.active:
            p.set_transfer(f"{_DIRECTION[transfer.direction]} {transfer.done}/{transfer.total or '?'}"
                           + (f" · {transfer.detail}" if transfer.detail else ""),
                           transfer.done, transfer.total, True)
        else:
            p.set_transfer(self._outcome.get(kind, "No transfer yet"), 1 if kind in self._outcome else 0, 1, False)
        whys = {k: self.sync(k) for k in PlanKind}   # each kind compared once per change
        for k in PlanKind:                      # a dot on each tab whose plan is not the vehicle's
            p.tabs.setTabText(list(KINDS.values()).index(k), ("● " if whys[k] else "") + _TITLES[k])
        why = whys[kind]
        theirs = self.vehicle_plan(kind)
        failed = f"{self._outcome[kind]}. " if self._failed.get(kind) else ""
        if why:
            sync = f"Differs from the vehicle's: {why}"
        elif theirs is not None:
            sync = f"Same as the vehicle's {kind.label} ({len(theirs)} items)"
        else:
            sync = f"No {kind.label} here; the vehicle's is not known yet"
        fence_off = fence_off_words(s) if kind is PlanKind.FENCE and (theirs or self.doc.fence) else ""
        p.syncLabel.setText(failed + sync + (f". {fence_off}" if fence_off else ""))
        p.syncLabel.setStyleSheet("color: #ffb020;" if why or failed or fence_off else "")
        # the mission's controls and progress: from the vehicle's mode and MISSION_CURRENT
        link_ok = s.link.status is LinkStatus.OK and self.adapter.replay is None     # a recording is only watched
        for button in (p.uploadButton, p.downloadButton, p.clearButton):
            button.setEnabled(button.isEnabled() and link_ok)
        mission_plan = self.vehicle_plan(PlanKind.MISSION)
        count = m.count if m.count is not None else (len(mission_plan) if mission_plan is not None else 0)
        running = s.mode == "AUTO" and s.flying and m.state is not MissionRunState.COMPLETE
        held = (s.flying and s.mode != "AUTO" and bool(m.current) and count > 0
                and m.state is not MissionRunState.COMPLETE)
        limits = m.limit_problems                # the driver's limits on the held mission (or no home yet)
        p.startButton.setEnabled(link_ok and count > 0 and not running and not limits)
        p.startButton.setToolTip(f"Not started: the mission's {'; '.join(limits)}" if limits else "")
        p.pauseButton.setEnabled(link_ok and running)
        p.resumeButton.setEnabled(link_ok and held)
        p.skip_allowed = link_ok and count > 0
        current = m.current if m.current and (running or held) and not whys[PlanKind.MISSION] else None
        drawn = (self.layer.current, self.layer.current_entry, self.layer.progress)
        self.layer.current = current
        entry = self.doc.entry_of_seq(current) if current else None
        if entry != self.layer.current_entry:
            self.layer.current_entry = entry
            self._refresh_rows_only()
        p.progressLabel.setText(self.progress_text(s, held))
        self.layer.progress = p.progressLabel.text() if running or held else ""
        if (self.layer.current, self.layer.current_entry, self.layer.progress) != drawn:
            self.view.update()                  # the map shows the current item and the progress: only on a change

    def _refresh_rows_only(self) -> None:
        table = self.panel.tables["mission"]
        for r in range(table.rowCount()):
            for c in range(table.columnCount()):
                item = table.item(r, c)
                if item is not None:
                    item.setBackground(Qt.darkGreen if r == self.layer.current_entry else Qt.transparent)

    def _doc_version(self) -> tuple:
        return (tuple(self.doc.entries), tuple(self.doc.fence), tuple(self.doc.rally))

    def progress_text(self, s: VehicleState, held: bool = False) -> str:
        """"Item N of M · WAYPOINT · 45 m, 9 s to it", from what the vehicle reports."""
        return progress_text(s, self.vehicle_plan(PlanKind.MISSION), self.editor.perf.cruise, held)

    # -- transfers ----------------------------------------------------------------------------------
    def transfer(self, action: str, confirmed: PlanKind | None = None) -> None:
        """Upload every plan that differs from the vehicle's (the tab shown's at least), Download the tab's, or
        Remove it from the vehicle (asked first; ``confirmed``: the kind the pilot said yes to); the driver's answers
        come back by themselves."""
        kind = confirmed if confirmed is not None else KINDS[self.panel.layer]
        if action == "upload":
            for k in self.to_upload():
                self._outcome[k] = f"Uploading the {k.label}…"
                self._sending[k] = self.doc.plan(k)
                self.adapter.command("upload_plan", self._sending[k])
            self._say_what_stays()
        elif action == "clear" and confirmed is None:
            self._ask_removal(kind)
            return
        elif action == "download":
            self._reread.discard(kind)          # the pilot's own download: into the list, as always
            self._outcome[kind] = f"Downloading the {kind.label}…"
            self.adapter.command("download_plan", kind)
        else:
            self._outcome[kind] = f"Clearing the {kind.label}…"
            self.adapter.command("clear_plan", kind)
        self._shown = None
        self._show_vehicle(self._state)

    def _say_what_stays(self) -> None:
        """A fence or rally points the vehicle keeps from before while this plan has none: said now, or once read
        (into what the vehicle holds only) when nothing is known of them."""
        for kind in (PlanKind.FENCE, PlanKind.RALLY):
            if self.doc.plan(kind).items or kind in self.to_upload():
                continue
            theirs = self.vehicle_plan(kind)
            if theirs is not None:
                self.notices.left_on_vehicle(kind, theirs)
            elif kind not in self._reread:
                self._left_behind.add(kind)
                self._reread.add(kind)
                self.adapter.command("download_plan", kind)

    def to_upload(self) -> list[PlanKind]:
        """The tab shown, and every other plan here that is not the vehicle's (one the vehicle holds but that is
        empty here is left there: removing is Remove from vehicle's, asked first)."""
        shown = KINDS[self.panel.layer]
        return [k for k in PlanKind if k is shown or (self.sync(k) and self.doc.plan(k).items)]

    def _ask_removal(self, kind: PlanKind) -> None:
        """Remove from vehicle asks first: it cannot be undone here (the list stays, Upload puts it back)."""
        theirs = self.vehicle_plan(kind)
        held = f"It holds {len(theirs)} items." if theirs is not None else "What it holds has not been read."
        box, (remove,) = self._warning("removeQuestion", f"Remove the {kind.label} from the vehicle",
                                       f"Remove the {kind.label} from the vehicle? {held}\n\n"
                                       "The list here stays as it is.",
                                       ("Remove from vehicle", QMessageBox.DestructiveRole))

        def answered(b: QMessageBox) -> None:
            b.deleteLater()
            if b.clickedButton() is remove:
                self.transfer("clear", confirmed=kind)
        self.remove_question = ask(box, answered)

    def _transfer_finished(self, name: str, outcome) -> None:
        result: CommandResult = outcome.result
        kind = outcome.plan.kind if outcome.plan is not None else _kind_of(result.command)
        if kind is None:
            return
        if result.ok and outcome.plan is not None:
            self.on_vehicle[kind] = outcome.plan
            if name == "download_plan" and kind in self._reread:
                self._reread.discard(kind)      # what the vehicle holds now; the plan here stays as it is
                if kind in self._left_behind:
                    self.notices.left_on_vehicle(kind, outcome.plan)
            elif name == "download_plan":
                self.editor.load(outcome.plan)
                self._synced[kind] = (self.doc.plan(kind), outcome.plan)
            elif kind in self._sending:         # the driver read it back and found it the same in meaning
                self._synced[kind] = (self._sending.pop(kind), outcome.plan)
                if kind is PlanKind.FENCE:
                    self.notices.fence_uploaded(self._state, outcome.plan)
        self._left_behind.discard(kind)
        self._outcome[kind] = str(result)
        self._failed[kind] = not result.ok
        self._shown = None
        self._show_vehicle(self._state)

    def command_finished(self, result: CommandResult) -> None:
        """A clear's answer (a CommandResult of its own): the vehicle holds nothing of that kind any more."""
        kind = _kind_of(result.command) if result.command.startswith("clear") else None
        if kind is None:
            return
        if result.ok:
            self.on_vehicle[kind] = Plan(kind, ())
        self._outcome[kind] = str(result)
        self._failed[kind] = not result.ok
        self._shown = None
        self._show_vehicle(self._state)

    # -- flying it ---------------------------------------------------------------------------------
    def ask_start(self) -> None:
        """One confirmation, like Take off: what will fly, and that from the ground it arms and takes off."""
        if self._question is not None and self._question.isVisible():
            return
        s = self._state
        plan = self.vehicle_plan(PlanKind.MISSION)
        count = s.mission.count if s.mission.count is not None else len(plan or ())
        text = f"Fly the vehicle's mission ({count} items) in AUTO?"
        if plan is not None and self.sync(PlanKind.MISSION):
            text += "\n\nIt differs from the plan shown here: the vehicle flies the one it holds."
        text += ("\n\nFrom the ground the motors start and it takes off. Keep clear of the propellers."
                 if not s.flying else "\n\nIt leaves what it is doing now and flies the mission.")
        text += "\nPause holds it where it is (BRAKE); Stop, Land and RTL stay available."
        self._question = ask(mission_start_question(self._window, text), self._start_answered)
        self.startAsked.emit(self._question)

    @property
    def question(self) -> QMessageBox | None:
        return self._question

    def _start_answered(self, box: QMessageBox) -> None:
        if box.clickedButton() is box.button(QMessageBox.Yes):
            if self._state.link.status is LinkStatus.OK:
                self.adapter.command("start_mission")
            else:
                self._window.log_message("Mission start not sent: no link to the vehicle", Severity.WARNING)
        box.deleteLater()
        if self._question is box:
            self._question = None

    def skip_to(self, seq: int) -> None:
        self.adapter.command("set_mission_item", seq)

    def _context(self, hit, actions: list) -> None:
        """Right click on the map: Skip to item N on a mission item; Delete in Plan mode."""
        if hit is None:
            return
        layer, index, _ = hit
        if layer == "mission":
            seq = self.doc.first_seq(index)
            if seq is not None and not self.sync(PlanKind.MISSION):
                actions.append((f"Skip to item {seq}", self.panel.skip_allowed, lambda: self.skip_to(seq)))
        if self.layer.editing:
            actions.append(("Delete", True, lambda: (self.editor.select(layer, index),
                                                     self.editor.delete_selected())))


def _kind_of(command: str) -> PlanKind | None:
    return next((k for k in PlanKind if command.endswith(k.label)), None)


def _rounded(s: VehicleState) -> tuple:
    """What the progress line shows of the vehicle's movement, to the metre."""
    pos = s.position
    return (round(pos.lat, 5), round(pos.lon, 5), round(s.velocity.ground_speed)) if pos is not None else ()
