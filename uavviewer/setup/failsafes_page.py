"""Setup › Failsafes and fence: what the vehicle will do when the battery runs low, the radio or the ground
station is lost, the EKF fails or the fence is breached, in plain words from its parameters; a warning where a
combination leaves it with no failsafe. Change… opens the parameter on the Parameters page."""
from __future__ import annotations

from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QLabel, QPushButton, QTreeWidget, QTreeWidgetItem, QVBoxLayout, QWidget

from .failsafe_words import failsafes

__all__ = ["FailsafesPage"]


class FailsafesPage(QWidget):
    title = "Failsafes"

    def __init__(self, runner, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._runner = runner
        layout = QVBoxLayout(self)
        self.lines = QTreeWidget()
        self.lines.setHeaderLabels(["When", "The vehicle"])
        self.lines.setRootIsDecorated(False)
        layout.addWidget(self.lines, 1)
        self.warnings = QLabel("")
        self.warnings.setObjectName("setupFailsafeWarnings")
        self.warnings.setWordWrap(True)
        self.warnings.setStyleSheet("color: #c62828; font-weight: bold")
        layout.addWidget(self.warnings)
        change = QPushButton("Change in Parameters…")
        change.clicked.connect(self._change)
        layout.addWidget(change)
        self._shown = None

    def _change(self) -> None:
        item = self.lines.currentItem()
        name = item.data(0, Qt.UserRole) if item is not None else None     # the row's own parameter
        self._runner.open_parameter(name or "FS_THR_ENABLE")

    def show_state(self, s) -> None:
        got = failsafes(s)
        lines, warnings = got.lines, got.warnings
        if (lines, warnings) == self._shown:
            return
        self._shown = (lines, warnings)
        self.lines.clear()
        for area, words, name in lines:
            item = QTreeWidgetItem([area, words])
            item.setData(0, Qt.UserRole, name)
            self.lines.addTopLevelItem(item)
        self.lines.resizeColumnToContents(0)
        self.warnings.setText("\n".join(warnings))
