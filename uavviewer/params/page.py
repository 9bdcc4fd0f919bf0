"""The Parameters page: groups on the left, the searchable table in the middle, the editor on the right, the
download's progress on top and the pending changes at the bottom. It shows and asks; the controller acts."""
from __future__ import annotations

import re

from PyQt5.QtCore import QItemSelectionModel, QModelIndex, Qt, QTimer, pyqtSignal
from PyQt5.QtGui import QKeySequence
from PyQt5.QtWidgets import (
    QAbstractItemView, QCheckBox, QFileDialog, QHBoxLayout, QHeaderView, QLabel, QLineEdit, QListWidget,
    QListWidgetItem, QProgressBar, QPushButton, QShortcut, QSplitter, QTableView, QVBoxLayout, QWidget,
)

from driver.params.model import ParameterTable

from ..widgets.dialog_fit import closes_with_esc, scrollable, stack_when_narrow
from .editor import ParamEditor
from .filter_model import ParameterFilter
from .table_model import Column, NAME_ROLE, ParameterModel
from .values import group_of

__all__ = ["ParametersPage"]

_OF = re.compile(r"(\d+) of (\d+)")

#: The page's own look, on top of the window's style sheet (resources/style.qss).
STYLE = """
QLabel#paramTitle { font-size: 17px; font-weight: bold; color: #e6ebf0; }
QLabel#paramFacts { color: #b8c4d0; }
QLabel#paramWarning { color: #ffb020; }
QLabel#paramReboot { color: #8fd0ff; }
QLabel#paramError { color: #ff6b5b; }
QLabel#paramDescription { color: #c9d3dd; }
QLabel#pendingLabel[pending="true"] { color: #ffd27a; font-weight: bold; }
QFrame#paramEditor { background: #11161d; border: 1px solid #262d36; border-radius: 6px; }
QTableView#paramTable { alternate-background-color: #1a2029; gridline-color: #232a33; }
QPushButton#reviewButton:enabled { background: #1f5fa8; border-color: #2f81f7; }
"""

PARAM_FILES = "Parameter files (*.param *.parm *.txt);;All files (*)"
SAVE_FORMATS = "MAVProxy: NAME VALUE (*.param);;Mission Planner: NAME,VALUE (*.param)"
METADATA_FILES = "ArduPilot parameter metadata (*.xml);;All files (*)"


