"""The Plan dock: the editable item list beside the map, the survey's settings, the plan's totals, the transfers
and the mission's own controls (Start, Pause, Resume) with its progress.

It says what the pilot wants through its signals and shows what it is given; the plan controller decides.
"""
from __future__ import annotations

from PyQt5.QtCore import QItemSelectionModel, Qt, pyqtSignal
from PyQt5.QtGui import QBrush, QColor, QKeySequence
from PyQt5.QtWidgets import (
    QAbstractItemView, QCheckBox, QComboBox, QDoubleSpinBox, QFormLayout, QGroupBox, QHBoxLayout, QHeaderView,
    QLabel, QMenu, QProgressBar, QPushButton, QShortcut, QSizePolicy, QTabWidget, QTableWidget, QTableWidgetItem,
    QToolButton, QVBoxLayout, QWidget,
)

from .table import PlanTable
from .vehicle_view import VehicleView
from .survey import CAMERAS

__all__ = ["PlanPanel", "LAYERS", "TOOLS"]

LAYERS = ("mission", "fence", "rally")
ROWS_IN_VIEW = 6                   # the list's rows in view where the column allows (its dock is sized for them: room.py)
ROWS_AT_LEAST = 3                  # and never fewer: at 1024×600 the list showed none, Upload scrolled away
#: What a click on the map adds, for each tab.
TOOLS = {
    "mission": ("Waypoint", "ROI", "Land", "Loiter (time)", "Survey area"),
    "fence": ("Inclusion polygon", "Exclusion polygon", "Inclusion circle", "Exclusion circle"),
    "rally": ("Rally point",),
}
COLUMNS = {
    "mission": ("#", "Item", "Alt m", "Speed m/s", "Hold s"),
    "fence": ("Shape", "Points", "Radius m"),
    "rally": ("#", "Alt m"),
}


