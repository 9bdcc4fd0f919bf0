"""The autopilot's words and the outcome of every command, newest at the bottom.

Quiet by design: a line said again right after itself is counted on that line ("PreArm: GPS 1: Bad fix (×3)"),
and a burst of the same command (a wheel turned notch by notch: gimbal pitch -5°, -10°, -15°) is one line that
shows the burst's latest outcome: one line per gesture.
"""
from __future__ import annotations

import re
import time as _time

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtGui import QBrush, QColor
from PyQt5.QtWidgets import QAbstractItemView, QHeaderView, QToolButton, QTreeWidget, QTreeWidgetItem, QWidget

from driver.vehicle.state import CommandResult, CommandStatus, Severity

__all__ = ["MessagesView", "severity_color", "GESTURE_GAP"]

GESTURE_GAP = 2.0              # s: the same command's outcomes closer than this are one gesture, one line
_COUNT, _BASE, _GESTURE = Qt.UserRole + 1, Qt.UserRole + 2, Qt.UserRole + 3
_NUMBER = re.compile(r"^[-+]?\d+(\.\d+)?[°%a-z/]*,?$")    # "-35°", "3", "40.28," (a name like "solo-1:" is not)

_COLORS = {
    Severity.EMERGENCY: "#ff3b3b", Severity.ALERT: "#ff3b3b", Severity.CRITICAL: "#ff3b3b",
    Severity.ERROR: "#ff6b5b", Severity.WARNING: "#ffb020", Severity.NOTICE: "#8fd0ff",
    Severity.INFO: "#d8dee6", Severity.DEBUG: "#7d8792",
}
_RESULT_SEVERITY = {
    CommandStatus.ACCEPTED: Severity.INFO, CommandStatus.IN_PROGRESS: Severity.INFO,
    CommandStatus.REFUSED: Severity.ERROR, CommandStatus.TIMED_OUT: Severity.WARNING,
    CommandStatus.REJECTED: Severity.WARNING, CommandStatus.ABORTED: Severity.NOTICE,
}


def severity_color(severity: Severity) -> str:
    return _COLORS.get(Severity(severity), "#d8dee6")


