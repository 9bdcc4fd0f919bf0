"""Plan mode: edit the mission, fence and rally points on the map and in the list, move them to and from the
vehicle, and fly the mission (docs/missions-viewer.md).

Everything about the vehicle comes from its snapshots: what it holds (the plan read back after an upload, or
downloaded), its transfers' progress, the mission's state and current item. A plan is shown as uploaded, and a
mission as started, paused or resumed, only when the driver says the vehicle confirmed it.
"""
from __future__ import annotations

import logging
import math
from dataclasses import replace

from PyQt5.QtCore import QObject, Qt, pyqtSignal
from PyQt5.QtWidgets import QDockWidget, QMessageBox, QScrollArea, QToolButton

from driver.frames import offset_ned
from driver.mission.wire import difference
from driver.mission.plan import MissionItem, MissionRunState, Plan, PlanKind, TransferDirection
from driver.state import CommandResult, LinkStatus, Severity, VehicleState
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..dialogs import ask, mission_start_question
from .plan_layer import PlanLayer
from .plan_model import ITEM_KINDS, FenceShape, Performance, PlanDocument, is_nav, new_item
from .plan_panel import PlanPanel
from .survey import SurveySpec, camera_named

__all__ = ["PlanController"]

log = logging.getLogger(__name__)

KINDS = {"mission": PlanKind.MISSION, "fence": PlanKind.FENCE, "rally": PlanKind.RALLY}
CIRCLE_RADIUS = 30.0          # m: a new fence circle, then edited in the list
DEFAULT_ALTITUDE = 10.0       # m above home: the first waypoint's, later ones take the one before's
_TITLES = {PlanKind.MISSION: "Mission", PlanKind.FENCE: "Fence", PlanKind.RALLY: "Rally"}
_DIRECTION = {TransferDirection.UPLOAD: "Uploading", TransferDirection.DOWNLOAD: "Downloading",
              TransferDirection.CLEAR: "Clearing"}


