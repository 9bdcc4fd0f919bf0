"""What the viewer remembers between runs (QSettings): sticks, speeds, last link, camera, the signing key file's
path, gamepads (mapped per controller GUID), window layout. Never a signing passphrase or key: only where the
pilot keeps the key file."""
from __future__ import annotations

import math
import re
from dataclasses import asdict, dataclass, fields

from PyQt5.QtCore import QByteArray, QSettings

from driver.vehicle.api import CEILING
from driver.vehicle.state import BatteryThresholds
from driver.vehicle.rules import TAKEOFF_ALTITUDE_RANGE

from .input.sticks import MaxSpeeds, StickMode, StickShaping

__all__ = ["ViewerSettings", "load_settings", "save_settings", "default_qsettings", "split_uris",
           "TAKEOFF_ALTITUDE_RANGE"]

#: Takeoff altitudes a pilot may choose (Preferences and --takeoff-altitude): the driver's rule, driver.rules.

ORGANISATION = "JdeRobot"
APPLICATION = "UavViewerPy"


@dataclass
class ViewerSettings:
    stick_mode: str = StickMode.MODE2.value
    max_horizontal: float = 2.0      # m/s
    max_vertical: float = 1.0        # m/s
    max_yaw_deg_s: float = 45.0      # deg/s
    deadband: float = 0.05
    expo: float = 0.0
    takeoff_altitude: float = 3.0    # m
    last_connection: str = ""
    cameras: str = ""                # camera URIs, one a line or comma separated; "" = the mode's own camera
    media_folder: str = ""           # snapshots and recordings; "" = Movies/UavViewer
    hud: bool = True                 # HUD over the video when the viewer starts
    signing_key_file: str = ""       # Link security: the key file's path, never the key or a passphrase
    gamepad: str = "auto"            # the gamepad that flies: "auto" (the first connected), "off", or its GUID
    gamepad_background: bool = False  # the gamepad keeps flying while the window is not active
    gamepad_mappings: str = ""       # JSON: controller GUID -> its mapping (uavviewer.input.gamepad_mapping)
    tile_url: str = ""               # Map: a {z}/{x}/{y} tile server; "" = the offline grid only
    tile_attribution: str = ""       # shown on the map with its tiles
    tile_cache_mb: float = 200.0     # the disk cache's limit
    map_tiles: bool = False          # the Map shows tiles (else the offline grid), as the pilot last chose
    map_offline: bool = False        # tiles from the cache only
    battery_warning_cell: float = BatteryThresholds.warning_cell       # V a cell: our own alarm (driver.battery)
    battery_critical_cell: float = BatteryThresholds.critical_cell
    battery_warning_percent: float = BatteryThresholds.warning_percent
    battery_critical_percent: float = BatteryThresholds.critical_percent

    @property
    def camera_uris(self) -> list[str]:
        return split_uris(self.cameras)

    @property
    def mode(self) -> StickMode:
        try:
            return StickMode(self.stick_mode)
        except ValueError:
            return StickMode.MODE2

    @property
    def speeds(self) -> MaxSpeeds:
        return MaxSpeeds(self.max_horizontal, self.max_vertical, self.max_yaw_deg_s)

    @property
    def battery_thresholds(self) -> BatteryThresholds:
        return BatteryThresholds(self.battery_warning_cell, self.battery_critical_cell,
                                 self.battery_warning_percent, self.battery_critical_percent)

    @property
    def shaping(self) -> StickShaping:
        return StickShaping(self.deadband, self.expo)


def split_uris(text: str) -> list[str]:
    r"""``"sim, 0\nvideo.mp4?loop=1"`` -> ``["sim", "0", "video.mp4?loop=1"]``."""
    return [u.strip() for u in re.split(r"[,\n]", text or "") if u.strip()]


def default_qsettings() -> QSettings:
    return QSettings(ORGANISATION, APPLICATION)


def load_settings(qs: QSettings) -> ViewerSettings:
    out = ViewerSettings()
    for f in fields(ViewerSettings):
        key = f"viewer/{f.name}"
        if not qs.contains(key):
            continue
        raw = qs.value(key)
        default = getattr(out, f.name)
        if isinstance(default, bool):          # an INI file gives "true"/"false"
            setattr(out, f.name, str(raw).lower() in ("true", "1"))
            continue
        try:
            value = float(raw) if isinstance(default, float) else str(raw)
        except (TypeError, ValueError):
            continue
        if isinstance(value, float) and value != value:
            continue
        setattr(out, f.name, value)
    # Sanity: a corrupt file must not give wild speeds.
    out.max_horizontal = min(max(out.max_horizontal, 0.1), CEILING.horizontal)
    out.max_vertical = min(max(out.max_vertical, 0.1), CEILING.vertical)
    out.max_yaw_deg_s = min(max(out.max_yaw_deg_s, 5.0), float(math.floor(math.degrees(CEILING.yaw_rate))))
    out.deadband = min(max(out.deadband, 0.0), 0.5)
    out.expo = min(max(out.expo, 0.0), 1.0)
    low, high = TAKEOFF_ALTITUDE_RANGE
    out.takeoff_altitude = min(max(out.takeoff_altitude, low), high)
    out.stick_mode = out.mode.value
    out.tile_cache_mb = min(max(out.tile_cache_mb, 10.0), 5000.0)
    if out.battery_thresholds.problem():                  # a corrupt file: the defaults, never no alarm
        default = BatteryThresholds()
        out.battery_warning_cell, out.battery_critical_cell = default.warning_cell, default.critical_cell
        out.battery_warning_percent, out.battery_critical_percent = default.warning_percent, default.critical_percent
    return out


def save_settings(qs: QSettings, settings: ViewerSettings) -> None:
    for name, value in asdict(settings).items():
        qs.setValue(f"viewer/{name}", value)
    qs.sync()


def save_window(qs: QSettings, geometry: QByteArray, state: QByteArray) -> None:
    qs.setValue("window/geometry", geometry)
    qs.setValue("window/state", state)
    qs.sync()


def load_window(qs: QSettings) -> tuple[QByteArray | None, QByteArray | None]:
    g = qs.value("window/geometry")
    s = qs.value("window/state")
    return (g if isinstance(g, QByteArray) else None, s if isinstance(s, QByteArray) else None)
