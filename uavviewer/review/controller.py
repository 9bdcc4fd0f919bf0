"""File › Review a log…: a .BIN or .tlog opened off the window's thread (a 100 MB log indexes in about 1.5 s) and
shown in a :class:`ReviewWindow`; a log that cannot be read says why and breaks nothing."""
from __future__ import annotations

import logging
from concurrent.futures import Future, ThreadPoolExecutor

from PyQt5 import sip
from PyQt5.QtCore import QObject, Qt, pyqtSignal
from PyQt5.QtWidgets import QAction, QFileDialog, QMessageBox

from driver.review import LogError, open_log

from .view import ReviewWindow

log = logging.getLogger(__name__)

__all__ = ["ReviewController"]


class ReviewController(QObject):
    """Given the window (its ``menuFile`` and ``adapter``). ``opened`` gives each new :class:`ReviewWindow`;
    ``failed`` the words shown for a log that cannot be read."""

    opened = pyqtSignal(object)
    failed = pyqtSignal(str)
    _done = pyqtSignal(object, str)

    def __init__(self, window, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.window = window
        self.views: list[ReviewWindow] = []
        self._pool = ThreadPoolExecutor(1, thread_name_prefix="review")
        self._done.connect(self._show)
        self.action = QAction("Re&view a log (plots)…", window)
        self.action.setObjectName("actionReviewLog")
        self.action.setToolTip("Plots, events, the path and the parameters of a DataFlash .BIN or a telemetry .tlog, "
                               "in a window of its own; the vehicle flown now stays flown")
        self.action.triggered.connect(self.ask_open)
        actions = window.menuFile.actions()
        beside = getattr(getattr(window, "logs", None), "action", None)     # under Replay a flight, its neighbour
        window.menuFile.insertAction(beside if beside in actions else actions[0] if actions else None, self.action)

    def current_params(self) -> dict[str, float]:
        values = self.window.adapter.state.parameters.values
        return {name: float(p.value) for name, p in values.items()}

    def ask_open(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self.window, "Open a flight log", "",
                                              "Flight logs (*.BIN *.bin *.tlog);;All files (*)")
        if path:
            self.open(path)

    def open(self, path: str) -> Future:
        """Index the log on a worker thread; the view opens when it is ready (or the reason is shown)."""
        future = self._pool.submit(open_log, path)
        future.add_done_callback(lambda f: self._done.emit(f, path))
        return future

    def _show(self, future: Future, path: str) -> None:
        try:
            flight = future.result()
        except LogError as e:
            self._fail(str(e))
            return
        except Exception as e:                               # noqa: BLE001 - a bad file never crashes the window
            log.exception("opening %s", path)
            self._fail(f"{path}: cannot be read ({e})")
            return
        view = ReviewWindow(flight, self.current_params, submit=self._pool.submit)
        view.setAttribute(Qt.WA_DeleteOnClose)          # closed, its window and its log's arrays go
        view.destroyed.connect(self._forget)
        view.resize(1366, 768)
        view.show()
        self.views.append(view)
        self.opened.emit(view)

    def _forget(self, _view=None) -> None:
        """Drop the reviews Qt has deleted since they closed: kept here, each held its log's arrays for good."""
        self.views = [v for v in self.views if not sip.isdeleted(v)]

    def _fail(self, text: str) -> None:
        self.failed.emit(text)
        box = QMessageBox(QMessageBox.Warning, "Cannot open this log", text, QMessageBox.Ok, self.window)
        box.setModal(False)
        box.show()
        self.box = box

    def close(self) -> None:
        for view in self.views:
            view.close()
        self._pool.shutdown(wait=False, cancel_futures=True)
