"""Editing the plan in Plan mode: what a click, a drag, the Add menu, Delete and the list's cells do to the
:class:`~uavviewer.plan.model.PlanDocument`, and the list, survey box and totals shown from it.

The vehicle's part (transfers, flying, progress) is :class:`uavviewer.plan.controller.PlanController`'s.
"""
from __future__ import annotations

import math
from dataclasses import replace

from PyQt5.QtCore import QObject, pyqtSignal
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.mission.plan import MissionItem, Plan, PlanKind

from .checks import outside_fence, unreachable
from .history import PlanHistory
from .model import ITEM_KINDS, FenceShape, Performance, PlanDocument, is_nav, new_item
from .survey import SurveySpec, camera_named

__all__ = ["PlanEditor", "LAYER_OF"]

LAYER_OF = {PlanKind.MISSION: "mission", PlanKind.FENCE: "fence", PlanKind.RALLY: "rally"}
CIRCLE_RADIUS = 30.0          # m: a new fence circle, then edited in the list
DEFAULT_ALTITUDE = 10.0       # m above home: the first waypoint's, later ones take the one before's


class PlanEditor(QObject):
    refreshed = pyqtSignal()                 # the list was shown again from the document

    def __init__(self, doc: PlanDocument, layer, panel, view, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.doc, self.layer, self.panel, self.view = doc, layer, panel, view
        self.tool = "Waypoint"
        self.selected: tuple[str, int] | None = None
        self.home: tuple[float, float] | None = None     # the vehicle's; totals and the path start there
        self.perf = Performance()
        self.history = PlanHistory(doc, self)
        self.history.restored.connect(self._restored)
        self._gesture = 0                                # each press on an item starts a new drag (undo step)
        p = panel
        p.toolChanged.connect(self._tool)
        p.layerChanged.connect(lambda _layer: self.refresh())
        p.addRequested.connect(self.add_without_place)
        p.deleteRequested.connect(self.delete_selected)
        p.finishRequested.connect(self.finish_shape)
        p.rowSelected.connect(self.select)
        p.moveRequested.connect(self.move_selected)
        p.rowsDropped.connect(self.move_rows)
        p.cellEdited.connect(self.edit_cell)
        p.surveyEdited.connect(self._survey_edited)
        layer.clicked.connect(self.click)
        layer.picked.connect(self._picked)
        layer.dragged.connect(self.drag)

    # -- editing ------------------------------------------------------------------------------------
    def _tool(self, tool: str) -> None:
        if tool != self.tool:
            self.tool = tool
            self.layer.draft = []
            self.refresh()
            self.view.update()

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
                                              alt=self.perf.rtl_alt))
            self._select("rally", len(self.doc.rally) - 1)
        else:                                       # a corner of a survey area or a fence polygon
            self.layer.draft.append((lat, lon))
        self._changed(f"Add {tool}")

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
        self._changed(f"Add {self.tool}")

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
        self._select("mission", self.doc.insert(index, new_item(command, alt=alt, speed=self.perf.cruise)))
        self._changed(f"Add {what}")

    def _items(self, layer: str) -> list:
        return {"mission": self.doc.entries, "fence": self.doc.fence, "rally": self.doc.rally}[layer]

    def _rows(self) -> tuple[str, list[int]]:
        """The tab's selected rows (several with Shift or Ctrl), else the item selected on the map."""
        layer = self.panel.layer
        rows = self.panel.selected_rows(layer)
        if not rows and self.selected is not None:
            layer, rows = self.selected[0], [self.selected[1]]
        return layer, [r for r in rows if 0 <= r < len(self._items(layer))]

    def delete_selected(self) -> None:
        """Delete the selected item(s): the list's selected rows, or the item picked on the map."""
        layer, rows = self._rows()
        if not rows:
            return
        items = self._items(layer)
        for r in sorted(rows, reverse=True):
            del items[r]
        first = min(rows)
        self._select(layer, min(first, len(items) - 1) if items else None)
        self._changed("Delete" if len(rows) == 1 else f"Delete {len(rows)} items")

    def move_selected(self, step: int) -> None:
        """The selected item(s) one place up (``step`` -1) or down (+1) in their list."""
        layer, rows = self._rows()
        items = self._items(layer)
        if not rows or min(rows) + step < 0 or max(rows) + step >= len(items):
            return
        rows = sorted(rows, reverse=step > 0)
        for r in rows:
            items[r], items[r + step] = items[r + step], items[r]
        self._select(layer, rows[-1] + step if step > 0 else rows[0] + step)
        self._changed("Move up" if step < 0 else "Move down")
        self.panel.select_rows(layer, [r + step for r in rows])

    def move_rows(self, layer: str, rows: list[int], before: int) -> None:
        """Rows dragged in the list: their items go before row ``before`` (as it was counted before the move)."""
        items = self._items(layer)
        rows = sorted(r for r in set(rows) if 0 <= r < len(items))
        if not rows:
            return
        moving = [items[r] for r in rows]
        at = max(0, min(before, len(items))) - sum(r < before for r in rows)
        rest = [item for r, item in enumerate(items) if r not in rows]
        items[:] = rest[:at] + moving + rest[at:]
        self._select(layer, at)
        self._changed("Move by dragging")
        self.panel.select_rows(layer, list(range(at, at + len(moving))))

    def clear_layer(self, layer: str) -> None:
        """Clear the editor's tab (the vehicle keeps what it holds): one undoable step."""
        self._items(layer).clear()
        if layer == "fence":
            self.doc.fence_extra.clear()
        self.layer.draft = []
        self._select(layer, None)
        self._changed(f"Clear the {layer}")

    def new_plan(self) -> None:
        """Everything empty: mission, fence and rally points (undoable; the vehicle keeps what it holds)."""
        for layer in LAYER_OF.values():
            self._items(layer).clear()
        self.doc.fence_extra.clear()
        self.layer.draft = []
        self._select("mission", None)
        self._changed("New plan")

    def _picked(self, layer: str, index: int) -> None:
        self._gesture += 1                          # a drag that follows is one undo step of its own
        self.select(layer, index)

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
        self._changed("Move on the map", ("drag", self._gesture, layer, index, vertex))

    def select(self, layer: str, index: int) -> None:
        if layer != self.panel.layer:
            self.panel.tabs.setCurrentIndex(list(LAYER_OF.values()).index(layer))
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
        self._changed(f"Edit {column}")

    def _survey_edited(self, v: dict) -> None:
        if self.selected and self.selected[0] == "mission":
            entry = self.doc.entries[self.selected[1]]
            if isinstance(entry, SurveySpec):
                self.doc.entries[self.selected[1]] = replace(
                    entry, altitude=v["altitude"], camera=camera_named(v["camera"]), front_overlap=v["front"],
                    side_overlap=v["side"], angle=v["angle"])
                self._changed("Edit the survey", ("survey", self.selected[1]))

    def load(self, plan: Plan) -> None:
        """A plan from the vehicle or a file replaces the one of its kind being edited."""
        self.doc.load(plan)
        self._select(LAYER_OF[plan.kind], None)
        self._changed(f"Load the {plan.kind.label}")

    def load_entries(self, entries: list) -> None:
        """A mission opened from a file, its surveys kept surveys (uavviewer.plan.survey_file)."""
        self.doc.entries = list(entries)
        self._select("mission", None)
        self._changed("Open the mission")

    def _changed(self, what: str = "Edit", merge=None) -> None:
        """After every edit: one undo step (``merge``: steps with the same key in a row are one), shown again."""
        self.history.record(what, merge)
        self.refresh()
        self.view.update()

    def _restored(self) -> None:
        """An undo or redo replaced the document: the selection is kept where it still exists."""
        if self.selected is not None and not 0 <= self.selected[1] < len(self._items(self.selected[0])):
            self._select(self.selected[0], None)
        self.layer.draft = []
        self.refresh()
        self.view.update()

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
        speeds = doc.leg_speeds(self.perf.cruise)
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
        warnings = unreachable(doc.entries, seqs)
        self.layer.breaches = fenced = outside_fence(doc, seqs, self.home)   # marked on the map too
        for i, why in fenced.rows.items():
            warnings[i] = f"{warnings[i]}; {why}" if i in warnings else why
        p.set_rows("mission", rows, editable, sel[1] if sel and sel[0] == "mission" else None, current_entry,
                   warnings)
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
        totals = doc.totals(self.home, self.perf)
        totals_text = ("Plan: " + totals.text()) if self.home is not None else \
            "Plan totals need the vehicle's home position"
        p.totalsLabel.setText(f"{totals_text} · cruise {self.perf.cruise_text()}")
        p.totalsLabel.setToolTip(self.perf.cruise_source())
        p.totalsLabel.setStyleSheet("color: #ff4d4d;" if totals.beyond_reserve else "")
        self.refreshed.emit()


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