class PlanController(QObject):
    startAsked = pyqtSignal(object)           # the Start mission question, open (tests answer it)
    changed = pyqtSignal()                    # the plan being edited changed

    def __init__(self, map_controller, adapter, window, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.map = map_controller
        self.view = map_controller.view
        self.adapter = adapter
        self._window = window
        self.doc = PlanDocument()
        self.layer = PlanLayer(self.doc, self)
        self.view.overlays.append(self.layer)
        self.panel = PlanPanel()
        self.dock = self._dock(window)
        self.plan_button = self._map_button(map_controller.panel)
        self.tool = "Waypoint"
        self.selected: tuple[str, int] | None = None
        self.on_vehicle: dict[PlanKind, Plan] = {}      # what each transfer last confirmed the vehicle holds
        self._sending: dict[PlanKind, Plan] = {}        # each kind's upload under way
        self._synced: dict[PlanKind, tuple[Plan, Plan]] = {}   # (here, there) the driver last found the same
        self._outcome: dict[PlanKind, str] = {}         # each kind's last transfer, in words
        self._state = VehicleState()
        self._perf = Performance()
        self._shown: tuple | None = None                # what the flying part last showed (redrawn on change)
        self._question: QMessageBox | None = None
        p = self.panel
        p.editToggled.connect(self.set_editing)
        p.toolChanged.connect(self._tool)
        p.layerChanged.connect(lambda _layer: self.refresh())
        p.addRequested.connect(self.add_without_place)
        p.deleteRequested.connect(self.delete_selected)
        p.finishRequested.connect(self.finish_shape)
        p.rowSelected.connect(self.select)
        p.cellEdited.connect(self.edit_cell)
        p.surveyEdited.connect(self._survey_edited)
        p.transferRequested.connect(self.transfer)
        p.cancelRequested.connect(lambda: self.adapter.drone.cancel_transfer(KINDS[p.layer]))
        p.startRequested.connect(self.ask_start)
        p.pauseRequested.connect(lambda: self.adapter.command("pause_mission"))
        p.resumeRequested.connect(lambda: self.adapter.command("resume_mission"))
        p.skipRequested.connect(self.skip_to)
        self.layer.clicked.connect(self.click)
        self.layer.picked.connect(self.select)
        self.layer.dragged.connect(self.drag)
        self.layer.contextRequested.connect(self._context)
        adapter.stateChanged.connect(self.show_state)
        adapter.transferFinished.connect(self._transfer_finished)
        adapter.commandFinished.connect(self.command_finished)
        self.refresh()

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
        dock.hide()
        window.addDockWidget(Qt.RightDockWidgetArea, dock)      # tabbed with Telemetry when first shown: tabbed
        window.menuView.addAction(dock.toggleViewAction())      # now, the window would lay out for a tab bar
        self._tabbed = False
        dock.visibilityChanged.connect(lambda _shown: self._dock_shown(dock.isVisible()))
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
        if on:                                  # the map beside the list, as tall as the list
            w = self._window
            w.mapDock.raise_()
            w.resizeDocks([self.dock, w.mapDock], [1, 1], Qt.Vertical)
        if on:
            self.dock.raise_()
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

    # -- editing ------------------------------------------------------------------------------------
    def _tool(self, tool: str) -> None:
        if tool != self.tool:
            self.tool = tool
            self.layer.draft = []
            self.refresh()
            self.view.update()

    @property
    def home(self) -> tuple[float, float] | None:
        h = self._state.home
        return (h.lat, h.lon) if h is not None else None

    def _altitude_before(self, index: int) -> float:
        alts = [e.altitude if isinstance(e, SurveySpec) else e.alt for e in self.doc.entries[:index]
                if isinstance(e, SurveySpec) or (is_nav(e) and e.alt > 0)]
        return alts[-1] if alts else DEFAULT_ALTITUDE

    def _where(self) -> int:
        """Where a new mission entry goes: before the selected one in Insert mode, else at the end."""
        if self.panel.insertCheck.isChecked() and self.selected and self.selected[0] == "mission":
            return self.selected[1]
        return len(self.doc.entries)

    def _takeoff_first(self, index: int) -> int:
        """A first place to fly to in an empty mission brings a takeoff before it: ArduCopter starts a mission
        from the ground only with one. Returns where the new entry goes now."""
        if index == 0 and not any(isinstance(e, MissionItem) and e.command == mavlink.MAV_CMD_NAV_TAKEOFF
                                   for e in self.doc.entries):
            self.doc.insert(0, new_item(mavlink.MAV_CMD_NAV_TAKEOFF, alt=DEFAULT_ALTITUDE))
            return 1
        return index

    def click(self, lat: float, lon: float) -> None:
        """A click on free map in Plan mode: add what the tool says there."""
        layer, tool = self.panel.layer, self.tool
        if layer == "mission" and tool in ITEM_KINDS:
            index = self._where()
            if tool in ("Waypoint", "Loiter (time)"):
                index = self._takeoff_first(index)
            item = new_item(ITEM_KINDS[tool], lat, lon, self._altitude_before(index))
            self._select("mission", self.doc.insert(index, item))
        elif tool.endswith("circle"):
            self.doc.fence.append(FenceShape(tool.startswith("Inclusion"), ((lat, lon),), CIRCLE_RADIUS))
            self._select("fence", len(self.doc.fence) - 1)
        elif layer == "rally":
            self.doc.rally.append(MissionItem(mavlink.MAV_CMD_NAV_RALLY_POINT, lat=lat, lon=lon,
                                              alt=self._perf.rtl_alt))
            self._select("rally", len(self.doc.rally) - 1)
        else:                                       # a corner of a survey area or a fence polygon
            self.layer.draft.append((lat, lon))
        self._changed()

    def finish_shape(self) -> None:
        """The polygon being drawn becomes a survey or a fence polygon (three corners at least)."""
        draft, self.layer.draft = self.layer.draft, []
        if len(draft) >= 3:
            if self.tool == "Survey area":
                v = self.panel.survey_values()
                spec = SurveySpec(tuple(draft), v["altitude"], camera_named(v["camera"]), v["front"], v["side"],
                                  v["angle"])
                self._select("mission", self.doc.insert(self._takeoff_first(self._where()), spec))
            else:
                self.doc.fence.append(FenceShape(self.tool.startswith("Inclusion"), tuple(draft)))
                self._select("fence", len(self.doc.fence) - 1)
        self._changed()

    def add_without_place(self, what: str) -> None:
        """+ Takeoff (first), + RTL, + Speed (before the selected item, else at the end)."""
        command = ITEM_KINDS[what]
        if command == mavlink.MAV_CMD_NAV_TAKEOFF:
            index = 0
            alt = self._altitude_before(len(self.doc.entries))
        else:
            index = self.selected[1] if (what == "Change speed" and self.selected and self.selected[0] == "mission") \
                else self._where()
            alt = 0.0
        self._select("mission", self.doc.insert(index, new_item(command, alt=alt, speed=self._perf.cruise)))
        self._changed()

    def delete_selected(self) -> None:
        if self.selected is None:
            return
        layer, i = self.selected
        items = {"mission": self.doc.entries, "fence": self.doc.fence, "rally": self.doc.rally}[layer]
        if 0 <= i < len(items):
            del items[i]
        self._select(layer, min(i, len(items) - 1) if items else None)
        self._changed()

    def drag(self, layer: str, index: int, vertex: int, lat: float, lon: float) -> None:
        if layer == "mission":
            entry = self.doc.entries[index]
            if isinstance(entry, SurveySpec):
                polygon = list(entry.polygon)
                polygon[vertex] = (lat, lon)
                self.doc.entries[index] = replace(entry, polygon=tuple(polygon))
            else:
                self.doc.move(index, lat, lon)
        elif layer == "fence":
            shape = self.doc.fence[index]
            vertices = list(shape.vertices)
            vertices[vertex] = (lat, lon)
            self.doc.fence[index] = replace(shape, vertices=tuple(vertices))
        else:
            self.doc.rally[index] = replace(self.doc.rally[index], lat=lat, lon=lon)
        self._changed()

    def select(self, layer: str, index: int) -> None:
        if KINDS[layer] is not KINDS[self.panel.layer]:
            self.panel.tabs.setCurrentIndex(list(KINDS).index(layer))
        self._select(layer, index)
        self.refresh()

    def _select(self, layer: str, index: int | None) -> None:
        self.selected = (layer, index) if index is not None else None
        self.layer.selected = self.selected

    def edit_cell(self, layer: str, row: int, column: str, value: float) -> None:
        """A value typed in the list: altitude, speed (a DO_CHANGE_SPEED before the item), hold, radius."""
        if layer == "mission" and 0 <= row < len(self.doc.entries):
            entry = self.doc.entries[row]
            if column == "Alt m" and math.isfinite(value) and value > 0:
                if isinstance(entry, SurveySpec):
                    self.doc.entries[row] = replace(entry, altitude=value)
                else:
                    self.doc.set_altitude(row, value)
            elif column == "Speed m/s":
                row = self.doc.set_speed(row, value if math.isfinite(value) and value > 0 else None)
            elif column == "Hold s" and math.isfinite(value):
                self.doc.set_hold(row, value)
            self._select("mission", row)
        elif layer == "fence" and column == "Radius m" and 0 <= row < len(self.doc.fence) and value > 0:
            self.doc.fence[row] = replace(self.doc.fence[row], radius=value)
        elif layer == "rally" and column == "Alt m" and 0 <= row < len(self.doc.rally) and value > 0:
            self.doc.rally[row] = replace(self.doc.rally[row], alt=value)
        self._changed()

    def _survey_edited(self, v: dict) -> None:
        if self.selected and self.selected[0] == "mission":
            entry = self.doc.entries[self.selected[1]]
            if isinstance(entry, SurveySpec):
                self.doc.entries[self.selected[1]] = replace(
                    entry, altitude=v["altitude"], camera=camera_named(v["camera"]), front_overlap=v["front"],
                    side_overlap=v["side"], angle=v["angle"])
                self._changed()

    def load(self, plan: Plan) -> None:
        """A plan from the vehicle or a file replaces the one of its kind being edited."""
        self.doc.load(plan)
        self._select({PlanKind.MISSION: "mission", PlanKind.FENCE: "fence", PlanKind.RALLY: "rally"}[plan.kind],
                     None)
        self._changed()

    def _changed(self) -> None:
        self.refresh()
        self.view.update()
        self.changed.emit()

    # -- showing it ---------------------------------------------------------------------------------
    def refresh(self) -> None:
        """The list, the survey box, the totals and the vehicle part, from the document and the last state."""
        p, doc = self.panel, self.doc
        seqs = []
        seq = 0
        for entry in doc.entries:
            seqs.append(seq + 1)
            seq += len(doc.survey_of(entry).items) if isinstance(entry, SurveySpec) else 1
        p.row_seq = seqs
        speeds = doc.leg_speeds(self._perf.cruise)
        rows, editable = [], []
        for i, entry in enumerate(doc.entries):
            if isinstance(entry, SurveySpec):
                s = doc.survey_of(entry)
                rows.append((seqs[i], f"Survey: {len(s.passes)} passes, {s.photos} photos",
                             f"{entry.altitude:g}", f"{speeds[i]:g}", ""))
                editable.append((False, False, True, True, False))
                continue
            nav = is_nav(entry)
            hold = entry.param1 if entry.command in (mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_CMD_NAV_LOITER_TIME) \
                else None
            name = _describe(entry)
            alt_ok = entry.command not in (mavlink.MAV_CMD_NAV_LAND, mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH) and (
                nav or entry.has_position)
            speed = entry.param2 if entry.command == mavlink.MAV_CMD_DO_CHANGE_SPEED else speeds[i] if nav else None
            rows.append((seqs[i], name, f"{entry.alt:g}" if alt_ok else "", "" if speed is None else f"{speed:g}",
                         "" if hold is None else f"{hold:g}"))
            editable.append((False, False, alt_ok, speed is not None, hold is not None))
        sel = self.selected
        current_entry = self.layer.current_entry
        p.set_rows("mission", rows, editable, sel[1] if sel and sel[0] == "mission" else None, current_entry)
        p.set_rows("fence", [(s.label, len(s.vertices) if not s.circle else "", f"{s.radius:g}" if s.circle else "")
                             for s in doc.fence], [(False, False, s.circle) for s in doc.fence],
                   sel[1] if sel and sel[0] == "fence" else None)
        p.set_rows("rally", [(i + 1, f"{r.alt:g}") for i, r in enumerate(doc.rally)],
                   [(False, True) for _ in doc.rally], sel[1] if sel and sel[0] == "rally" else None)
        entry = doc.entries[sel[1]] if sel and sel[0] == "mission" and 0 <= sel[1] < len(doc.entries) else None
        if isinstance(entry, SurveySpec):
            s = doc.survey_of(entry)
            p.set_survey({"camera": entry.camera.name, "altitude": entry.altitude, "front": entry.front_overlap,
                          "side": entry.side_overlap, "angle": entry.angle},
                         f"GSD {s.gsd:.2f} cm/px · {len(s.passes)} passes {s.spacing:.1f} m apart · photo every "
                         f"{s.trigger_distance:.1f} m, {s.photos} photos · {s.area / 10000:.2f} ha")
        else:
            p.set_survey({"camera": p.cameraCombo.currentText(), "altitude": p.altitudeSpin.value(),
                          "front": p.frontSpin.value() / 100, "side": p.sideSpin.value() / 100,
                          "angle": p.angleSpin.value()}, "Click the area's corners on the map, then Finish shape")
            p.surveyBox.setVisible(self.tool == "Survey area" and p.layer == "mission")
        p.finishButton.setVisible(self.tool in ("Survey area", "Inclusion polygon", "Exclusion polygon"))
        totals = doc.totals(self.home, self._perf)
        p.totalsLabel.setText(("Plan: " + totals.text()) if self.home is not None else
                              "Plan totals need the vehicle's home position")
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
    def show_state(self, s: VehicleState) -> None:
        old_home = self.home
        self._state = s
        self.layer.home = self.home
        perf = Performance.from_parameters(s.parameters)
        if perf != self._perf or self.home != old_home:
            self._perf = perf
            self.refresh()
            self.view.update()
        else:
            self._show_vehicle(s)

    def _show_vehicle(self, s: VehicleState) -> None:
        m = s.mission
        kind = KINDS[self.panel.layer]
        key = (m, kind, self._doc_version(), s.mode, s.link.status, s.flying, self._outcome.get(kind),
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
        for k in PlanKind:                      # a dot on each tab whose plan is not the vehicle's
            p.tabs.setTabText(list(KINDS.values()).index(k), ("● " if self.sync(k) else "") + _TITLES[k])
        why = self.sync(kind)
        theirs = self.vehicle_plan(kind)
        p.syncLabel.setText(f"Differs from the vehicle's: {why}" if why else
                            f"Same as the vehicle's {kind.label} ({len(theirs)} items)" if theirs is not None else
                            f"No {kind.label} here; the vehicle's is not known yet")
        p.syncLabel.setStyleSheet("color: #ffb020;" if why else "")
        # the mission's controls and progress: from the vehicle's mode and MISSION_CURRENT
        link_ok = s.link.status is LinkStatus.OK
        mission_plan = self.vehicle_plan(PlanKind.MISSION)
        count = m.count if m.count is not None else (len(mission_plan) if mission_plan is not None else 0)
        running = s.mode == "AUTO" and s.flying and m.state is not MissionRunState.COMPLETE
        held = (s.flying and s.mode != "AUTO" and bool(m.current) and count > 0
                and m.state is not MissionRunState.COMPLETE)
        p.startButton.setEnabled(link_ok and count > 0 and not running)
        p.pauseButton.setEnabled(link_ok and running)
        p.resumeButton.setEnabled(link_ok and held)
        p.skip_allowed = link_ok and count > 0
        current = m.current if m.current and (running or held) and not self.sync(PlanKind.MISSION) else None
        self.layer.current = current
        entry = self.doc.entry_of_seq(current) if current else None
        if entry != self.layer.current_entry:
            self.layer.current_entry = entry
            self._refresh_rows_only()
        p.progressLabel.setText(self.progress_text(s, held))
        self.view.update()

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
        m = s.mission
        if m.state is MissionRunState.UNKNOWN and m.count is None:
            return "Mission: the vehicle has not said yet"
        if m.state is MissionRunState.NO_MISSION or not m.count:
            return "No mission on the vehicle"
        if m.state is MissionRunState.COMPLETE:
            return f"Mission complete ({m.count} items)"
        if not m.current or not (s.flying or m.state is MissionRunState.ACTIVE):
            return f"Mission of {m.count} items on the vehicle, not flying"
        plan = self.vehicle_plan(PlanKind.MISSION)
        item = plan.items[m.current - 1] if plan is not None and 1 <= m.current <= len(plan.items) else None
        name = m.current_name or (item.name if item is not None else "")
        text = f"Item {m.current} of {m.count}" + (f" · {name}" if name else "")
        if held:
            text += f" · paused ({s.mode})"
        to = self._to_item(s, item)
        if to is not None:
            text += f" · {to[0]:.0f} m, {to[1]:.0f} s to it"
        return text

    def _to_item(self, s: VehicleState, item: MissionItem | None) -> tuple[float, float] | None:
        pos = s.position
        if item is None or pos is None or not (item.lat or item.lon) or not item.has_position:
            return None
        north, east = offset_ned(pos.lat, pos.lon, item.lat, item.lon)
        d = math.hypot(north, east)
        speed = s.velocity.ground_speed if s.velocity.ground_speed > 0.5 else self._perf.cruise
        return d, d / max(speed, 0.1)

    # -- transfers ----------------------------------------------------------------------------------
    def transfer(self, action: str) -> None:
        """Upload, Download or Clear the plan of the tab shown; the driver's answer comes back by itself."""
        kind = KINDS[self.panel.layer]
        if action == "upload":
            self._outcome[kind] = f"Uploading the {kind.label}…"
            self._sending[kind] = self.doc.plan(kind)
            self.adapter.command("upload_plan", self._sending[kind])
        elif action == "download":
            self._outcome[kind] = f"Downloading the {kind.label}…"
            self.adapter.command("download_plan", kind)
        else:
            self._outcome[kind] = f"Clearing the {kind.label}…"
            self.adapter.command("clear_plan", kind)
        self._shown = None
        self._show_vehicle(self._state)

    def _transfer_finished(self, name: str, outcome) -> None:
        result: CommandResult = outcome.result
        kind = outcome.plan.kind if outcome.plan is not None else _kind_of(result.command)
        if kind is None:
            return
        if result.ok and outcome.plan is not None:
            self.on_vehicle[kind] = outcome.plan
            if name == "download_plan":
                self.load(outcome.plan)
                self._synced[kind] = (self.doc.plan(kind), outcome.plan)
            elif kind in self._sending:         # the driver read it back and found it the same in meaning
                self._synced[kind] = (self._sending.pop(kind), outcome.plan)
        self._outcome[kind] = str(result)
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
            actions.append(("Delete", True, lambda: (self.select(layer, index), self.delete_selected())))


def _describe(item: MissionItem) -> str:
    c = item.command
    if c == mavlink.MAV_CMD_DO_CHANGE_SPEED:
        return "Change speed"
    if c == mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH:
        return "RTL"
    if c == mavlink.MAV_CMD_NAV_LOITER_TIME:
        return "Loiter (time)"
    if c in (mavlink.MAV_CMD_DO_SET_ROI, mavlink.MAV_CMD_DO_SET_ROI_LOCATION):
        return "ROI"
    if c == mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST:
        return f"Camera every {item.param1:g} m" if item.param1 > 0 else "Camera off"
    return item.name.replace("_", " ").title()


def _kind_of(command: str) -> PlanKind | None:
    return next((k for k in PlanKind if command.endswith(k.label)), None)


def _rounded(s: VehicleState) -> tuple:
    """What the progress line shows of the vehicle's movement, to the metre."""
    pos = s.position
    return (round(pos.lat, 5), round(pos.lon, 5), round(s.velocity.ground_speed)) if pos is not None else ()
