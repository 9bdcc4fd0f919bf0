"""Help › About: the version, the vehicle flown, the libraries, where the logs are."""
from __future__ import annotations

from PyQt5.QtCore import PYQT_VERSION_STR, QT_VERSION_STR, Qt
from PyQt5.QtWidgets import QMessageBox
from pymavlink import __version__ as pymavlink_version

from driver.version import __version__

__all__ = ["show_about"]


def show_about(window) -> QMessageBox:
    """Not modal and no nested event loop: flying goes on while it is open."""
    firmware = window.adapter.state.firmware
    box = QMessageBox(QMessageBox.Information, "About UavViewerPy",
                      f"UavViewerPy {__version__} — fly a MAVLink drone from a laptop.\n\n"
                      f"Vehicle: {window.window_name()}" + (f", ArduCopter {firmware}" if firmware else "") +
                      f"\nPyQt {PYQT_VERSION_STR}, Qt {QT_VERSION_STR}, pymavlink {pymavlink_version}"
                      f"\n\n{window.logs.about_line()}",
                      QMessageBox.Close, window)
    box.setObjectName("aboutBox")
    box.setWindowModality(Qt.NonModal)
    box.setAttribute(Qt.WA_DeleteOnClose)
    box.show()
    return box
