"""Geotag photos…: the reviewed log's camera events written into a folder of photos (driver.review.geotag), run off
the window's thread (a log opens again there, and each photo is read and written whole), the report shown."""
from __future__ import annotations

import logging
import os
from concurrent.futures import Future, ThreadPoolExecutor

from PyQt5.QtCore import pyqtSignal
from PyQt5.QtWidgets import (QCheckBox, QComboBox, QDialog, QDoubleSpinBox, QFileDialog, QFormLayout, QHBoxLayout,
                             QLabel, QLineEdit, QPlainTextEdit, QPushButton, QVBoxLayout, QWidget)

from driver.review.geotag import DEFAULT_TOLERANCE, OUTPUT_FOLDER, GeotagError, GeotagReport, geotag
from driver.review.log import LogError

from ..widgets.dialog_fit import close_buttons, scrollable
log = logging.getLogger(__name__)

__all__ = ["GeotagDialog"]


class GeotagDialog(QDialog):
    """For one log (its path: the worker opens its own copy, so closing the review never pulls the log from under
    it). ``finished_run`` gives the :class:`GeotagReport`, or the words of the error."""

    finished_run = pyqtSignal(object)
    _progress = pyqtSignal(int, int)
    _done = pyqtSignal(object)

    def __init__(self, log_path: str, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.log_path = log_path
        self.setWindowTitle(f"Geotag photos — {os.path.basename(log_path)}")
        self.setObjectName("geotagDialog")
        self._pool = ThreadPoolExecutor(1, thread_name_prefix="geotag")
        self.future: Future | None = None
        self.folder = QLineEdit()
        self.folder.setPlaceholderText("the folder of the flight's photos")
        self.folder.textChanged.connect(self._folder_changed)
        browse = QPushButton("Browse…")
        browse.clicked.connect(self.ask_folder)
        self.output = QLineEdit()
        self.in_place = QCheckBox("Rewrite the original photos (no copies)")
        self.in_place.toggled.connect(self.output.setDisabled)
        self.offset = QDoubleSpinBox()
        self.offset.setRange(-48 * 3600.0, 48 * 3600.0)
        self.offset.setDecimals(1)
        self.offset.setSuffix(" s")
        self.offset.setToolTip("How far the camera's clock runs ahead of UTC (a camera on UTC+2: 7200 s)")
        self.tolerance = QDoubleSpinBox()
        self.tolerance.setRange(0.0, 3600.0)
        self.tolerance.setDecimals(1)
        self.tolerance.setSuffix(" s")
        self.tolerance.setValue(DEFAULT_TOLERANCE)
        self.match = QComboBox()
        self.match.addItem("in order (n-th photo, n-th event), checked by time", "order")
        self.match.addItem("by time (the nearest event; for missed triggers)", "time")
        self.altitude = QComboBox()
        self.altitude.addItem("above mean sea level", "msl")
        self.altitude.addItem("above home", "relative")
        self.run_button = QPushButton("Geotag")
        self.run_button.clicked.connect(self.run)
        self.status = QLabel()
        self.report = QPlainTextEdit()
        self.report.setReadOnly(True)

        row = QHBoxLayout()
        row.addWidget(self.folder, 1)
        row.addWidget(browse)
        form = QFormLayout()
        form.addRow("Photos", row)
        form.addRow("Write copies to", self.output)
        form.addRow("", self.in_place)
        form.addRow("Camera clock ahead of UTC", self.offset)
        form.addRow("Time tolerance", self.tolerance)
        form.addRow("Match", self.match)
        form.addRow("Altitude", self.altitude)
        body = QWidget()                           # it scrolls where the room is narrow; Close stays in view
        inner = QVBoxLayout(body)
        inner.setContentsMargins(0, 0, 0, 0)
        inner.addLayout(form)
        buttons = QHBoxLayout()
        buttons.addWidget(self.status, 1)
        buttons.addWidget(self.run_button)
        inner.addLayout(buttons)
        inner.addWidget(self.report, 1)
        layout = QVBoxLayout(self)
        layout.addWidget(scrollable(body, horizontal=True), 1)
        layout.addWidget(close_buttons(self))
        self._progress.connect(lambda done, total: self.status.setText(f"writing {done} of {total}…"))
        self._done.connect(self._show)
        self.resize(640, 480)

    def _folder_changed(self, folder: str) -> None:
        self.output.setPlaceholderText(os.path.join(folder, OUTPUT_FOLDER) if folder else "")

    def ask_folder(self) -> None:
        folder = QFileDialog.getExistingDirectory(self, "The flight's photos", os.path.dirname(self.log_path))
        if folder:
            self.folder.setText(folder)

    def run(self) -> Future | None:
        """Geotag on the worker thread; the button waits until the report is in."""
        folder = self.folder.text().strip()
        if not folder:
            self.status.setText("choose the folder of photos first")
            return None
        self.run_button.setEnabled(False)
        self.status.setText("reading the log and the photos…")
        self.report.clear()
        options = dict(output=self.output.text().strip() or None, clock_offset=self.offset.value(),
                       tolerance=self.tolerance.value(), in_place=self.in_place.isChecked(),
                       by=self.match.currentData(), altitude=self.altitude.currentData(),
                       progress=self._progress.emit)
        self.future = self._pool.submit(geotag, self.log_path, folder, **options)
        self.future.add_done_callback(self._done.emit)
        return self.future

    def _show(self, future: Future) -> None:
        self.run_button.setEnabled(True)
        try:
            report: GeotagReport = future.result()
        except (GeotagError, LogError) as e:
            self._finish(str(e), str(e))
            return
        except Exception as e:                              # noqa: BLE001 - a bad photo never takes the window down
            log.exception("geotag %s", self.log_path)
            self._finish(f"geotagging failed: {e}", f"geotagging failed: {e}")
            return
        lines = report.lines()
        left = [f"{n} {one if n == 1 else many}" for n, one, many in (
            (len(report.unmatched), "photo untagged", "photos untagged"),
            (len(report.events_without_photo), "event without a photo", "events without a photo")) if n]
        self._finish(lines[0].split(" into ")[0] + (f"; {', '.join(left)}" if left else ""), "\n".join(lines),
                     report)

    def _finish(self, status: str, text: str, result: object = None) -> None:
        self.status.setText(status)
        self.report.setPlainText(text)
        self.finished_run.emit(result if result is not None else text)

    def shutdown(self) -> None:
        """The review closes: a run under way finishes its photo by photo writes, nothing new starts."""
        self._pool.shutdown(wait=False)
