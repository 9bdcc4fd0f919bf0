"""Help › Keys: every key and gamepad button, and what it does."""
from __future__ import annotations

from PyQt5 import uic
from PyQt5.QtWidgets import QDialog, QTableWidgetItem, QWidget

from .. import RESOURCES
from ..widgets.dialog_fit import FRAME_ALLOWANCE
from .gamepad_mapping import ACTIONS, CONTROLLER_BUTTONS
from .keyboard import key_help

__all__ = ["KeysDialog"]


class KeysDialog(QDialog):
    """Help > Keys, filled from the same tables the keyboard and the gamepad use."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        uic.loadUi(str(RESOURCES / "ui" / "keys_dialog.ui"), self)
        self.setObjectName("keysDialog")
        rows = key_help() + [(f"Gamepad {button.upper()}", ACTIONS[action])
                             for action, button in CONTROLLER_BUTTONS.items()]
        rows.append(("Gamepad sticks", "As the on-screen sticks (mode and mapping: Preferences › Gamepad)"))
        self.table.setColumnCount(2)
        self.table.setHorizontalHeaderLabels(["Key", "Action"])
        self.table.setRowCount(len(rows))
        for i, (key, text) in enumerate(rows):
            self.table.setItem(i, 0, QTableWidgetItem(key))
            self.table.setItem(i, 1, QTableWidgetItem(text))
        self.table.resizeColumnToContents(0)
        self._fit_rows()

    def _fit_rows(self) -> None:
        """Tall enough for every row, the last one too (as far as the screen allows; then it scrolls)."""
        t = self.table
        t.setWordWrap(False)                    # one line a row; the dialog is as wide as the longest
        t.resizeColumnsToContents()
        t.setMinimumWidth(sum(t.columnWidth(c) for c in range(t.columnCount())) + 2 * t.frameWidth() + 4)
        t.verticalHeader().setDefaultSectionSize(t.fontMetrics().height() + 6)   # compact rows: all in view
        needed = t.horizontalHeader().sizeHint().height() + 2 * t.frameWidth() + \
            sum(t.rowHeight(i) for i in range(t.rowCount())) + 6      # + the header's border
        screen = self.screen() if hasattr(self, "screen") else None
        limit = (screen.availableGeometry().height() - 110 - FRAME_ALLOWANCE if screen is not None  # intro, buttons,
                 else needed)                                                                      # a title bar
        t.setMinimumHeight(max(120, min(needed, limit)))
        self.adjustSize()                       # (Qt caps this at 2/3 of the screen: grow to what the rows need)
        if screen is not None:
            self.resize(self.sizeHint().boundedTo(screen.availableGeometry().size()))
        t.setMinimumSize(120, 120)              # that is its size, not its least: beside the flight controls it scrolls