class MessagesView(QTreeWidget):
    """Time · source · text, coloured by severity; keeps the last ``limit`` lines. A line naming a parameter
    can carry a Fix… button (:meth:`offer_fix`) that opens it on the Parameters page."""
    fixRequested = pyqtSignal(str)             # a line's Fix… was clicked: the parameter it names

    def __init__(self, parent: QWidget | None = None, limit: int = 500) -> None:
        super().__init__(parent)
        self.setObjectName("messagesView")
        self._limit = limit
        self.setColumnCount(3)
        self.setHeaderLabels(["Time", "From", "Message"])
        self.setRootIsDecorated(False)
        self.setUniformRowHeights(True)
        self.setSelectionMode(QAbstractItemView.NoSelection)
        self.setFocusPolicy(Qt.NoFocus)
        self.setMinimumHeight(30)              # its header on 1024×600: the latest line is in the status strip
        header = self.header()
        header.setSectionResizeMode(0, QHeaderView.ResizeToContents)
        header.setSectionResizeMode(1, QHeaderView.ResizeToContents)
        header.setStretchLastSection(True)
        self._fix_column = 3                   # Fix… buttons, added with the first one
        # the newest line in view, also for lines added while hidden (a tab behind Map): scrolled to the bottom
        # while hidden, it opened at the top; scrolled up by the pilot, it stays where it was put
        self._newest = True
        bar = self.verticalScrollBar()
        bar.rangeChanged.connect(lambda _low, high: self._newest and bar.setValue(high))
        bar.valueChanged.connect(lambda value: self.isVisible() and setattr(self, "_newest",
                                                                             value >= bar.maximum()))

    def add_message(self, when: float, severity: Severity, text: str, source: str = "vehicle",
                    gesture: str = "") -> QTreeWidgetItem:
        """A line; the same line as the last one is counted on it instead (×N). ``gesture``: a command's kind
        (its name without numbers): its outcome replaces the last line's when that was the same kind, moments
        ago."""
        last = self.topLevelItem(self.topLevelItemCount() - 1) if self.topLevelItemCount() else None
        if last is not None and last.text(1) == source and last.data(0, Qt.UserRole) == int(severity) \
                and last.data(0, _BASE) == text:
            self._put(last, when, severity, text, last.data(0, _COUNT) + 1)
            return last
        if gesture and last is not None and last.data(0, _GESTURE) == gesture \
                and (when - last.data(0, _GESTURE + 1) <= GESTURE_GAP or "superseded by" in last.data(0, _BASE)):
            # (a step the next one superseded is that one's line however long the vehicle took to answer it)
            self._put(last, when, severity, text, 1)
            return last
        item = QTreeWidgetItem(["", source, ""])
        item.setData(0, _GESTURE, gesture)
        self._put(item, when, severity, text, 1)
        self.addTopLevelItem(item)
        while self.topLevelItemCount() > self._limit:
            self.takeTopLevelItem(0)
        if self._newest:
            self.scrollToBottom()
        return item

    def showEvent(self, event) -> None:  # noqa: N802 (Qt's name)
        super().showEvent(event)
        if self._newest:
            self.scrollToBottom()

    @staticmethod
    def _put(item: QTreeWidgetItem, when: float, severity: Severity, text: str, count: int) -> None:
        shown = f"{text} (×{count})" if count > 1 else text
        item.setText(0, _time.strftime("%H:%M:%S", _time.localtime(when)))
        item.setText(2, shown)
        brush = QBrush(QColor(severity_color(severity)))
        for col in range(3):
            item.setForeground(col, brush)
        item.setData(0, Qt.UserRole, int(severity))
        item.setData(0, _COUNT, count)
        item.setData(0, _BASE, text)
        item.setData(0, _GESTURE + 1, when)
        item.setToolTip(2, shown)

    def add_result(self, result: CommandResult, when: float | None = None) -> None:
        severity = _RESULT_SEVERITY.get(result.status, Severity.INFO)
        gesture = " ".join(w for w in result.command.split() if not _NUMBER.match(w))
        self.add_message(_time.time() if when is None else when, severity, str(result), "command", gesture)

    def offer_fix(self, item: QTreeWidgetItem, name: str) -> QToolButton:
        """A Fix… button at the end of ``item``'s line that asks to open parameter ``name``."""
        if self.columnCount() <= self._fix_column:
            self.setColumnCount(self._fix_column + 1)
            self.headerItem().setText(self._fix_column, "")
            header = self.header()
            header.setStretchLastSection(False)
            header.setSectionResizeMode(2, QHeaderView.Stretch)
            header.setSectionResizeMode(self._fix_column, QHeaderView.ResizeToContents)
        button = QToolButton()
        button.setObjectName("fixButton")
        button.setText("Fix…")
        button.setToolTip(f"Open {name} on the Parameters page")
        button.setStyleSheet("QToolButton { color: #8cb8ff; border: 1px solid #34475c; border-radius: 4px;"
                             " padding: 0 6px; background: #22303f; } QToolButton:hover { background: #2b3d51; }")
        button.clicked.connect(lambda: self.fixRequested.emit(name))
        item.setData(self._fix_column, Qt.UserRole, name)
        self.setItemWidget(item, self._fix_column, button)
        return button

    def fix_button(self, row: int) -> QToolButton | None:
        """The Fix… button of line ``row`` (None if it names no parameter)."""
        item = self.topLevelItem(row)
        return self.itemWidget(item, self._fix_column) if item is not None else None

    # -- for tests ----------------------------------------------------------------------------
    def texts(self) -> list[str]:
        return [self.topLevelItem(i).text(2) for i in range(self.topLevelItemCount())]

    def severities(self) -> list[int]:
        return [self.topLevelItem(i).data(0, Qt.UserRole) for i in range(self.topLevelItemCount())]
