"""The Flight logs table: a row a log (number, date, size, a progress bar, the rate, the time left) and one button
that does what the row allows now: Download, Resume, Cancel, Open or Retry.

It draws the controller's rows and says what the pilot clicked; it decides nothing. Rows are updated in place (five
times a second while a log downloads), so the selection and the buttons stay under the cursor.
"""
from __future__ import annotations

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import QAbstractItemView, QHeaderView, QProgressBar, QPushButton, QTableWidget, \
    QTableWidgetItem, QWidget

from .rows import LogRow, RowState, date_text, rate_text, size_text, time_left_text

__all__ = ["LogTable", "COLUMNS"]

COLUMNS = ("Log", "Date (UTC)", "Size", "Progress", "Rate", "Time left", "")
PROGRESS, ACTION = 3, 6


def action_of(row: LogRow) -> str:
    if row.running:
        return "Cancel"
    return {RowState.SAVED: "Open", RowState.PARTIAL: "Resume", RowState.FAILED: "Retry"}.get(row.state, "Download")


def bar_text(row: LogRow) -> str:
    percent = f"{100 * row.fraction:.0f} %"
    if row.state is RowState.DOWNLOADING:
        return f"{percent}  {size_text(row.held)} of {size_text(row.size)}"
    if row.state in (RowState.FAILED, RowState.PARTIAL) and row.reason:
        return row.reason
    if row.state is RowState.PARTIAL:
        return f"{percent} kept, resumable"
    return row.state.value


class LogTable(QTableWidget):
    """``actionClicked(log_id, what)``: the row's button was pressed ("Download", "Cancel", "Open", ...)."""

    actionClicked = pyqtSignal(int, str)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(0, len(COLUMNS), parent)
        self.setObjectName("flightLogsTable")
        self.setHorizontalHeaderLabels(COLUMNS)
        self.setSelectionBehavior(QAbstractItemView.SelectRows)
        self.setSelectionMode(QAbstractItemView.ExtendedSelection)
        self.setEditTriggers(QAbstractItemView.NoEditTriggers)
        self.verticalHeader().setVisible(False)
        header = self.horizontalHeader()
        for column in range(len(COLUMNS)):
            header.setSectionResizeMode(column, QHeaderView.ResizeToContents)
        header.setSectionResizeMode(PROGRESS, QHeaderView.Stretch)
        self.ids: list[int] = []

    def set_rows(self, rows: tuple[LogRow, ...]) -> None:
        ids = [r.log_id for r in rows]
        if ids != self.ids:                       # another list: the rows are made again
            self.setRowCount(0)
            self.setRowCount(len(rows))
            self.ids = ids
            for index, row in enumerate(rows):
                self._make(index, row)
        for index, row in enumerate(rows):
            self._show(index, row)

    def selected_ids(self) -> list[int]:
        return sorted({self.ids[i.row()] for i in self.selectionModel().selectedRows()})

    def bar(self, log_id: int) -> QProgressBar:
        return self.cellWidget(self.ids.index(log_id), PROGRESS)

    def button(self, log_id: int) -> QPushButton:
        return self.cellWidget(self.ids.index(log_id), ACTION)

    def text(self, log_id: int, column: int) -> str:
        return self.item(self.ids.index(log_id), column).text()

    def _make(self, index: int, row: LogRow) -> None:
        for column in (0, 1, 2, 4, 5):
            item = QTableWidgetItem()
            item.setTextAlignment(Qt.AlignRight | Qt.AlignVCenter if column != 1 else Qt.AlignLeft | Qt.AlignVCenter)
            self.setItem(index, column, item)
        bar = QProgressBar()
        bar.setRange(0, 1000)
        bar.setTextVisible(True)
        self.setCellWidget(index, PROGRESS, bar)
        button = QPushButton()
        button.setFocusPolicy(Qt.NoFocus)          # Space flies (Stop): it never presses a button here
        button.clicked.connect(lambda _on, log_id=row.log_id: self.actionClicked.emit(log_id, button.text()))
        self.setCellWidget(index, ACTION, button)

    def _show(self, index: int, row: LogRow) -> None:
        texts = {0: str(row.log_id), 1: date_text(row.time_utc), 2: size_text(row.size), 4: rate_text(row),
                 5: time_left_text(row)}
        for column, text in texts.items():
            item = self.item(index, column)
            if item.text() != text:
                item.setText(text)
        bar = self.cellWidget(index, PROGRESS)
        bar.setValue(int(round(1000 * row.fraction)))
        bar.setFormat(bar_text(row))
        bar.setToolTip(row.reason or row.path)
        button = self.cellWidget(index, ACTION)
        button.setText(action_of(row))
        button.setToolTip(row.path if row.openable else "")