class ParametersPage(QWidget):
    refreshRequested = pyqtSignal()              # download every parameter again
    compareFileChosen = pyqtSignal(str)          # a .param file to compare with the vehicle
    saveFileChosen = pyqtSignal(str, bool)       # where to save the vehicle's parameters, in Mission Planner's format?
    metadataFileChosen = pyqtSignal(str)         # an apm.pdef.xml to read bounds and meanings from
    reviewRequested = pyqtSignal()
    discardRequested = pyqtSignal()              # drop every pending change
    stageRequested = pyqtSignal(str, str)        # name, value as typed
    revertRequested = pyqtSignal(str)

    def __init__(self, model: ParameterModel, parent: QWidget | None = None) -> None:
        super().__init__(parent, Qt.Window)
        self.setObjectName("parametersPage")
        self.setWindowTitle("Parameters")
        self.setAttribute(Qt.WA_QuitOnClose, False)   # closing the flying window ends the program, page open or not
        self.setStyleSheet(STYLE)
        self.model = model
        self.proxy = ParameterFilter(self)
        self.proxy.setSourceModel(model)
        self.file_dialog: QFileDialog | None = None

        self.search = QLineEdit()
        self.search.setObjectName("paramSearch")
        self.search.setPlaceholderText("Search names and descriptions (Ctrl+F)")
        self.search.setClearButtonEnabled(True)
        self.modified_only = QCheckBox("Modified only")
        self.refresh_button = QPushButton("Refresh")
        self.refresh_button.setToolTip("Download every parameter from the vehicle again")
        self.compare_button = QPushButton("Load file…")
        self.compare_button.setToolTip("Compare a .param file with the vehicle and pick what to apply")
        self.save_button = QPushButton("Save file…")
        self.save_button.setToolTip("Save the vehicle's parameters as a .param file (MAVProxy / Mission Planner)")
        self.metadata_button = QPushButton("Metadata…")
        self.metadata_button.setToolTip("Read bounds, units and descriptions from ArduPilot's apm.pdef.xml")
        top = QVBoxLayout()                      # two rows: the page fits beside the flight controls at 1024 px
        search_row, files_row = QHBoxLayout(), QHBoxLayout()
        search_row.addWidget(self.search, 1)
        search_row.addWidget(self.modified_only)
        for b in (self.refresh_button, self.compare_button, self.save_button, self.metadata_button):
            files_row.addWidget(b)
        files_row.addStretch(1)
        top.addLayout(search_row)
        top.addLayout(files_row)

        self.progress = QProgressBar()
        self.progress.setObjectName("paramProgress")
        self.progress.setMaximumHeight(18)
        self.status = QLabel()
        self.status.setObjectName("paramStatus")
        self.status.setWordWrap(True)             # a long status wraps: it never widens the page
        status_row = QHBoxLayout()
        status_row.addWidget(self.status, 1)
        status_row.addWidget(self.progress, 1)

        self.groups = QListWidget()
        self.groups.setObjectName("paramGroups")
        self.groups.setMinimumWidth(120)
        self.table = QTableView()
        self.table.setObjectName("paramTable")
        self._to_centre = ""
        self._centring = QTimer(self, singleShot=True, interval=0)
        self._centring.timeout.connect(self._centre)
        self.table.setModel(self.proxy)
        self.table.setSelectionBehavior(QAbstractItemView.SelectRows)
        self.table.setSelectionMode(QAbstractItemView.SingleSelection)
        self.table.setEditTriggers(QAbstractItemView.NoEditTriggers)
        self.table.verticalHeader().hide()
        self.table.verticalHeader().setDefaultSectionSize(22)
        self.table.setWordWrap(False)
        self.table.setAlternatingRowColors(True)
        self.table.setShowGrid(False)
        header = self.table.horizontalHeader()
        header.setSectionResizeMode(QHeaderView.Interactive)
        header.setStretchLastSection(True)
        for column, width in ((Column.NAME, 150), (Column.VALUE, 150), (Column.UNITS, 50), (Column.RANGE, 110),
                              (Column.STATUS, 90)):
            self.table.setColumnWidth(column, width)
        self.editor = ParamEditor()
        self.editor.setMinimumWidth(260)
        splitter = QSplitter(Qt.Horizontal)
        splitter.addWidget(self.groups)
        splitter.addWidget(self.table)
        splitter.addWidget(self.editor)
        splitter.setStretchFactor(0, 0)
        splitter.setStretchFactor(1, 3)
        splitter.setStretchFactor(2, 1)
        splitter.setSizes([140, 640, 300])
        self.splitter = splitter

        self.pending_label = QLabel()
        self.pending_label.setObjectName("pendingLabel")
        self.discard_button = QPushButton("Discard all")
        self.review_button = QPushButton("Review and write…")
        self.review_button.setObjectName("reviewButton")
        # the pending line wraps on a row of its own: one write's "1 change(s) pending…" widened the page to 827 px
        self.pending_label.setWordWrap(True)
        bottom = QHBoxLayout()
        bottom.addWidget(self.discard_button)
        bottom.addWidget(self.review_button)
        bottom.addStretch(1)
        self.close_button = QPushButton("Close")
        self.close_button.setObjectName("paramClose")
        self.close_button.setToolTip("Close Parameters (Esc); pending changes stay pending")
        bottom.addWidget(self.close_button)

        body = QWidget()                          # it scrolls in the room beside the flight controls; the buttons stay
        inner = QVBoxLayout(body)
        inner.setContentsMargins(0, 0, 0, 0)
        inner.addLayout(top)
        inner.addLayout(status_row)
        inner.addWidget(splitter, 1)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(8, 8, 8, 8)
        layout.addWidget(scrollable(body, horizontal=True), 1)
        layout.addWidget(self.pending_label)
        layout.addLayout(bottom)
        closes_with_esc(self)
        self.resize(1300, 700)

        self.search.textChanged.connect(self.proxy.set_search)
        self.modified_only.toggled.connect(self.proxy.set_modified_only)
        self.groups.currentItemChanged.connect(self._group_picked)
        self.table.selectionModel().currentRowChanged.connect(lambda *_: self.show_current())
        self.table.activated.connect(lambda _index: self.editor.focus_value())      # Enter or double-click
        self.refresh_button.clicked.connect(self.refreshRequested)
        self.compare_button.clicked.connect(lambda: self._ask_file("Compare a parameter file with the vehicle",
                                                                   PARAM_FILES, self.compareFileChosen))
        self.save_button.clicked.connect(lambda: self._ask_file("Save the vehicle's parameters", SAVE_FORMATS,
                                                                self._save_chosen, save=True))
        self.metadata_button.clicked.connect(lambda: self._ask_file("ArduPilot parameter metadata", METADATA_FILES,
                                                                    self.metadataFileChosen))
        self.close_button.clicked.connect(self.close)
        self.review_button.clicked.connect(self.reviewRequested)
        self.discard_button.clicked.connect(self.discardRequested)
        self.editor.stageRequested.connect(self.stageRequested)
        self.editor.revertRequested.connect(self.revertRequested)
        model.dataChanged.connect(self._data_changed)
        model.namesChanged.connect(self._update_groups)
        model.metadataChanged.connect(self._show_metadata_columns)
        model.pendingChanged.connect(self._pending_changed)
        QShortcut(QKeySequence.Find, self, activated=lambda: (self.search.setFocus(), self.search.selectAll()))
        self._group_counts: dict[str, int] = {}
        self._update_groups()
        self._pending_changed()
        self._show_metadata_columns()

    def resizeEvent(self, event) -> None:  # noqa: N802 (Qt's name)
        """Beside the flight controls (430 px at 1024×600) the groups, the table and the editor stand one above the
        other; stacked, the editor keeps the height its fields need (the table scrolls), as the value is what the
        pilot came to change (at 1366×768 it was squeezed to its title)."""
        super().resizeEvent(event)
        stack_when_narrow(self.splitter, event.size().width(), [140, 640, 300],
                          [70, 260, self.editor.sizeHint().height()])

    # -- shown state -------------------------------------------------------------------------------
    def show_download(self, table: ParameterTable, connected: bool) -> None:
        """The download's progress: a bar while it runs, the count when complete, why when it stopped short."""
        expected = table.expected
        if table.downloading and table.complete:    # a table kept from before (the per-vehicle cache), re-read
            self.progress.setRange(0, 0)
            self.progress.show()
            text = f"{table.received:,} parameters shown, reading them again from the vehicle"
        elif table.downloading and expected:
            self.progress.setRange(0, expected)
            self.progress.setValue(min(table.received, expected))
            self.progress.setFormat(f"{table.received:,} of {expected:,}")
            self.progress.show()
            text = f"Downloading parameters: {table.received:,} of {expected:,}"
        elif table.downloading:
            # the count is not known yet (the list's first answer, or the whole file over MAVLink FTP): the
            # driver's own "N of M" (parameters, or the file's bytes) fills the bar, else it just shows it works
            shown = _OF.search(table.detail)
            got, total = (int(shown.group(1)), int(shown.group(2))) if shown else (0, 0)
            self.progress.setRange(0, total)
            self.progress.setValue(min(got, total))
            self.progress.setFormat(f"{got:,} of {total:,}" if total else "")
            self.progress.show()
            text = "Downloading parameters…" if table.detail else "Asking the vehicle for its parameters…"
        else:
            self.progress.hide()
            if table.complete:
                text = f"{table.received:,} parameters, all read from the vehicle"
            elif expected:
                text = f"{table.received:,} of {expected:,} parameters read: incomplete, press Refresh"
            elif table.received:
                text = f"{table.received:,} parameters read so far"
            else:
                text = "No parameters read yet" + ("" if connected else ": no vehicle connected")
        if table.detail:
            text += f" · {table.detail}"
        if not self.model.has_metadata:
            text += " · no metadata: bounds and meanings unknown (Metadata…)"
        self.status.setText(text)
        self.refresh_button.setEnabled(connected and not table.downloading)

    def show_current(self) -> None:
        """The editor follows the current row (and its parameter's newest value)."""
        name = self.current_name()
        param = self.model.parameter(name) if name else None
        self.editor.show_parameter(param, self.model.meta(name) if name else None,
                                   self.model.pending.get(name) if name else None,
                                   have_metadata=self.model.has_metadata)

    def current_name(self) -> str:
        index = self.table.currentIndex()
        return index.data(NAME_ROLE) if index.isValid() else ""

    def select(self, name: str) -> bool:
        """Show ``name``: the search and group are cleared if they hide it; False if the vehicle has not
        reported it (yet)."""
        row = self.model.row_of(name)
        if row < 0:
            return False
        source = self.model.index(row, Column.NAME)
        if not self.proxy.mapFromSource(source).isValid():
            self.search.clear()
            self.modified_only.setChecked(False)
            self.groups.setCurrentRow(0)
        index = self.proxy.mapFromSource(source)
        self.table.selectionModel().setCurrentIndex(
            index, QItemSelectionModel.ClearAndSelect | QItemSelectionModel.Rows)
        self.table.scrollTo(index, QAbstractItemView.PositionAtCenter)
        self._to_centre = name                  # and again once laid out (the page just opened, rows just in)
        self._centring.start()
        self.show_current()
        return True

    def _centre(self) -> None:
        """The row :meth:`select` picked in the middle of the table, if it is still the one picked."""
        if self.current_name() == self._to_centre:
            self.table.scrollTo(self.table.currentIndex(), QAbstractItemView.PositionAtCenter)

    def visible_names(self) -> list[str]:
        """The names listed now, top to bottom."""
        return [self.proxy.index(r, 0).data(NAME_ROLE) for r in range(self.proxy.rowCount())]

    # -- reactions ---------------------------------------------------------------------------------
    def _data_changed(self, top: QModelIndex, bottom: QModelIndex, *_) -> None:
        name = self.current_name()
        if name and top.row() <= self.model.row_of(name) <= bottom.row():
            self.show_current()

    def _pending_changed(self) -> None:
        n = len(self.model.pending)
        self.pending_label.setText(f"{n} change(s) pending: nothing is written until you review them" if n
                                   else "No pending changes")
        self.pending_label.setProperty("pending", bool(n))
        self.pending_label.style().unpolish(self.pending_label)
        self.pending_label.style().polish(self.pending_label)
        self.review_button.setEnabled(bool(n))
        self.discard_button.setEnabled(bool(n))
        self.show_current()

    def _update_groups(self) -> None:
        counts: dict[str, int] = {}
        for row in range(self.model.rowCount()):
            group = group_of(self.model.name_at(row))
            counts[group] = counts.get(group, 0) + 1
        if counts == self._group_counts and self.groups.count():
            return
        self._group_counts = counts
        current = self.proxy.group
        self.groups.blockSignals(True)
        self.groups.clear()
        everything = QListWidgetItem(f"All ({self.model.rowCount():,})")
        everything.setData(Qt.UserRole, "")
        self.groups.addItem(everything)
        for group in sorted(counts):
            item = QListWidgetItem(f"{group} ({counts[group]})")
            item.setData(Qt.UserRole, group)
            self.groups.addItem(item)
            if group == current:
                self.groups.setCurrentItem(item)
        if not current:
            self.groups.setCurrentRow(0)
        self.groups.blockSignals(False)

    def _show_metadata_columns(self) -> None:
        """Units, range and description only say something with metadata: without it the values get the room."""
        for column in (Column.UNITS, Column.RANGE, Column.DESCRIPTION):
            self.table.setColumnHidden(column, not self.model.has_metadata)

    def pick_group(self, group: str) -> None:
        for i in range(self.groups.count()):
            if self.groups.item(i).data(Qt.UserRole) == group:
                self.groups.setCurrentRow(i)
                return

    def _group_picked(self, item: QListWidgetItem | None, _previous=None) -> None:
        self.proxy.set_group(item.data(Qt.UserRole) if item is not None else "")

    def _save_chosen(self, path: str) -> None:
        dialog = self.file_dialog
        mission_planner = dialog is not None and dialog.selectedNameFilter().startswith("Mission Planner")
        self.saveFileChosen.emit(path, mission_planner)

    def _ask_file(self, title: str, filters: str, chosen, save: bool = False) -> QFileDialog:
        """A file dialog that does not block (``open``); ``chosen`` is emitted with the path."""
        dialog = QFileDialog(self, title, "", filters)
        dialog.setOption(QFileDialog.DontUseNativeDialog, True)
        if save:
            dialog.setAcceptMode(QFileDialog.AcceptSave)
            dialog.setDefaultSuffix("param")
        else:
            dialog.setFileMode(QFileDialog.ExistingFile)
        dialog.setAttribute(Qt.WA_DeleteOnClose)
        dialog.fileSelected.connect(chosen)
        dialog.finished.connect(lambda _r: setattr(self, "file_dialog", None))
        self.file_dialog = dialog
        dialog.open()
        return dialog
