"""Where the flight logs are: File › Open logs folder (the desktop's file manager) and a line in Help › About.

Every live session records its MAVLink as ``flight-<time>.tlog`` (and the viewer's own ``viewer.log``) in the
logs folder (``--log-dir``, by default the per-user data folder's ``logs/``); a pilot looking for the flight just
flown finds it here, without knowing the platform's data folder.
"""
from __future__ import annotations

import os
from pathlib import Path

from PyQt5.QtCore import QCoreApplication, QObject, QStandardPaths, QUrl
from PyQt5.QtGui import QDesktopServices
from PyQt5.QtWidgets import QAction

from driver.vehicle.state import Severity

__all__ = ["LogsFolder", "default_log_dir"]


def default_log_dir() -> Path:
    """The per-user data folder Qt knows for this platform, plus logs/."""
    QCoreApplication.setApplicationName("UavViewerPy")
    return Path(QStandardPaths.writableLocation(QStandardPaths.AppDataLocation)) / "logs"


class LogsFolder(QObject):
    def __init__(self, window, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self._window = window
        self.open_url = QDesktopServices.openUrl          # the desktop's file manager (tests put their own)
        self.action = QAction("Open &logs folder", window)
        self.action.setObjectName("actionOpenLogsFolder")
        self.action.triggered.connect(self.open)

    @property
    def path(self) -> str | None:
        """The folder live links record into; None with --no-log."""
        return getattr(self._window.connections, "log_dir", None)

    @property
    def downloads(self) -> str:
        """Where the vehicle's DataFlash logs are saved (Logs › Flight logs): this folder, or with --no-log the
        default one (downloading a log is asked for by name; --no-log is about recording the link)."""
        return self.path or str(default_log_dir())

    def about_line(self) -> str:
        return f"Flight logs: {self.path}" if self.path else "Flight logs: not recorded (--no-log)"

    def open(self) -> None:
        path = self.path
        if not path:
            self._window.log_message("No flight logs are recorded in this session (--no-log)", Severity.NOTICE)
            return
        os.makedirs(path, exist_ok=True)
        if not self.open_url(QUrl.fromLocalFile(path)):
            self._window.log_message(f"No file manager opened the logs folder: {path}", Severity.WARNING)
