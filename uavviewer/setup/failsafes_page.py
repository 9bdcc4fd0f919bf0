"""Setup › Failsafes and fence: what the vehicle will do when the battery runs low, the radio or the ground
station is lost, the EKF fails or the fence is breached, in plain words from its parameters; a warning where a
combination leaves it with no failsafe. Change… opens the parameter on the Parameters page."""
from __future__ import annotations

from PyQt5.QtWidgets import QLabel, QPushButton, QTreeWidget, QTreeWidgetItem, QVBoxLayout, QWidget

from .failsafe_words import failsafe_lines

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
        text = item.text(1) if item is not None else ""
        name = text[text.rfind("(") + 1:].split(" ")[0] if "(" in text else "FS_THR_ENABLE"
        self._runner.open_parameter(name)

    def show_state(self, s) -> None:
        lines, warnings = failsafe_lines(s)
        if (lines, warnings) == self._shown:
            return
        self._shown = (lines, warnings)
        self.lines.clear()
        for area, words in lines:
            self.lines.addTopLevelItem(QTreeWidgetItem([area, words]))
        self.lines.resizeColumnToContents(0)
        self.warnings.setText("\n".join(warnings))
