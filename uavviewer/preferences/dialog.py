"""Preferences: sticks, speeds, takeoff altitude, cameras, link security (and the signing set-up question)."""
from __future__ import annotations

import math
import os
from dataclasses import replace

from PyQt5 import uic
from PyQt5.QtCore import pyqtSignal
from PyQt5.QtWidgets import QDialog, QFileDialog, QMessageBox, QWidget

from driver.vehicle.api import CEILING
from driver.link.signing import key_from_passphrase, read_key_file, write_key_file
from driver.vehicle.state import CommandResult, Signing, SigningStatus

from .. import RESOURCES
from ..camera.controller import default_media_folder
from ..widgets.ask import ask, cautious_question
from ..widgets.dialog_fit import scrollable
from ..connect.security import SIGNING_WARNINGS
from ..settings import TAKEOFF_ALTITUDE_RANGE, ViewerSettings, split_uris
from ..input.sticks import StickMode
from ..telemetry.panel import GOOD, NORMAL, WARN

__all__ = ["SettingsDialog", "signing_setup_question"]


class SettingsDialog(QDialog):
    """Stick mode, maximum speeds, deadband, expo, takeoff altitude; the camera: sources, media folder, HUD;
    and Link security: MAVLink 2 signing.

    The Link security buttons act at once, through the signals below (the window carries them to the drone
    and feeds back :meth:`set_signing` and :meth:`show_signing_result`); OK keeps only the key file's path.
    ``signing_unavailable``: why this drone cannot be signed from here (a remote one); the page says it.
    """

    signingKeyRequested = pyqtSignal(object)      # bytes: sign with this key from now on; None: stop signing
    signingSetupRequested = pyqtSignal(bytes)     # give the vehicle this key (the pilot confirmed: in clear)
    signingRemoveRequested = pyqtSignal()         # tell the vehicle to stop signing
    allowUnsignedRequested = pyqtSignal(bool)     # let the vehicle's unsigned frames in, or not

    def __init__(self, settings: ViewerSettings, parent: QWidget | None = None,
                 signing_unavailable: str = "") -> None:
        super().__init__(parent)
        uic.loadUi(str(RESOURCES / "ui" / "settings_dialog.ui"), self)
        self.setObjectName("preferencesDialog")
        self.setMinimumWidth(0)                   # 520 px is its first width, not its least: the pages scroll
        self.resize(max(self.width(), 520), self.height())
        form = QDialog.layout(self)               # the pages scroll on a short screen; OK and Cancel stay in view
        at = form.indexOf(self.pages)
        form.removeWidget(self.pages)
        form.insertWidget(at, scrollable(self.pages, horizontal=True), 1)
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
        self.deadband.setValue(100.0 * settings.deadband)        # a fraction of the travel, shown in %
        self.expo.setValue(100.0 * settings.expo)
        t = settings.battery_thresholds
        self.batteryWarningCell.setValue(t.warning_cell)
        self.batteryWarningPercent.setValue(t.warning_percent)
        self.batteryCriticalCell.setValue(t.critical_cell)
        self.batteryCriticalPercent.setValue(t.critical_percent)
        self.takeoffAltitude.setValue(settings.takeoff_altitude)
        self.cameraUris.setPlainText("\n".join(settings.camera_uris))
        self.mediaFolder.setText(settings.media_folder)
        self.mediaFolder.setPlaceholderText(default_media_folder())
        self.hudDefault.setChecked(settings.hud)
        self.tileUrl.setText(settings.tile_url)
        self.tileAttribution.setText(settings.tile_attribution)
        self.tileCacheMb.setValue(int(settings.tile_cache_mb))
        self.folder_dialog: QFileDialog | None = None
        self.browseMediaFolder.clicked.connect(self.browse_media_folder)
        self._init_signing(settings, signing_unavailable)

    def add_page(self, page: QWidget, title: str) -> None:
        """A page with a widget of its own (Gamepad), after the others."""
        self.pages.addTab(page, title)

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
                       max_yaw_deg_s=self.maxYaw.value(), deadband=self.deadband.value() / 100.0,
                       expo=self.expo.value() / 100.0, takeoff_altitude=self.takeoffAltitude.value(),
                       battery_warning_cell=max(self.batteryWarningCell.value(), self.batteryCriticalCell.value()),
                       battery_critical_cell=self.batteryCriticalCell.value(),
                       battery_warning_percent=max(self.batteryWarningPercent.value(),
                                                   self.batteryCriticalPercent.value()),
                       battery_critical_percent=self.batteryCriticalPercent.value(),
                       cameras="\n".join(split_uris(self.cameraUris.toPlainText())),
                       media_folder=self.mediaFolder.text().strip(), hud=self.hudDefault.isChecked(),
                       signing_key_file=self.signingKeyFile.text().strip(), tile_url=self.tileUrl.text().strip(),
                       tile_attribution=self.tileAttribution.text().strip(),
                       tile_cache_mb=float(self.tileCacheMb.value()))

    # -- Link security ------------------------------------------------------------------------------
    def _init_signing(self, settings: ViewerSettings, unavailable: str) -> None:
        self._signing = Signing()
        self._unavailable = unavailable
        self.signing_status_color = ""            # the status line's colour (GOOD, WARN or NORMAL)
        self.key_file_dialog: QFileDialog | None = None
        self.save_key_dialog: QFileDialog | None = None
        self.setup_box: QMessageBox | None = None
        self.signingKeyFile.setText(settings.signing_key_file)
        (self.keyFromFile if settings.signing_key_file else self.keyFromPassphrase).setChecked(True)
        self.signingPassphrase.textEdited.connect(lambda _text: self.keyFromPassphrase.setChecked(True))
        self.signingKeyFile.textEdited.connect(lambda _text: self.keyFromFile.setChecked(True))
        self.signingPassphrase.textChanged.connect(self._update_signing_buttons)
        self.signingKeyFile.textChanged.connect(self._update_signing_buttons)
        self.keyFromPassphrase.toggled.connect(self._update_signing_buttons)
        self.browseKeyFile.clicked.connect(self.browse_key_file)
        self.signWithKey.clicked.connect(self._sign_with_key)
        self.stopSigning.clicked.connect(lambda: self.signingKeyRequested.emit(None))
        self.setupSigning.clicked.connect(self.ask_setup)
        self.removeSigning.clicked.connect(lambda: self.signingRemoveRequested.emit())
        self.allowUnsigned.clicked.connect(self.allowUnsignedRequested)   # the pilot's click, never set_signing
        self.saveKeyFile.clicked.connect(self.choose_key_file_to_save)
        if unavailable:
            self.signingUnavailable.setText(f"Not available with this connection: {unavailable}.")
            self.signingUnavailable.setStyleSheet(f"color: {WARN};")
            self.signingUnavailable.setVisible(True)
            for w in (self.signingStatusLabel, self.signingStatus, self.keyFromPassphrase, self.signingPassphrase,
                      self.keyFromFile, self.signingKeyFile, self.browseKeyFile, self.signWithKey,
                      self.stopSigning, self.setupSigning, self.removeSigning, self.allowUnsigned,
                      self.saveKeyFile):
                w.setEnabled(False)
            self.signingStatus.setText("not known here")
            return
        self.set_signing(self._signing)

    def set_signing(self, signing: Signing) -> None:
        """The live state of signing on the link (from each snapshot)."""
        if self._unavailable:
            return
        self._signing = signing
        text = signing.summary
        if self.signingStatus.text() != text:
            self.signingStatus.setText(text)
            self.signingStatus.setToolTip(text)
        color = WARN if signing.status in SIGNING_WARNINGS else (
            GOOD if signing.status is SigningStatus.SIGNING else NORMAL)
        if color != self.signing_status_color:
            self.signing_status_color = color
            self.signingStatus.setStyleSheet(f"color: {color}; font-weight: bold;")
        if self.allowUnsigned.isChecked() != signing.allow_unsigned:
            self.allowUnsigned.setChecked(signing.allow_unsigned)
        self._update_signing_buttons()

    def show_signing_result(self, result: CommandResult) -> None:
        """What came of a Link security button: accepted, or refused and why (the vehicle's words)."""
        self._show_signing_text(str(result), GOOD if result.ok else WARN)

    def _show_signing_text(self, text: str, color: str) -> None:
        self.signingResult.setText(text)
        self.signingResult.setStyleSheet(f"color: {color};")

    def _update_signing_buttons(self) -> None:
        if self._unavailable:
            return
        from_file = self.keyFromFile.isChecked()
        phrase = bool(self.signingPassphrase.text())
        named = bool(self.signingKeyFile.text().strip()) if from_file else phrase
        in_use = self._signing.link_id is not None
        busy = self._signing.status is SigningStatus.SETTING_UP
        self.signWithKey.setEnabled(named)
        self.setupSigning.setEnabled(named and not busy)
        self.stopSigning.setEnabled(in_use)
        self.removeSigning.setEnabled(in_use and not busy)
        self.saveKeyFile.setEnabled(not from_file and phrase)

    def chosen_key(self) -> bytes | None:
        """The key the page names now (the passphrase's, or the key file's); None, with the reason shown."""
        try:
            if self.keyFromFile.isChecked():
                path = self.signingKeyFile.text().strip()
                if not path:
                    raise ValueError("choose a key file")
                return read_key_file(os.path.expanduser(path))
            if not self.signingPassphrase.text():
                raise ValueError("enter a passphrase")
            return key_from_passphrase(self.signingPassphrase.text())
        except ValueError as exc:
            self._show_signing_text(f"No key: {exc}", WARN)
            return None

    def _sign_with_key(self) -> None:
        key = self.chosen_key()
        if key is not None:
            self.signingKeyRequested.emit(key)

    def ask_setup(self) -> QMessageBox | None:
        """Confirm first (the key travels in clear), then ask for SETUP_SIGNING; nothing waits on the answer."""
        key = self.chosen_key()
        if key is None:
            return None
        self.setup_box = ask(signing_setup_question(self), lambda box: self._setup_answered(box, key))
        return self.setup_box

    def _setup_answered(self, box: QMessageBox, key: bytes) -> None:
        if box.clickedButton() is box.button(QMessageBox.Yes):
            self._show_signing_text("Sending the key to the vehicle…", NORMAL)
            self.signingSetupRequested.emit(key)
        box.deleteLater()
        if self.setup_box is box:
            self.setup_box = None

    def browse_key_file(self) -> QFileDialog:
        """Qt's own (non-native) file chooser, opened without waiting on it."""
        start = self.signingKeyFile.text().strip() or os.path.expanduser("~")
        dialog = QFileDialog(self, "Signing key file", start)
        dialog.setFileMode(QFileDialog.ExistingFile)
        dialog.setOptions(QFileDialog.DontUseNativeDialog)
        dialog.fileSelected.connect(self._key_file_chosen)
        self.key_file_dialog = dialog
        dialog.open()
        return dialog

    def _key_file_chosen(self, path: str) -> None:
        self.signingKeyFile.setText(path)
        self.keyFromFile.setChecked(True)

    def choose_key_file_to_save(self) -> QFileDialog | None:
        """Save the passphrase's key to a file only the pilot can read (0600), chosen without waiting."""
        key = self.chosen_key()
        if key is None:
            return None
        start = os.path.join(os.path.expanduser("~"), "uavviewer-signing.key")
        dialog = QFileDialog(self, "Save the signing key", start)
        dialog.setAcceptMode(QFileDialog.AcceptSave)
        dialog.setOptions(QFileDialog.DontUseNativeDialog)
        dialog.fileSelected.connect(lambda path, k=key: self._save_key(path, k))
        self.save_key_dialog = dialog
        dialog.open()
        return dialog

    def _save_key(self, path: str, key: bytes) -> None:
        try:
            write_key_file(path, key)
        except OSError as exc:
            self._show_signing_text(f"Key not saved: {exc}", WARN)
            return
        self.signingKeyFile.setText(path)
        self.keyFromFile.setChecked(True)
        self.signingPassphrase.clear()
        self._show_signing_text(f"Key saved to {path}, readable only by you. OK remembers this file; the "
                                "passphrase is not kept.", GOOD)


def signing_setup_question(parent: QWidget) -> QMessageBox:
    """Before SETUP_SIGNING: the key travels in clear. Cancel is the focused default."""
    return cautious_question(parent, "Set up signing on the vehicle",
                             "Send the signing key to the vehicle?\n\n"
                             "SETUP_SIGNING carries the key in clear: anyone listening on this link learns it. Send "
                             "it only over USB or a cable, never over a radio or Wi-Fi link.\n\n"
                             "The vehicle keeps the key, and from then on its telemetry links obey only frames signed "
                             "with it. It must be disarmed.", "Send the key", "signingSetupQuestion",
                             QMessageBox.Warning)
