"""Preferences, the key list, and the takeoff confirmation (non-blocking)."""
from __future__ import annotations

import math
from dataclasses import replace

from PyQt5 import uic
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QDialog, QFileDialog, QMessageBox, QTableWidgetItem, QWidget

from driver.api import CEILING

from . import RESOURCES
from .camera_controller import default_media_folder
from .keyboard import key_help
from .settings import TAKEOFF_ALTITUDE_RANGE, ViewerSettings, split_uris
from .sticks import StickMode

__all__ = ["SettingsDialog", "KeysDialog", "takeoff_question", "mode_question"]


class SettingsDialog(QDialog):
    """Stick mode, maximum speeds, deadband, expo, takeoff altitude, and the camera: sources, media folder, HUD."""

    def __init__(self, settings: ViewerSettings, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        uic.loadUi(str(RESOURCES / "ui" / "settings_dialog.ui"), self)
        self._settings = settings
        for mode in StickMode:
            self.stickMode.addItem(mode.title, mode.value)
        self.stickMode.setCurrentIndex(self.stickMode.findData(settings.mode.value))
        self.maxHorizontal.setMaximum(CEILING.horizontal)     # no more than the driver ever streams
        self.maxVertical.setMaximum(CEILING.vertical)
        self.maxYaw.setMaximum(math.floor(math.degrees(CEILING.yaw_rate)))
        self.takeoffAltitude.setRange(*TAKEOFF_ALTITUDE_RANGE)
        self.maxHorizontal.setValue(settings.max_horizontal)
        self.maxVertical.setValue(settings.max_vertical)
        self.maxYaw.setValue(settings.max_yaw_deg_s)
        self.deadband.setValue(settings.deadband)
        self.expo.setValue(settings.expo)
        self.takeoffAltitude.setValue(settings.takeoff_altitude)
        self.cameraUris.setPlainText("\n".join(settings.camera_uris))
        self.mediaFolder.setText(settings.media_folder)
        self.mediaFolder.setPlaceholderText(default_media_folder())
        self.hudDefault.setChecked(settings.hud)
        self.folder_dialog: QFileDialog | None = None
        self.browseMediaFolder.clicked.connect(self.browse_media_folder)

    def browse_media_folder(self) -> QFileDialog:
        """Qt's own (non-native) folder chooser, opened without waiting on it."""
        dialog = QFileDialog(self, "Media folder", self.mediaFolder.text() or default_media_folder())
        dialog.setFileMode(QFileDialog.Directory)
        dialog.setOptions(QFileDialog.ShowDirsOnly | QFileDialog.DontUseNativeDialog)
        dialog.fileSelected.connect(self.mediaFolder.setText)
        self.folder_dialog = dialog
        dialog.open()
        return dialog

    def chosen(self) -> ViewerSettings:
        return replace(self._settings, stick_mode=self.stickMode.currentData(),
                       max_horizontal=self.maxHorizontal.value(), max_vertical=self.maxVertical.value(),
                       max_yaw_deg_s=self.maxYaw.value(), deadband=self.deadband.value(),
                       expo=self.expo.value(), takeoff_altitude=self.takeoffAltitude.value(),
                       cameras="\n".join(split_uris(self.cameraUris.toPlainText())),
                       media_folder=self.mediaFolder.text().strip(), hud=self.hudDefault.isChecked())


class KeysDialog(QDialog):
    """Help > Keys, filled from the same table the keyboard handler uses."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        uic.loadUi(str(RESOURCES / "ui" / "keys_dialog.ui"), self)
        rows = key_help()
        self.table.setColumnCount(2)
        self.table.setHorizontalHeaderLabels(["Key", "Action"])
        self.table.setRowCount(len(rows))
        for i, (key, text) in enumerate(rows):
            self.table.setItem(i, 0, QTableWidgetItem(key))
            self.table.setItem(i, 1, QTableWidgetItem(text))
        self.table.resizeColumnToContents(0)


def takeoff_question(parent: QWidget, altitude: float) -> QMessageBox:
    """A window-modal question, opened with ``open()`` so nothing waits on it.

    Cancel is the focused default: Space (Stop) or Enter must never start the motors; only a click does.
    """
    box = QMessageBox(QMessageBox.Question, "Take off",
                      f"Take off and climb to {altitude:.1f} m above home?\n\n"
                      "The motors will start. Keep clear of the propellers.",
                      QMessageBox.Yes | QMessageBox.Cancel, parent)
    box.setObjectName("takeoffQuestion")
    go = box.button(QMessageBox.Yes)
    go.setText("Take off")
    go.setFocusPolicy(Qt.NoFocus)
    go.setAutoDefault(False)
    box.setDefaultButton(QMessageBox.Cancel)
    box.setEscapeButton(QMessageBox.Cancel)
    return box


def mode_question(parent: QWidget, mode: str, warning: str) -> QMessageBox:
    """Confirm a mode that needs an RC transmitter in flight, saying why (the driver's words).

    Like the takeoff question: window-modal, opened without waiting, Cancel the focused default.
    """
    box = QMessageBox(QMessageBox.Warning, f"Switch to {mode}", warning, QMessageBox.Yes | QMessageBox.Cancel,
                      parent)
    box.setObjectName("modeQuestion")
    go = box.button(QMessageBox.Yes)
    go.setText(f"Switch to {mode}")
    go.setFocusPolicy(Qt.NoFocus)
    go.setAutoDefault(False)
    box.setDefaultButton(QMessageBox.Cancel)
    box.setEscapeButton(QMessageBox.Cancel)
    return box
