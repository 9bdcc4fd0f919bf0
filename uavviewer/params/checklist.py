"""The table both dialogs show: a parameter per row, ticked to act on it, the notes column stretching."""
from __future__ import annotations

from PyQt5.QtWidgets import QAbstractItemView, QHeaderView, QTableWidget

__all__ = ["checklist"]


def checklist(rows: int, headers: list[str], stretch: int) -> QTableWidget:
    """A read-only table of ``rows`` rows; every column fits its contents except ``stretch``."""
    table = QTableWidget(rows, len(headers))
    table.setHorizontalHeaderLabels(headers)
    table.verticalHeader().hide()
    table.setSelectionMode(QAbstractItemView.NoSelection)
    table.setEditTriggers(QAbstractItemView.NoEditTriggers)
    header = table.horizontalHeader()
    for column in range(len(headers)):
        header.setSectionResizeMode(column, QHeaderView.Stretch if column == stretch else QHeaderView.ResizeToContents)
    return table
