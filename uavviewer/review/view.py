"""One reviewed log in one view (docs/review.md): the searchable field tree, the plots with their events and cursor,
the flight path on the map coloured by mode with the cursor's marker, the events, the parameters as flown and
their difference from the vehicle's, presets and CSV export, and geotagging the flight's photos."""
from __future__ import annotations

import logging
import os
from concurrent.futures import CancelledError, Future, ThreadPoolExecutor

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import (QComboBox, QFileDialog, QHBoxLayout, QLabel, QMainWindow, QPushButton, QSplitter,
                             QTabWidget, QVBoxLayout, QWidget)

from driver.review.log import PRESETS, FlightLog

from ..map.log_path import LogPathOverlay, mode_colour
from ..map.map_view import MapView
from ..widgets.dialog_fit import close_buttons, closes_with_esc, scrollable, stack_when_narrow
from .events_list import EventsList
from .field_tree import FieldTree
from .geotag_dialog import GeotagDialog
from .params_table import FlightParams
from .plots import ReviewPlots

log = logging.getLogger(__name__)

__all__ = ["ReviewWindow"]


class ReviewWindow(QMainWindow):
    """``current_params``: a callable giving the vehicle's parameters now (name -> value; empty when none).
    ``submit``: runs slow work off the window's thread (the controller's pool; the view's own worker if not given).
    ``exported`` gives the rows a CSV export wrote, or the words of its error."""

    exported = pyqtSignal(object)
    _export_done = pyqtSignal(object, str, int)

    def __init__(self, flight: FlightLog, current_params=dict, parent: QWidget | None = None,
                 submit=None) -> None:
        super().__init__(parent)
        self.log = flight
        self._own_pool = ThreadPoolExecutor(1, thread_name_prefix="review-export") if submit is None else None
        self._submit = submit or self._own_pool.submit
        self.export_future: Future | None = None
        self._export_done.connect(self._show_export, Qt.QueuedConnection)     # after export() returns, always
        self.setWindowTitle(f"Review — {os.path.basename(flight.path)}")
        self.setObjectName("reviewWindow")
        self.tree = FieldTree()
        self.plots = ReviewPlots()
        self.map = MapView()
        self.path_overlay = LogPathOverlay(self.map, self)
        self.events = EventsList()
        self.params = FlightParams()
        self.preset = QComboBox()
        self.preset.addItem("Preset…")
        self.preset.addItems(list(PRESETS))
        self.preset.activated[str].connect(self.apply_preset)
        clear = QPushButton("Clear plots")
        clear.clicked.connect(self.plots.clear_fields)
        self.export_button = QPushButton("Export CSV…")
        self.export_button.clicked.connect(self.ask_export)
        self.geotag_button = QPushButton("Geotag photos…")
        self.geotag_button.setToolTip("Write the position of each of this flight's camera events (CAM, TRIG, "
                                      "CAMERA_FEEDBACK) into its photo's EXIF")
        self.geotag_button.clicked.connect(self.open_geotag)
        self.geotag_dialog: GeotagDialog | None = None
        self.status = QLabel()
        self.warning = QLabel()                     # a damaged or cut-short log says so above everything
        self.warning.setObjectName("reviewWarning")
        self.warning.setWordWrap(True)
        self.warning.setStyleSheet("background: #4a3a1c; color: #ffd27a; padding: 4px; font-weight: bold")
        self.warning.hide()
        bar = QHBoxLayout()
        for w in (self.preset, clear, self.export_button, self.geotag_button):
            bar.addWidget(w)
        bar.addWidget(self.status, 1)
        self.legend = QLabel()
        self.legend.setTextFormat(Qt.RichText)

        side = QTabWidget()
        side.addTab(self.map, "Path")
        side.addTab(self.events, "Events")
        side.addTab(self.params, "Parameters")
        self.side = side
        right = QSplitter(Qt.Vertical)
        right.addWidget(_column(bar, self.plots))
        right.addWidget(_column(side, self.legend))
        right.setSizes([430, 300])
        main = QSplitter(Qt.Horizontal)
        main.addWidget(self.tree)
        main.addWidget(right)
        main.setSizes([260, 1100])
        self.main_splitter = main
        self.setCentralWidget(_column(self.warning, scrollable(main, horizontal=True), close_buttons(self), stretch=1))
        closes_with_esc(self)                       # a window of its own closes as a dialog does

        self.tree.fieldChosen.connect(self.add_field)
        self.plots.cursorMoved.connect(self.path_overlay.set_time)
        self.path_overlay.timePicked.connect(self.plots.set_cursor)      # and back: a click on the path
        self.events.timeChosen.connect(self.plots.set_cursor)
        self._current_params = current_params
        self.flown_params = self.log.params()
        side.currentChanged.connect(lambda index: index == side.indexOf(self.params) and self.compare_params())
        self._fill()

    def resizeEvent(self, event) -> None:  # noqa: N802 (Qt's name)
        """Beside the flight controls the field tree stands above the plots and the path."""
        super().resizeEvent(event)
        stack_when_narrow(self.main_splitter, event.size().width(), [260, 1100], [140, 600])

    def compare_params(self) -> None:
        """The parameters as flown beside the vehicle's now (read again each time the tab is shown: the vehicle
        may have been connected, or its table read, since the log was opened)."""
        try:
            current = self._current_params() or {}
        except Exception:                                   # noqa: BLE001 - a comparison is optional
            log.exception("current parameters")
            current = {}
        self.params.show_params(self.flown_params, current)

    def _fill(self) -> None:
        tree = self.log.tree()
        self.tree.set_tree(tree, {t: self.log.count(t) for t in tree})
        events = self.log.events()
        self.plots.show_events(events)
        self.events.show_events(events)
        path = self.log.flight_path()
        if path is not None:
            self.path_overlay.set_path(path.t, path.lat, path.lon, path.mode)
            seen = list(dict.fromkeys(path.mode))
            self.legend.setText("Path by mode: " + "  ".join(
                f'<span style="color:{mode_colour(m).name()}">■ {m or "?"}</span>' for m in seen))
        else:
            self.legend.setText("No position in this log: no path to draw.")
        self.compare_params()
        skipped = self.log.skipped_bytes
        self.status.setText(f"{sum(self.log.count(t) for t in tree):,} records, {len(tree)} types"
                            + (f"; {skipped:,} unreadable bytes skipped" if skipped else ""))
        if skipped:                                 # a truncated .BIN opened as if whole, its status line unread
            self.warning.setText(f"This log is damaged or cut short: {skipped:,} bytes could not be read and were "
                                 "skipped. The flight may end early or miss records; what is shown is what was read.")
        self.warning.setVisible(bool(skipped))

    # -- fields --------------------------------------------------------------------------------------------------
    def add_field(self, mtype: str, field: str, axis: int = 0) -> None:
        t, values = self.log.series(mtype, field)
        self.plots.add((mtype, field), t, values, axis)

    def apply_preset(self, name: str) -> int:
        """The preset's fields this log has (ATT for a .BIN, ATTITUDE for a .tlog); returns how many."""
        if name not in PRESETS:
            return 0
        self.plots.clear_fields()
        chosen = self.log.preset(name)
        for t, f, axis in chosen:
            self.add_field(t, f, axis)
        self.status.setText(f"{name}: {len(chosen)} fields" if chosen else f"{name}: none of its fields in this log")
        self.preset.setCurrentIndex(0)
        return len(chosen)

    def export(self, path: str) -> Future:
        """Write the plotted fields to ``path`` off the window's thread (a long log's rows take seconds); the status
        line says when it is done, or why it failed."""
        fields = list(self.plots.curves)
        self.export_button.setEnabled(False)
        self.status.setText(f"exporting {len(fields)} fields to {os.path.basename(path)}…")
        self.export_future = self._submit(self.log.export_csv, path, fields)
        self.export_future.add_done_callback(lambda f: self._export_done.emit(f, path, len(fields)))
        return self.export_future

    def _show_export(self, future: Future, path: str, fields: int) -> None:
        self.export_button.setEnabled(True)
        try:
            rows = future.result()
        except CancelledError:                              # the application closes
            return
        except Exception as e:                              # noqa: BLE001 - a full disk never takes the window down
            log.exception("export %s", path)
            self.status.setText(f"export to {os.path.basename(path)} failed: {e}")
            self.exported.emit(str(e))
            return
        self.status.setText(f"exported {fields} fields, {rows:,} rows to {os.path.basename(path)}")
        self.exported.emit(rows)

    def ask_export(self) -> None:
        if not self.plots.curves:
            self.status.setText("plot the fields to export first")
            return
        base = os.path.splitext(self.log.path)[0] + ".csv"
        path, _ = QFileDialog.getSaveFileName(self, "Export CSV", base, "CSV (*.csv)")
        if path:
            self.export(path)

    def open_geotag(self) -> GeotagDialog:
        if self.geotag_dialog is None:
            self.geotag_dialog = GeotagDialog(self.log.path, self)
        self.geotag_dialog.show()
        self.geotag_dialog.raise_()
        return self.geotag_dialog

    def closeEvent(self, event) -> None:  # noqa: N802
        if self.geotag_dialog is not None:
            self.geotag_dialog.shutdown()
        if self.export_future is not None and not self.export_future.done():
            self.export_future.add_done_callback(lambda _f: self.log.close())     # the file is read to the end
        else:
            self.log.close()
        if self._own_pool is not None:
            self._own_pool.shutdown(wait=False)
        super().closeEvent(event)


def _column(*parts, stretch: int = -1) -> QWidget:
    """Widgets and layouts stacked without margins; the part at index ``stretch`` takes the room left."""
    box = QWidget()
    layout = QVBoxLayout(box)
    layout.setContentsMargins(0, 0, 0, 0)
    for i, part in enumerate(parts):
        if isinstance(part, QHBoxLayout):
            layout.addLayout(part)
        else:
            layout.addWidget(part, 1 if i == stretch else 0)
    return box
