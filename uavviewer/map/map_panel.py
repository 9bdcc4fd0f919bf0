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
        self.downloadButton.clicked.connect(self.downloadRequested.emit)
        self.set_tiles_available(False)

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

    def set_status(self, text: str) -> None:
        self.statusLabel.setText(text)
        self.statusLabel.setToolTip(text)
