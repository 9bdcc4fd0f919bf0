"""The pilot's preferences: loaded at start, applied to the parts they steer, edited in Preferences, saved.

Preferences is not modal: Stop, Land and RTL stay one click away while it is open. Its Link security page acts
at once, through the adapter (never waiting), and its results come back to the page. ``--takeoff-altitude``
holds for this run only: shown in Preferences and left alone, it is never saved as the Preferences' value.
A choice made on the window itself (the Map's layer, offline) is kept for the next run too.
"""
from __future__ import annotations

import logging
from dataclasses import replace

from PyQt5.QtCore import QByteArray, QObject, QSettings, Qt

from driver.vehicle.state import CommandResult, VehicleState

from ..camera.controller import default_media_folder
from ..input.gamepad_page import GamepadPage
from ..map.controller import TileSettings
from ..settings import ViewerSettings, load_settings, load_window, save_settings, save_window
from .dialog import SettingsDialog

__all__ = ["Preferences"]

log = logging.getLogger(__name__)


class Preferences(QObject):
    """``window``: the main window (its sticks, map, camera and adapter, which the preferences steer)."""

    def __init__(self, window, qsettings: QSettings, takeoff_altitude: float | None) -> None:
        super().__init__(window)
        self.window = w = window
        self.qsettings = qsettings
        self.settings: ViewerSettings = load_settings(qsettings)
        self.takeoff_override = takeoff_altitude
        self.dialog: SettingsDialog | None = None           # Preferences while open
        w.actionPreferences.triggered.connect(self.edit)
        # every vehicle flown (a fleet's pick, File › Connect) is judged by the pilot's battery thresholds
        w.adapter.droneChanged.connect(lambda _drone: self.set_battery_thresholds())

    @property
    def takeoff_altitude(self) -> float:
        """--takeoff-altitude for this run, else the Preferences' value."""
        return self.takeoff_override if self.takeoff_override is not None else self.settings.takeoff_altitude

    def keep_map_choices(self, panel) -> None:
        """The Map's offline switch as saved (its controller is listening already); its choices are kept."""
        panel.offlineCheck.setChecked(self.settings.map_offline)
        panel.layerRequested.connect(lambda on: self.remember(map_tiles=on))
        panel.offlineRequested.connect(lambda on: self.remember(map_offline=on))

    def apply(self) -> None:
        s, w = self.settings, self.window
        w.sticks.apply(s)
        self.set_battery_thresholds()
        w.map.set_tile_settings(TileSettings(s.tile_url.strip(), s.tile_attribution.strip(), int(s.tile_cache_mb),
                                             w.tile_cache_dir))
        if s.map_tiles and s.tile_url:
            w.mapPanel.layerCombo.setCurrentIndex(1)

    def remember(self, **choice) -> None:
        """A choice made on the window itself (the Map's layer, offline), kept for the next run."""
        self.settings = replace(self.settings, **choice)
        save_settings(self.qsettings, self.settings)

    def set_battery_thresholds(self) -> None:
        """The pilot's battery thresholds become the driver's alarm (a remote drone keeps its own judge)."""
        try:
            self.window.adapter.drone.set_battery_thresholds(self.settings.battery_thresholds)
        except NotImplementedError:
            pass
        except Exception:                       # noqa: BLE001 - a bad value or a remote failure: keep the alarm
            log.exception("setting the battery thresholds failed")

    def edit(self) -> None:
        """Not modal: Stop, Land and RTL stay one click away while it is open (its opening centres the sticks)."""
        if self.dialog is not None:
            self.dialog.raise_()
            self.dialog.activateWindow()
            return
        w = self.window
        shown = self.takeoff_altitude
        dialog = SettingsDialog(replace(self.settings, takeoff_altitude=shown), w,
                                signing_unavailable=w.signing_unavailable)
        dialog.setAttribute(Qt.WA_DeleteOnClose)
        a, said = w.adapter, self._show_signing_result
        dialog.signingKeyRequested.connect(lambda key: a.send(a.drone.use_signing_key, key, then=said))
        dialog.signingSetupRequested.connect(lambda key: a.send(a.drone.setup_signing, key, then=said))
        dialog.signingRemoveRequested.connect(lambda: a.send(a.drone.remove_signing, then=said))
        dialog.allowUnsignedRequested.connect(lambda on: a.send(a.drone.allow_unsigned, on, then=said))
        dialog.set_signing(w.adapter.state.signing)
        gamepad = GamepadPage(w.sticks.gamepad, self.settings)
        dialog.add_page(gamepad, "Gamepad")
        dialog.accepted.connect(lambda: self._chosen(replace(dialog.chosen(), **gamepad.chosen()), shown))
        # finished, not destroyed: a slot on ``destroyed`` would run while a garbage-collected window is being
        # torn down (its children go with it) and touch a half-deleted wrapper.
        dialog.finished.connect(lambda _result: setattr(self, "dialog", None))
        self.dialog = dialog
        dialog.show()

    def show_state(self, s: VehicleState) -> None:
        if self.dialog is not None:
            self.dialog.set_signing(s.signing)

    def _show_signing_result(self, result: CommandResult) -> None:
        if self.dialog is not None:
            self.dialog.show_signing_result(result)

    def _chosen(self, settings: ViewerSettings, shown_altitude: float) -> None:
        if self.takeoff_override is not None and settings.takeoff_altitude == shown_altitude:
            # --takeoff-altitude was shown and left alone: it stays for this run and is not saved.
            self.set_settings(replace(settings, takeoff_altitude=self.settings.takeoff_altitude),
                              keep_override=True)
        else:
            self.set_settings(settings)

    def set_settings(self, settings: ViewerSettings, keep_override: bool = False) -> None:
        old, self.settings = self.settings, settings
        if not keep_override:
            self.takeoff_override = None         # the pilot has now chosen the altitude in Preferences
        save_settings(self.qsettings, settings)
        self.apply()
        camera = self.window.camera
        camera.folder = settings.media_folder or default_media_folder()
        if settings.hud != old.hud:
            self.window.camera_panel.hud_button.setChecked(settings.hud)
        if settings.camera_uris != old.camera_uris:          # new sources replace even --camera's
            camera.set_sources(settings.camera_uris or self.window.default_cameras)

    def restore_window(self) -> tuple[QByteArray | None, QByteArray | None]:
        return load_window(self.qsettings)

    def save(self, geometry: QByteArray, state: QByteArray) -> None:
        """On closing: the preferences and the window's geometry and docks."""
        save_settings(self.qsettings, self.settings)
        save_window(self.qsettings, geometry, state)
