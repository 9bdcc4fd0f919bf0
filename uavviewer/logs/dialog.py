"""Logs › Flight logs: the vehicle's DataFlash logs in a window of their own, beside the flying one (not modal:
Land and Stop stay a click away). Refresh, Download (the selected logs), Download all, Erase all (asked first),
the table, and a line that says what runs or why not. It shows the controller's rows and passes the pilot's clicks
on; the logic is the controller's."""
from __future__ import annotations

from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QDialog, QHBoxLayout, QLabel, QMessageBox, QPushButton, QVBoxLayout, QWidget

from ..widgets.ask import ask, cautious_question
from .rows import RowState
from .table import LogTable

__all__ = ["FlightLogsDialog"]


class FlightLogsDialog(QDialog):
    def __init__(self, controller, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.controller = c = controller
        self.setObjectName("flightLogsDialog")
        self.setWindowTitle("Flight logs")
        self.setModal(False)
        self.erase_box: QMessageBox | None = None
        self.status = QLabel()
        self.status.setObjectName("flightLogsStatus")
        self.status.setWordWrap(True)
        self.status.setTextInteractionFlags(Qt.TextSelectableByMouse)
        self.table = LogTable()
        self.folder = QLabel()
        self.folder.setObjectName("flightLogsFolder")
        self.folder.setTextInteractionFlags(Qt.TextSelectableByMouse)
        self.refresh_button = self._button("Refresh", "Ask the vehicle for its list of logs again", c.refresh)
        self.download_button = self._button("Download", "Download the selected logs, one after another",
                                            lambda: c.download(self.table.selected_ids()))
        self.download_all_button = self._button("Download all", "Every log not saved here yet", c.download_all)
        self.erase_button = self._button("Erase all…", "Erase every log on the vehicle (asks first)", self.ask_erase)
        close = self._button("Close", "The downloads go on with this window closed", self.close)
        buttons, ends = QHBoxLayout(), QHBoxLayout()        # two rows: it fits beside the flight controls
        for b in (self.refresh_button, self.download_button, self.download_all_button):
            buttons.addWidget(b)
        buttons.addStretch(1)
        ends.addWidget(self.erase_button)
        ends.addStretch(1)
        ends.addWidget(close)
        layout = QVBoxLayout(self)
        layout.addWidget(self.status)
        layout.addWidget(self.table, 1)
        layout.addWidget(self.folder)
        layout.addLayout(buttons)
        layout.addLayout(ends)
        self.resize(860, 420)
        self.table.actionClicked.connect(self._row_action)
        self.table.cellDoubleClicked.connect(lambda index, _column: c.open(self.table.ids[index]))  # a saved one
        self.table.itemSelectionChanged.connect(self._enable)
        c.rowsChanged.connect(self.show_rows)
        c.statusChanged.connect(self.status.setText)
        c.busyChanged.connect(lambda _busy: self._enable())
        self.show_rows(c.rows)
        self.status.setText(c.status)

    @staticmethod
    def _button(text: str, tip: str, slot) -> QPushButton:
        b = QPushButton(text)
        b.setToolTip(tip)
        b.setFocusPolicy(Qt.NoFocus)               # Space flies (Stop), even with this window in front
        b.setAutoDefault(False)
        b.clicked.connect(lambda _on: slot())
        return b

    def showEvent(self, event) -> None:  # noqa: N802
        why = self.controller.unavailable()
        if why:
            self.status.setText(why)
        self._enable()
        super().showEvent(event)

    def show_rows(self, rows) -> None:
        self.table.set_rows(rows)
        self.folder.setText(f"Saved in {self.controller.folder()}")
        self._enable()

    def _enable(self) -> None:
        able = not self.controller.unavailable()
        erasing_allowed = able and not self.controller.busy
        rows = self.controller.rows
        self.refresh_button.setEnabled(able)
        self.download_button.setEnabled(able and bool(self.table.selected_ids()))
        self.download_all_button.setEnabled(able and any(not r.running and r.state is not RowState.SAVED for r in rows))
        self.erase_button.setEnabled(erasing_allowed and bool(rows))

    def _row_action(self, log_id: int, what: str) -> None:
        if what == "Cancel":
            self.controller.cancel(log_id)
        elif what == "Open":
            self.controller.open(log_id)
        else:                                        # Download, Resume, Retry
            self.controller.download([log_id])

    def ask_erase(self) -> QMessageBox:
        """Erase all only after a click on the question's own button (Enter and Space say Cancel)."""
        n = len(self.controller.rows)
        box = cautious_question(self, "Erase every log?",
                                f"Erase all {n} logs on the vehicle? This cannot be undone. The files already "
                                "saved on this computer are kept.", "Erase all", "eraseLogsQuestion",
                                QMessageBox.Warning)
        self.erase_box = box
        return ask(box, lambda b: self.controller.erase() if b.clickedButton() is b.button(QMessageBox.Yes) else None)
