"""Setup › Summary: firmware, then one line per area (done / needs attention and why / not applicable)."""
from __future__ import annotations

from PyQt5.QtWidgets import QLabel, QTreeWidget, QTreeWidgetItem, QVBoxLayout, QWidget

from .summary import ATTENTION, DONE, summary

__all__ = ["SummaryPage"]

_MARK = {DONE: "✔ done", ATTENTION: "⚠ needs attention"}


class SummaryPage(QWidget):
    title = "Summary"

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        layout = QVBoxLayout(self)
        self.firmware = QLabel("Firmware: not reported yet")
        self.firmware.setObjectName("setupFirmware")
        layout.addWidget(self.firmware)
        self.lines = QTreeWidget()
        self.lines.setHeaderLabels(["Area", "State", "Why"])
        self.lines.setRootIsDecorated(False)
        layout.addWidget(self.lines)
        self._shown: list = []

    def show_state(self, s) -> None:
        board = {2: "quadcopter", 13: "hexacopter", 14: "octocopter", 4: "helicopter"}.get(s.vehicle_type, "")
        self.firmware.setText(f"Firmware: ArduCopter {s.firmware or '(version not reported yet)'}"
                              + (f" — {board} (MAV_TYPE {s.vehicle_type})" if board else "")
                              + " — board: not reported on this link")
        lines = summary(s)
        if lines == self._shown:
            return
        self._shown = lines
        self.lines.clear()
        for line in lines:
            self.lines.addTopLevelItem(QTreeWidgetItem([line.area, _MARK.get(line.verdict, line.verdict), line.why]))
        for column in range(2):
            self.lines.resizeColumnToContents(column)

    def verdict(self, area: str) -> str:
        return next((line.verdict for line in self._shown if line.area == area), "")