class PlanPanel(QWidget):
    editToggled = pyqtSignal(bool)               # Plan mode: clicks on the map add, drags move
    toolChanged = pyqtSignal(str)                # what a click adds ("Waypoint", "Inclusion circle", ...)
    layerChanged = pyqtSignal(str)               # the tab: "mission", "fence", "rally"
    addRequested = pyqtSignal(str)               # an item without a place: "Takeoff", "RTL", "Change speed"
    deleteRequested = pyqtSignal()
    finishRequested = pyqtSignal()               # end the polygon being drawn
    rowSelected = pyqtSignal(str, int)           # layer, row
    moveRequested = pyqtSignal(int)              # the selected item(s) one place up (-1) or down (+1)
    rowsDropped = pyqtSignal(str, list, int)     # layer, rows dragged in the list, the row they go before
    cellEdited = pyqtSignal(str, int, str, float)   # layer, row, column name, value
    surveyEdited = pyqtSignal(object)            # dict: camera, altitude, front, side, angle
    transferRequested = pyqtSignal(str)          # "upload", "download", "clear" (of the tab's plan)
    cancelRequested = pyqtSignal()
    startRequested = pyqtSignal()
    pauseRequested = pyqtSignal()
    resumeRequested = pyqtSignal()
    skipRequested = pyqtSignal(int)              # the vehicle's item number
    openRequested = pyqtSignal()
    saveRequested = pyqtSignal()
    newRequested = pyqtSignal()                  # an empty plan (asks first when edits are not saved)
    clearListRequested = pyqtSignal(str)         # empty the tab's list here (the vehicle keeps its own)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("planPanel")
        self._filling = False
        self.skip_allowed = False                # the controller says when Skip to item makes sense
        self._tips: dict[QWidget, str] = {}      # each vehicle button's own tooltip; why it is disabled follows
        self.row_seq: list[int | None] = []      # the vehicle's item number of each mission row
        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.setSpacing(4)

        bar = QHBoxLayout()
        self.editCheck = QCheckBox("Edit on map")
        self.editCheck.setToolTip("Plan mode: a click on the map adds, a drag moves an item or a corner")
        self.toolCombo = QComboBox()
        self.toolCombo.setToolTip("What a click on the map adds")
        self.finishButton = QToolButton(text="Finish shape")
        self.finishButton.setToolTip("End the polygon being drawn (at least three corners)")
        self.insertCheck = QCheckBox("Insert")
        self.insertCheck.setToolTip("Add before the selected item instead of at the end")
        bar.addWidget(self.editCheck)
        bar.addWidget(self.toolCombo, 1)
        bar.addWidget(self.insertCheck)          # here, not in the row below: that one, with ↑ ↓ and New, would
        bar.addWidget(self.finishButton)         # be wider than the dock, and its scroll bar hide a row of the list
        lay.addLayout(bar)

        adds = QHBoxLayout()
        self.addButton = QToolButton(text="Add")
        self.addButton.setToolTip("Items without a place on the map: a takeoff (first), RTL, a speed change")
        self.addButton.setPopupMode(QToolButton.InstantPopup)
        self.addMenu = QMenu(self.addButton)
        self.addMenu.setObjectName("planAddMenu")
        for what in ("Takeoff", "RTL", "Change speed"):
            self.addMenu.addAction(what, lambda w=what: self.addRequested.emit(w))
        self.addButton.setMenu(self.addMenu)
        self.deleteButton = QToolButton(text="Delete")
        self.deleteButton.setToolTip("Delete the selected item(s) (Delete key)")
        self.upButton = QToolButton(text="↑")
        self.upButton.setToolTip("Move the selected item(s) up")
        self.downButton = QToolButton(text="↓")
        self.downButton.setToolTip("Move the selected item(s) down")
        self.newButton = QToolButton(text="New")
        self.newButton.setToolTip("A new, empty plan: mission, fence and rally points (the vehicle keeps its own)")
        self.openButton = QToolButton(text="Open…")
        self.openButton.setToolTip("Open a plan file (QGroundControl .plan, or a WPL waypoint file)")
        self.saveButton = QToolButton(text="Save…")
        self.saveButton.setToolTip("Save the plan (QGroundControl .plan, or the mission as a WPL waypoint file)")
        for w in (self.addButton, self.deleteButton, self.upButton, self.downButton):
            adds.addWidget(w)
        adds.addStretch(1)
        adds.addWidget(self.newButton)
        adds.addWidget(self.openButton)
        adds.addWidget(self.saveButton)
        lay.addLayout(adds)

        self.totalsLabel = QLabel("Empty plan")
        self.totalsLabel.setObjectName("planTotals")
        self.totalsLabel.setWordWrap(True)

        transfers = QHBoxLayout()
        self.uploadButton = QPushButton("Upload")
        self.uploadButton.setToolTip("Upload the tab's plan, and every other plan here that differs from the vehicle's")
        self.downloadButton = QPushButton("Download")
        self.clearButton = QPushButton("Remove…")
        self.clearButton.setToolTip("Remove the tab's plan from the vehicle (asks first); the list here stays")
        self.cancelButton = QToolButton(text="✕")
        self.cancelButton.setToolTip("Cancel the transfer")
        self.progressBar = QProgressBar()
        self.progressBar.setTextVisible(True)
        self.progressBar.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Fixed)
        for w in (self.uploadButton, self.downloadButton, self.clearButton):
            transfers.addWidget(w)
        transfers.addWidget(self.progressBar, 1)
        transfers.addWidget(self.cancelButton)
        lay.addLayout(transfers)
        self.syncLabel = QLabel()
        self.syncLabel.setObjectName("planSync")
        self.syncLabel.setWordWrap(True)
        facts = QHBoxLayout()                    # the plan's totals and where it stands with the vehicle: one row,
        facts.addWidget(self.totalsLabel, 1)     # so that the list keeps six rows in view at 1280×720
        facts.addWidget(self.syncLabel, 1)
        lay.addLayout(facts)
        for label, lines in ((self.totalsLabel, 3), (self.syncLabel, 3)):
            _fixed_lines(label, lines)           # a longer text never pushes the list (and the map) while editing

        fly = QHBoxLayout()
        self.startButton = QPushButton("Start mission")
        self.startButton.setObjectName("startMission")
        self.pauseButton = QPushButton("Pause")
        self.resumeButton = QPushButton("Resume")
        for w in (self.startButton, self.pauseButton, self.resumeButton):
            fly.addWidget(w)
        for b in (self.uploadButton, self.downloadButton, self.clearButton, self.startButton, self.pauseButton,
                  self.resumeButton):
            b.setStyleSheet("padding: 2px 8px")  # as tall as the tool buttons: the list keeps its rows
        self.progressLabel = QLabel()
        self.progressLabel.setObjectName("missionProgress")
        self.progressLabel.setWordWrap(True)
        fly.addWidget(self.progressLabel, 1)     # beside the buttons it follows: one row less above the list
        _fixed_lines(self.progressLabel, 2)     # as tall as the buttons beside it
        lay.addLayout(fly)

        self.tabs = QTabWidget()
        self.tables: dict[str, QTableWidget] = {}
        for layer, title in zip(LAYERS, ("Mission", "Fence", "Rally")):
            table = PlanTable(0, len(COLUMNS[layer]))
            table.setObjectName(f"{layer}Table")
            table.verticalHeader().setDefaultSectionSize(table.fontMetrics().height() + 2)   # compact rows
            table.setMinimumHeight(table.horizontalHeader().sizeHint().height() + 2 * table.frameWidth()
                                   + ROWS_AT_LEAST * table.verticalHeader().defaultSectionSize())
            table.setHorizontalHeaderLabels(COLUMNS[layer])
            table.verticalHeader().hide()
            table.setSelectionBehavior(QAbstractItemView.SelectRows)
            table.setSelectionMode(QAbstractItemView.ExtendedSelection)      # Shift/Ctrl: several to delete or move
            table.setEditTriggers(QAbstractItemView.DoubleClicked | QAbstractItemView.EditKeyPressed
                                  | QAbstractItemView.AnyKeyPressed)
            header = table.horizontalHeader()
            header.setSectionResizeMode(QHeaderView.ResizeToContents)
            header.setSectionResizeMode(1 if layer == "mission" else 0, QHeaderView.Stretch)
            table.setContextMenuPolicy(Qt.CustomContextMenu)
            table.customContextMenuRequested.connect(lambda pos, l=layer: self._table_menu(l, pos))
            table.itemSelectionChanged.connect(lambda l=layer: self._selection(l))
            table.itemChanged.connect(lambda item, l=layer: self._edited(l, item))
            table.rowsDropped.connect(lambda rows, before, l=layer: self.rowsDropped.emit(l, rows, before))
            QShortcut(QKeySequence.Delete, table, self.deleteRequested.emit, context=Qt.WidgetShortcut)
            self.tables[layer] = table
            self.tabs.addTab(table, title)
        # the list asks for no more than its minimum (three rows); the Plan dock is sized for six where the column
        # has room (room.py: wanted_rows_height)
        self.tabs.ensurePolished()
        self.tabs.setMinimumHeight(self.tabs.minimumSizeHint().height())
        self.wanted_rows_height = (ROWS_IN_VIEW - ROWS_AT_LEAST) * table.verticalHeader().defaultSectionSize()
        self.tabs.setSizePolicy(QSizePolicy.Preferred, QSizePolicy.Ignored)
        lay.addWidget(self.tabs, 1)

        self.surveyBox = QGroupBox("Survey")
        form = QFormLayout(self.surveyBox)
        form.setContentsMargins(4, 2, 4, 2)
        self.cameraCombo = QComboBox()
        for camera in CAMERAS:
            self.cameraCombo.addItem(camera.name)
        self.altitudeSpin = self._spin(2, 120, 30, " m")
        self.frontSpin = self._spin(0, 95, 70, " %")
        self.sideSpin = self._spin(0, 95, 60, " %")
        self.angleSpin = self._spin(0, 359, 0, "°")
        overlaps = QHBoxLayout()
        overlaps.addWidget(QLabel("front"))
        overlaps.addWidget(self.frontSpin)
        overlaps.addWidget(QLabel("side"))
        overlaps.addWidget(self.sideSpin)
        form.addRow("Camera", self.cameraCombo)
        row = QHBoxLayout()
        row.addWidget(self.altitudeSpin)
        row.addWidget(QLabel("passes"))
        row.addWidget(self.angleSpin)
        form.addRow("Altitude", row)
        form.addRow("Overlap", overlaps)
        self.surveyLabel = QLabel()
        self.surveyLabel.setWordWrap(True)
        form.addRow(self.surveyLabel)
        self.surveyBox.hide()
        lay.addWidget(self.surveyBox)

        for w in self.findChildren(QWidget):
            # a table's viewport passes its focus policy on to the table (its focus proxy): left alone, or a
            # click in the list would leave the focus elsewhere and Delete would not reach it
            if not isinstance(w, (QTableWidget, QDoubleSpinBox, QComboBox)) and w.focusProxy() is None:
                w.setFocusPolicy(Qt.NoFocus)          # keys keep flying the drone
        self.editCheck.toggled.connect(self.editToggled.emit)
        self.toolCombo.currentTextChanged.connect(lambda t: t and self.toolChanged.emit(t))
        self.tabs.currentChanged.connect(self._tab)
        self.finishButton.clicked.connect(self.finishRequested.emit)
        self.deleteButton.clicked.connect(self.deleteRequested.emit)
        self.upButton.clicked.connect(lambda: self.moveRequested.emit(-1))
        self.downButton.clicked.connect(lambda: self.moveRequested.emit(1))
        self.newButton.clicked.connect(self.newRequested.emit)
        self.uploadButton.clicked.connect(lambda: self.transferRequested.emit("upload"))
        self.downloadButton.clicked.connect(lambda: self.transferRequested.emit("download"))
        self.clearButton.clicked.connect(lambda: self.transferRequested.emit("clear"))
        self.cancelButton.clicked.connect(self.cancelRequested.emit)
        self.startButton.clicked.connect(self.startRequested.emit)
        self.pauseButton.clicked.connect(self.pauseRequested.emit)
        self.resumeButton.clicked.connect(self.resumeRequested.emit)
        self.openButton.clicked.connect(self.openRequested.emit)
        self.saveButton.clicked.connect(self.saveRequested.emit)
        for w in (self.altitudeSpin, self.frontSpin, self.sideSpin, self.angleSpin):
            w.valueChanged.connect(self._survey_edited)
        self.cameraCombo.currentIndexChanged.connect(self._survey_edited)
        self._tab(0)

    @staticmethod
    def _spin(low: float, high: float, value: float, suffix: str) -> QDoubleSpinBox:
        spin = QDoubleSpinBox()
        spin.setRange(low, high)
        spin.setDecimals(0)
        spin.setValue(value)
        spin.setSuffix(suffix)
        spin.setKeyboardTracking(False)
        return spin

    # -- what the pilot does ----------------------------------------------------------------------
    @property
    def layer(self) -> str:
        return LAYERS[self.tabs.currentIndex()]

    def _tab(self, index: int) -> None:
        layer = LAYERS[index]
        self.toolCombo.blockSignals(True)
        self.toolCombo.clear()
        self.toolCombo.addItems(TOOLS[layer])
        self.toolCombo.blockSignals(False)
        mission = layer == "mission"
        for w in (self.addButton, self.insertCheck):
            w.setVisible(mission)
        self.layerChanged.emit(layer)
        self.toolChanged.emit(self.toolCombo.currentText())

    def _selection(self, layer: str) -> None:
        rows = self.tables[layer].selectionModel().selectedRows()
        if rows and not self._filling:
            self.rowSelected.emit(layer, rows[0].row())

    def _edited(self, layer: str, item: QTableWidgetItem) -> None:
        if self._filling:
            return
        column = COLUMNS[layer][item.column()]
        text = item.text().strip().replace(",", ".")
        try:
            value = float(text) if text not in ("", "-", "--") else float("nan")
        except ValueError:
            value = float("nan")
        self.cellEdited.emit(layer, item.row(), column, value)

    def _survey_edited(self, *_) -> None:
        if not self._filling:
            self.surveyEdited.emit(self.survey_values())

    def survey_values(self) -> dict:
        return {"camera": self.cameraCombo.currentText(), "altitude": self.altitudeSpin.value(),
                "front": self.frontSpin.value() / 100.0, "side": self.sideSpin.value() / 100.0,
                "angle": self.angleSpin.value()}

    def _table_menu(self, layer: str, pos) -> None:
        table = self.tables[layer]
        row = table.rowAt(pos.y())
        if row < 0:
            return
        if row not in self.selected_rows(layer):
            table.selectRow(row)
        menu = QMenu(table)
        menu.setAttribute(Qt.WA_DeleteOnClose)
        menu.setObjectName("planMenu")
        if layer == "mission":
            seq = self.row_seq[row] if row < len(self.row_seq) else None
            if seq is not None:
                menu.addAction(f"Skip to item {seq}", lambda: self.skipRequested.emit(seq)).setEnabled(
                    self.skip_allowed)
        menu.addAction("Delete", self.deleteRequested.emit)
        menu.addAction("Move up", lambda: self.moveRequested.emit(-1))
        menu.addAction("Move down", lambda: self.moveRequested.emit(1))
        menu.addSeparator()
        menu.addAction("Clear the list", lambda: self.clearListRequested.emit(layer))
        menu.popup(table.viewport().mapToGlobal(pos))

    # -- what it shows ----------------------------------------------------------------------------
    def selected_rows(self, layer: str) -> list[int]:
        return sorted(i.row() for i in self.tables[layer].selectionModel().selectedRows())

    def select_rows(self, layer: str, rows: list[int]) -> None:
        table = self.tables[layer]
        self._filling = True
        try:
            table.clearSelection()
            for r in rows:
                table.selectionModel().select(table.model().index(r, 0),
                                              QItemSelectionModel.Select | QItemSelectionModel.Rows)
        finally:
            self._filling = False

    def set_rows(self, layer: str, rows: list[tuple], editable: list[tuple[bool, ...]] | None = None,
                 selected: int | None = None, current: int | None = None,
                 warnings: dict[int, str] | None = None) -> None:
        """Rows of cell texts; ``editable`` per cell; ``current``: the row the vehicle flies now (highlighted);
        ``warnings``: what is wrong with a row, marked ⚠ on it and said in its tooltip."""
        warnings = warnings or {}
        table = self.tables[layer]
        self._filling = True
        try:
            table.setRowCount(len(rows))
            for r, cells in enumerate(rows):
                for c, text in enumerate(cells):
                    item = table.item(r, c)
                    if item is None:
                        item = QTableWidgetItem()
                        table.setItem(r, c, item)
                    warning = warnings.get(r, "")
                    item.setText(f"⚠ {text}" if warning and c == 1 else str(text))
                    item.setToolTip(warning)
                    item.setForeground(QColor("#ffb020") if warning else QBrush())
                    flags = Qt.ItemIsSelectable | Qt.ItemIsEnabled
                    if editable is not None and editable[r][c]:
                        flags |= Qt.ItemIsEditable
                    item.setFlags(flags)
                    item.setBackground(Qt.darkGreen if r == current else Qt.transparent)
            if selected is not None and 0 <= selected < len(rows):
                if selected not in self.selected_rows(layer):    # a multiple selection stays as it is
                    table.selectRow(selected)
            elif selected is None:
                table.clearSelection()
        finally:
            self._filling = False

    def set_survey(self, values: dict | None, summary: str = "") -> None:
        """The selected survey's settings (None hides the box)."""
        self.surveyBox.setVisible(values is not None)
        if values is None:
            return
        self._filling = True
        try:
            self.cameraCombo.setCurrentText(values["camera"])
            self.altitudeSpin.setValue(values["altitude"])
            self.frontSpin.setValue(round(values["front"] * 100))
            self.sideSpin.setValue(round(values["side"] * 100))
            self.angleSpin.setValue(values["angle"])
        finally:
            self._filling = False
        self.surveyLabel.setText(summary)

    def show_vehicle(self, view: VehicleView) -> None:
        """The vehicle's side of the panel as the plan controller worked it out (plan/vehicle_view.py), all at once:
        the transfer, the tabs' dots, the comparison, every button, the mission's progress."""
        t = view.transfer
        self.progressBar.setRange(0, max(1, t.total))
        self.progressBar.setValue(min(t.done, max(1, t.total)) if t.total else 0)
        self.progressBar.setFormat(t.text.split(" (")[0])   # "upload mission: accepted"; the whole in its tip
        self.progressBar.setToolTip(t.text)
        for index, title in enumerate(view.tab_titles):
            self.tabs.setTabText(index, title)
        self.syncLabel.setText(view.comparison)
        self.syncLabel.setStyleSheet("color: #ffb020;" if view.warning else "")
        for button, state in ((self.uploadButton, view.upload), (self.downloadButton, view.download),
                              (self.clearButton, view.remove), (self.cancelButton, view.cancel),
                              (self.startButton, view.start), (self.pauseButton, view.pause),
                              (self.resumeButton, view.resume)):
            button.setEnabled(state.enabled)
            what = self._tips.setdefault(button, button.toolTip())     # what it does, as built
            button.setToolTip("\n".join(w for w in (what, state.why_not) if w))
        self.skip_allowed = view.skip.enabled
        self.progressLabel.setText(view.progress)

    def show_current_row(self, current: int | None) -> None:
        """The mission's row the vehicle flies now, highlighted (None: none)."""
        table = self.tables["mission"]
        for r in range(table.rowCount()):
            for c in range(table.columnCount()):
                item = table.item(r, c)
                if item is not None:
                    item.setBackground(Qt.darkGreen if r == current else Qt.transparent)


def _fixed_lines(label: QLabel, lines: int) -> None:
    """As tall as ``lines`` wrapped lines, whatever it says (the rest is cut): the Plan dock is sized once, as it
    opens (plan_room.py), and nothing in it moves afterwards."""
    label.ensurePolished()
    label.setFixedHeight(lines * label.fontMetrics().lineSpacing() + 2)
    label.setAlignment(Qt.AlignLeft | Qt.AlignTop)

