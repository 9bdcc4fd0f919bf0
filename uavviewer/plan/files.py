"""File › Open plan… and Save plan…: QGroundControl ``.plan`` files (mission, fence and rally points together, its
surveys as surveys) and ``QGC WPL 110`` waypoint files, read and written by the driver's own readers
(driver.mission.files).

The type chosen in the chooser is the type written (a name typed without its ending gets the chosen type's), and
a WPL file is always the mission, whichever tab is shown: the format holds one plan, and Mission Planner and
MAVProxy read it as a mission. What it cannot hold (a fence, rally points, a survey's settings) is said.

The choosers are Qt's own, opened without waiting on them: the window keeps flying while one is open. A file that
cannot be read or written is said in a warning over the window, where the pilot chose it (in Messages alone it
went unseen at 1024×600, Messages behind the map), and that the plan shown is as it was.
"""
from __future__ import annotations

import os

from PyQt5.QtCore import QObject, pyqtSignal
from PyQt5.QtWidgets import QComboBox, QFileDialog, QMessageBox, QWidget

from driver.mission.files import PlanFile, PlanFileError, load_plan_file, save_plan_file
from driver.mission.plan import Plan, PlanKind
from driver.vehicle.state import Severity

from ..widgets.ask import ask

__all__ = ["PlanFiles", "FILTERS"]

PLAN_FILTER = "QGroundControl plan (*.plan)"
WPL_FILTER = "Waypoint file, QGC WPL 110: the mission only (*.waypoints *.txt *.mission)"
FILTERS = f"{PLAN_FILTER};;{WPL_FILTER};;All files (*)"


class PlanFiles(QObject):
    loaded = pyqtSignal(object)              # PlanFile: every plan the file holds
    said = pyqtSignal(str, object)           # what happened, Severity
    saved = pyqtSignal(str)                  # the path written (the plan's edits are safe there)

    def __init__(self, parent_window: QWidget, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._window = parent_window
        self.folder = os.path.expanduser("~")
        self.dialog: QFileDialog | None = None  # the chooser while open (tests answer it)
        self.error_box: QMessageBox | None = None   # why a file was not opened or saved, while shown

    def ask_open(self) -> QFileDialog:
        dialog = self._dialog("Open plan", QFileDialog.AcceptOpen)
        dialog.setFileMode(QFileDialog.ExistingFile)
        dialog.fileSelected.connect(self.open)
        dialog.open()
        return dialog

    def ask_save(self, plans, home, complex_items=()) -> QFileDialog:
        """``plans``: all three (a WPL file takes the mission); ``complex_items``: the mission's surveys."""
        dialog = self._dialog("Save plan", QFileDialog.AcceptSave)
        dialog.setDefaultSuffix("plan")
        # a name typed without its ending gets the type chosen (Qt's dialog appends the default suffix); the
        # type list is followed however it changes (a click, the keys, selectNameFilter)
        types = dialog.findChild(QComboBox, "fileTypeCombo")
        types.currentTextChanged.connect(lambda f: dialog.setDefaultSuffix("waypoints" if f == WPL_FILTER else "plan"))
        dialog.fileSelected.connect(lambda path: self.save(path, plans, home, complex_items))
        dialog.open()
        return dialog

    def _dialog(self, title: str, mode) -> QFileDialog:
        dialog = QFileDialog(self._window, title, self.folder, FILTERS)
        dialog.setObjectName("planFileDialog")
        dialog.setAcceptMode(mode)
        dialog.setOptions(QFileDialog.DontUseNativeDialog)
        dialog.finished.connect(dialog.deleteLater)
        self.dialog = dialog
        return dialog

    def open(self, path: str) -> PlanFile | None:
        try:
            got = load_plan_file(path)
        except (OSError, UnicodeDecodeError, PlanFileError) as exc:
            self._failed("Plan not opened", f"{os.path.basename(path)}: {exc}",
                         "The plan on the map is as it was, its edits too: nothing was discarded.")
            return None
        self.folder = os.path.dirname(path)
        self.loaded.emit(got)
        counts = ", ".join(f"{len(p)} {p.kind.label}" + ("" if p.kind.label.endswith("s") else " items")
                           for p in got.plans)
        self.said.emit(f"Plan opened from {path}: {counts}", Severity.INFO)
        return got

    def _failed(self, what: str, why: str, kept: str) -> None:
        """In Messages, and in a warning over the window (not waited on: the window flies on)."""
        self.said.emit(f"{what}: {why}", Severity.WARNING)
        if self.error_box is not None:
            self.error_box.reject()
        box = QMessageBox(QMessageBox.Warning, what, f"{what}: {why}\n\n{kept}", QMessageBox.Close, self._window)
        box.setObjectName("planFileError")
        self.error_box = ask(box, lambda b: setattr(self, "error_box", None) if self.error_box is b else None)

    def save(self, path: str, plans, home, complex_items=()) -> bool:
        wpl = not path.lower().endswith(".plan")
        plans = tuple(plans)
        mission = next((p for p in plans if p.kind is PlanKind.MISSION), Plan(PlanKind.MISSION))
        try:
            if wpl:
                save_plan_file(path, (mission,), home)
            else:
                save_plan_file(path, plans, home, complex_items)
        except (OSError, PlanFileError) as exc:
            self._failed("Plan not saved", str(exc), "Its edits are still here, not saved to a file.")
            return False
        self.folder = os.path.dirname(path)
        if wpl:
            left = [f"the {p.kind.label} ({len(p)} items)" for p in plans if p.kind is not PlanKind.MISSION and p.items]
            left += ["the surveys' settings (they are saved as their waypoints)"] if complex_items else []
            what = f"the mission ({len(mission)} items) as a WPL file" + (
                f"; a WPL file cannot hold {' and '.join(left)}: save a .plan to keep them" if left else "")
            severity = Severity.WARNING if left else Severity.INFO
        else:
            what, severity = "mission, fence and rally points", Severity.INFO
        self.said.emit(f"Plan saved to {path}: {what}", severity)
        self.saved.emit(path)
        return True
