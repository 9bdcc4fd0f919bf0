"""File › Open plan… and Save plan…: QGroundControl ``.plan`` files (mission, fence and rally points together) and
``QGC WPL 110`` waypoint files (one plan), read and written by the driver's own readers (driver.mission.files).

The choosers are Qt's own, opened without waiting on them: the window keeps flying while one is open.
"""
from __future__ import annotations

import os

from PyQt5.QtCore import QObject, pyqtSignal
from PyQt5.QtWidgets import QFileDialog, QWidget

from driver.mission.files import PlanFile, PlanFileError, load_plan_file, save_plan_file
from driver.mission.plan import Plan
from driver.state import Severity

__all__ = ["PlanFiles", "FILTERS"]

FILTERS = "QGroundControl plan (*.plan);;Waypoint file, QGC WPL 110 (*.waypoints *.txt *.mission);;All files (*)"


class PlanFiles(QObject):
    loaded = pyqtSignal(object)              # PlanFile: every plan the file holds
    said = pyqtSignal(str, object)           # what happened, Severity

    def __init__(self, parent_window: QWidget, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._window = parent_window
        self.folder = os.path.expanduser("~")
        self.dialog: QFileDialog | None = None  # the chooser while open (tests answer it)

    def ask_open(self) -> QFileDialog:
        dialog = self._dialog("Open plan", QFileDialog.AcceptOpen)
        dialog.setFileMode(QFileDialog.ExistingFile)
        dialog.fileSelected.connect(self.open)
        dialog.open()
        return dialog

    def ask_save(self, plans, home, one: Plan) -> QFileDialog:
        """``plans``: all three, for a .plan; ``one``: the plan of the tab shown, for a WPL file."""
        dialog = self._dialog("Save plan", QFileDialog.AcceptSave)
        dialog.setDefaultSuffix("plan")
        dialog.fileSelected.connect(lambda path: self.save(path, plans, home, one))
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
            self.said.emit(f"Plan not opened: {os.path.basename(path)}: {exc}", Severity.WARNING)
            return None
        self.folder = os.path.dirname(path)
        self.loaded.emit(got)
        counts = ", ".join(f"{len(p)} {p.kind.label}" + ("" if p.kind.label.endswith("s") else " items")
                           for p in got.plans)
        self.said.emit(f"Plan opened from {path}: {counts}", Severity.INFO)
        return got

    def save(self, path: str, plans, home, one: Plan) -> bool:
        wpl = not path.lower().endswith(".plan")
        try:
            save_plan_file(path, (one,) if wpl else tuple(plans), home)
        except (OSError, PlanFileError) as exc:
            self.said.emit(f"Plan not saved: {exc}", Severity.WARNING)
            return False
        self.folder = os.path.dirname(path)
        what = f"the {one.kind.label} ({len(one)} items) as a WPL file" if wpl else "mission, fence and rally points"
        self.said.emit(f"Plan saved to {path}: {what}", Severity.INFO)
        return True
