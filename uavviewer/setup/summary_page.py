"""Setup › Summary: the firmware and the board as the vehicle told them (its banner and AUTOPILOT_VERSION,
driver.setup.banner), then one line per area (done / needs attention and why / not applicable)."""
from __future__ import annotations

from PyQt5.QtWidgets import QLabel, QTreeWidget, QTreeWidgetItem, QVBoxLayout, QWidget

from .summary import ATTENTION, DONE, summary

__all__ = ["SummaryPage", "firmware_words"]

_MARK = {DONE: "✔ done", ATTENTION: "⚠ needs attention"}


class SummaryPage(QWidget):
    title = "Summary"

    def __init__(self, runner, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._runner = runner
        layout = QVBoxLayout(self)
        self.firmware = QLabel("Firmware: not reported yet")
        self.firmware.setObjectName("setupFirmware")
        self.firmware.setWordWrap(True)
        layout.addWidget(self.firmware)
        self.lines = QTreeWidget()
        self.lines.setHeaderLabels(["Area", "State", "Why"])
        self.lines.setRootIsDecorated(False)
        layout.addWidget(self.lines)
        self._shown: list = []

    def show_state(self, s) -> None:
        no_setup = self._runner.no_setup()
        self.firmware.setText(firmware_words(s, no_setup))
        lines = summary(s, no_setup)
        if lines == self._shown:
            return
        self._shown = lines
        self.lines.clear()
        for line in lines:
            item = QTreeWidgetItem([line.area, _MARK.get(line.verdict, line.verdict), line.why])
            item.setToolTip(2, line.why)                # the whole of it where the column cuts it
            self.lines.addTopLevelItem(item)
        for column in range(2):
            self.lines.resizeColumnToContents(column)

    def verdict(self, area: str) -> str:
        return next((line.verdict for line in self._shown if line.area == area), "")


def firmware_words(s, no_setup: str = "") -> str:
    """"ArduCopter V4.6.3, board: CubeOrange", the frame's MAV_TYPE, and what is not known and why."""
    a = s.autopilot
    if a.firmware_line:
        firmware = " ".join(a.firmware_line.split()[:2])          # "ArduCopter V4.6.3", its git hash left out
    elif s.firmware:
        firmware = f"ArduCopter {s.firmware}"
    else:
        firmware = "ArduCopter, version not reported" + (" on this link" if no_setup else " yet")
    kind = {2: "quadcopter", 13: "hexacopter", 14: "octocopter", 4: "helicopter", 15: "tricopter"}.get(s.vehicle_type)
    board = f"not reported on this link ({no_setup})" if no_setup and not a.board else a.board_words()
    details = [d for d in (a.os_line, a.frame_line[len("Frame: "):] if a.frame_line else "",
                           f"{kind} (MAV_TYPE {s.vehicle_type})" if kind else "") if d]
    return f"{firmware}, board: {board}" + (f"\n{'; '.join(details)}" if details else "")
