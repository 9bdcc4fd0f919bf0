"""The Map dock: the canvas and its bar (follow, home, grid or tiles, offline, download this area)."""
from __future__ import annotations

from PyQt5 import uic
from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import QWidget

from .. import RESOURCES

__all__ = ["MapPanel"]


class MapPanel(QWidget):
    """Buttons say what the pilot wants; the controller decides what it means."""

    layerRequested = pyqtSignal(bool)          # True: tiles, False: the offline grid
    offlineRequested = pyqtSignal(bool)
    downloadRequested = pyqtSignal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        uic.loadUi(str(RESOURCES / "ui" / "map_panel.ui"), self)
        self.setObjectName("mapPanel")
        for button in (self.followButton, self.homeButton, self.downloadButton, self.layerCombo, self.offlineCheck):
            button.setFocusPolicy(Qt.NoFocus)           # keys keep flying the drone
        self.followButton.toggled.connect(self.mapView.set_follow)
        self.mapView.followChanged.connect(self._follow_changed)
        self.homeButton.clicked.connect(self._show_home)
        self.layerCombo.currentIndexChanged.connect(lambda i: self.layerRequested.emit(i == 1))
        self.offlineCheck.toggled.connect(self.offlineRequested.emit)
        self.layerCombo.currentIndexChanged.connect(lambda _i: self._explain_disabled())
        self.downloadButton.clicked.connect(self.downloadRequested.emit)
        self.set_tiles_available(False)

    def hold_still(self, on: bool) -> None:
        """Plan editing (``on``): the map never moves under the pointer, so a click lands where it was aimed; Follow
        is off and cannot be turned on. Editing over: Follow as it was before."""
        button = self.followButton
        if on and button.isEnabled():
            self._followed, self._follow_tip = button.isChecked(), button.toolTip()
            button.setChecked(False)
            button.setEnabled(False)
            button.setToolTip("Off while the plan is edited: the map stays still under the pointer")
        elif not on and not button.isEnabled():
            button.setEnabled(True)
            button.setToolTip(self._follow_tip)
            button.setChecked(self._followed)

    def _follow_changed(self, on: bool) -> None:
        if self.followButton.isChecked() != on:
            self.followButton.setChecked(on)

    def _show_home(self) -> None:
        self.followButton.setChecked(False)
        self.mapView.centre = (0.0, 0.0)
        self.mapView.update()

    def set_tiles_available(self, available: bool, why: str = "") -> None:
        """Tiles can be chosen only with a server in Preferences (and a home with a latitude)."""
        model = self.layerCombo.model()
        model.item(1).setEnabled(available)
        model.item(1).setToolTip(why)
        if not available and self.layerCombo.currentIndex() == 1:
            self.layerCombo.setCurrentIndex(0)
        tiles = self.layerCombo.currentIndex() == 1
        self.offlineCheck.setEnabled(tiles)
        self.downloadButton.setEnabled(tiles and not self.offlineCheck.isChecked())
        # a disabled control says why, and what enables it
        needs = ("Needs the Tiles layer: " + (why or "pick Tiles in the list") if not tiles else "")
        self.offlineCheck.setToolTip(needs or "Tiles from the cache only: no network")
        self.downloadButton.setToolTip(needs or ("Offline: untick Offline to download" if self.offlineCheck.isChecked()
                                                 else "Keep the tiles of this area (this zoom and three closer) "
                                                      "for offline use"))

    def _explain_disabled(self) -> None:
        """The layer changed: Offline and Download follow it, saying why when they cannot be used."""
        model = self.layerCombo.model()
        self.set_tiles_available(model.item(1).isEnabled(), model.item(1).toolTip())

    def set_status(self, text: str) -> None:
        self.statusLabel.setText(text)
        self.statusLabel.setToolTip(text)
