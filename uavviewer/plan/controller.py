"""Plan mode: the Plan dock and the plan on the map, edited by :class:`~uavviewer.plan.editor.PlanEditor`, moved
to and from the vehicle by :class:`~uavviewer.plan.transfers.PlanTransfers`; here the mission is flown
(docs/missions-viewer.md).

Everything about the vehicle comes from its snapshots: what it holds (the plan read back after an upload, or
downloaded), its transfers' progress, the mission's state and current item. A plan is shown as uploaded, and a
mission as started, paused or resumed, only when the driver says the vehicle confirmed it. What the panel shows of
it is worked out in one place, without Qt (plan/vehicle_view.py), and applied at once.
"""
from __future__ import annotations

import logging

from PyQt5.QtCore import QObject, Qt, pyqtSignal
from PyQt5.QtGui import QKeySequence
from PyQt5.QtWidgets import QAction, QDockWidget, QMenu, QMessageBox, QScrollArea, QToolButton, QWidget

from driver.mission.plan import Plan, PlanKind
from driver.vehicle.state import LinkStatus, Severity, VehicleState

from ..widgets.ask import ask, cautious_question, warning_question
from .editor import PlanEditor
from .files import PlanFiles
from .layer import PlanLayer
from .model import Performance, PlanDocument
from .notices import UploadNotices
from .room import make_room_for_plan
from .panel import PlanPanel
from .progress import progress_text
from .survey_file import complex_items, mission_entries
from .transfers import PlanTransfers
from .vehicle_view import VehicleView, held_by_vehicle, vehicle_view

__all__ = ["PlanController"]

log = logging.getLogger(__name__)

KINDS = {"mission": PlanKind.MISSION, "fence": PlanKind.FENCE, "rally": PlanKind.RALLY}


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
        self._may_close = False                              # the pilot said their edits may go
        self.notices = UploadNotices(window, self)      # the fence off, a fence left from before: asked
        self.notices.said.connect(window.log_message)
        self.transfers = PlanTransfers(adapter, self.doc, self.editor, self.notices, window,
                                       lambda: KINDS[self.panel.layer], self)
        self.transfers.changed.connect(lambda: self._show_vehicle(self._state))
        self.notices.removeRequested.connect(lambda kind: self.transfers.transfer("clear", confirmed=kind))
        self._state = VehicleState()
        self._shown: VehicleView | None = None          # what the panel and the map last showed of the vehicle
        self._question: QMessageBox | None = None
        p = self.panel
        p.editToggled.connect(self.set_editing)
        p.transferRequested.connect(self.transfers.transfer)
        p.cancelRequested.connect(lambda: self.adapter.drone.cancel_transfer(KINDS[p.layer]))
        p.startRequested.connect(self.ask_start)
        p.pauseRequested.connect(lambda: self.adapter.send(self.adapter.drone.pause_mission))
        p.resumeRequested.connect(lambda: self.adapter.send(self.adapter.drone.resume_mission))
        p.skipRequested.connect(self.skip_to)
        self.layer.contextRequested.connect(self._context)
        adapter.stateChanged.connect(self.show_state)
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
        menu.addAction("Remove from vehicle…", lambda: self.transfers.transfer("clear"))
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
        box, (save, discard) = warning_question(self._window, "planDiscardQuestion", "Edits not saved",
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
        self._shown = None                      # the same view may now fall on another entry of the list
        self._show_vehicle(self._state)

    def show_state(self, s: VehicleState) -> None:
        old_home = self.home
        self._state = s
        self.transfers.follow(s)
        self.layer.home = self.editor.home = self.home
        perf = Performance.from_parameters(s.parameters)
        if perf != self.editor.perf or self.home != old_home:
            self.editor.perf = perf
            self.editor.refresh()
            self.view.update()
        else:
            self._show_vehicle(s)

    def _show_vehicle(self, s: VehicleState) -> None:
        """The panel and the map as :func:`~uavviewer.plan.vehicle_view.vehicle_view` works them out, applied only
        when what they show changes."""
        view = vehicle_view(s, self.transfers.facts(self.adapter.replay is not None, self.editor.perf.cruise))
        if view == self._shown:
            return
        self._shown = view
        self.panel.show_vehicle(view)
        drawn = (self.layer.current, self.layer.current_entry, self.layer.progress)
        self.layer.current = view.current
        entry = self.doc.entry_of_seq(view.current) if view.current else None
        if entry != self.layer.current_entry:
            self.layer.current_entry = entry
            self.panel.show_current_row(entry)
        self.layer.progress = view.on_map
        if (self.layer.current, self.layer.current_entry, self.layer.progress) != drawn:
            self.view.update()                  # the map shows the current item and the progress: only on a change

    # -- what the transfers know (PlanTransfers), as the tests and the window ask it ------------------------------
    @property
    def on_vehicle(self) -> dict[PlanKind, Plan]:
        return self.transfers.on_vehicle

    @property
    def remove_question(self) -> QMessageBox | None:
        return self.transfers.remove_question

    def how_it_differs(self, kind: PlanKind) -> str:
        return self.transfers.how_it_differs(kind)

    def vehicle_plan(self, kind: PlanKind) -> Plan | None:
        return self.transfers.vehicle_plan(kind)

    def progress_text(self, s: VehicleState, held: bool = False) -> str:
        """"Item N of M · WAYPOINT · 45 m, 9 s to it", from what the vehicle reports."""
        theirs = held_by_vehicle(s, self.transfers.on_vehicle, PlanKind.MISSION)
        return progress_text(s, theirs, self.editor.perf.cruise, held)

    # -- flying it ---------------------------------------------------------------------------------
    def ask_start(self) -> None:
        """One confirmation, like Take off: what will fly, and that from the ground it arms and takes off."""
        if self._question is not None and self._question.isVisible():
            return
        s = self._state
        plan = self.vehicle_plan(PlanKind.MISSION)
        count = s.mission.count if s.mission.count is not None else len(plan or ())
        text = f"Fly the vehicle's mission ({count} items) in AUTO?"
        if plan is not None and self.how_it_differs(PlanKind.MISSION):
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
                self.adapter.send(self.adapter.drone.start_mission)
            else:
                self._window.log_message("Mission start not sent: no link to the vehicle", Severity.WARNING)
        box.deleteLater()
        if self._question is box:
            self._question = None

    def skip_to(self, seq: int) -> None:
        self.adapter.send(self.adapter.drone.set_mission_item, seq)

    def _context(self, hit, actions: list) -> None:
        """Right click on the map: Skip to item N on a mission item; Delete in Plan mode."""
        if hit is None:
            return
        layer, index, _ = hit
        if layer == "mission":
            seq = self.doc.first_seq(index)
            if seq is not None and not self.how_it_differs(PlanKind.MISSION):
                actions.append((f"Skip to item {seq}", self.panel.skip_allowed, lambda: self.skip_to(seq)))
        if self.layer.editing:
            actions.append(("Delete", True, lambda: (self.editor.select(layer, index),
                                                     self.editor.delete_selected())))

