"""The table both dialogs show: a parameter per row, ticked to act on it, the notes column stretching."""
from __future__ import annotations

from PyQt5.QtWidgets import QAbstractItemView, QHeaderView, QTableWidget

__all__ = ["checklist"]

#: A tick box that shows when it is empty too (the window's style draws only QCheckBox's).
_STYLE = ("QTableWidget::indicator { width: 13px; height: 13px; border: 1px solid #6b7d91; border-radius: 3px;"
          " background: #0d1117; }"
          "QTableWidget::indicator:checked { background: #2f81f7; border-color: #8cb8ff; }")


def checklist(rows: int, headers: list[str], stretch: int) -> QTableWidget:
    """A read-only table of ``rows`` rows; every column fits its contents except ``stretch``."""
    table = QTableWidget(rows, len(headers))
    table.setStyleSheet(_STYLE)
    table.setHorizontalHeaderLabels(headers)
    table.verticalHeader().hide()
    table.setSelectionMode(QAbstractItemView.NoSelection)
    table.setEditTriggers(QAbstractItemView.NoEditTriggers)
    header = table.horizontalHeader()
    for column in range(len(headers)):
        header.setSectionResizeMode(column, QHeaderView.Stretch if column == stretch else QHeaderView.ResizeToContents)
    return table
