"""The window before any vehicle answers: waiting banner, settings remembered, keys dialog, --help."""
from __future__ import annotations

import socket
import subprocess
import sys
from pathlib import Path

import pytest
from PyQt5.QtWidgets import QApplication

from driver.vehicle import Vehicle, VehicleConfig
from uavviewer.dialogs import KeysDialog
from uavviewer.keyboard import key_help
from uavviewer.settings import ViewerSettings
from uavviewer.sticks import StickMode, pad_labels

from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture
def silent_vehicle():
    """A real driver pointed at a UDP port nobody sends to: it waits for a vehicle."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    v = Vehicle(VehicleConfig(connection=f"udpin:127.0.0.1:{port}")).start()
    yield v
    v.close()


def test_waiting_banner_and_inert_controls(qtbot, silent_vehicle, window_factory):
    w = window_factory(silent_vehicle)
    qtbot.waitUntil(lambda: w.linkBanner.isVisible(), timeout=3000)
    assert w.linkBanner.text() == f"Waiting for vehicle on {silent_vehicle.description}…"
    assert not w.flightControls.main_button.isEnabled()
    assert not w.leftStick.isEnabled() and not w.rightStick.isEnabled()
    assert not w.attitude.values["valid"]


def test_settings_are_remembered(qtbot, silent_vehicle, window_factory):
    w = window_factory(silent_vehicle)
    w.set_settings(ViewerSettings(stick_mode=StickMode.MODE1.value, max_horizontal=3.5, max_vertical=0.5,
                                  max_yaw_deg_s=30.0, deadband=0.1, expo=0.3, takeoff_altitude=5.0))
    assert w.leftStick._caption == pad_labels(StickMode.MODE1)[0]
    w.close()
    again = window_factory(silent_vehicle)
    s = again.settings
    assert (s.mode, s.max_horizontal, s.max_vertical, s.max_yaw_deg_s, s.deadband, s.expo,
            s.takeoff_altitude) == (StickMode.MODE1, 3.5, 0.5, 30.0, 0.1, 0.3, 5.0)
    assert again.rightStick._caption == pad_labels(StickMode.MODE1)[1]


def test_keys_dialog_lists_the_keys(qtbot, silent_vehicle, window_factory):
    w = window_factory(silent_vehicle)
    w.actionKeys.trigger()
    qtbot.waitUntil(lambda: any(isinstance(t, KeysDialog) and t.isVisible()
                                for t in QApplication.topLevelWidgets()), timeout=3000)
    dialog = next(t for t in QApplication.topLevelWidgets() if isinstance(t, KeysDialog))
    assert dialog.table.rowCount() == len(key_help())
    dialog.reject()


def test_help_documents_every_option():
    out = subprocess.run([sys.executable, str(ROOT / "main.py"), "--help"], capture_output=True, text=True,
                         timeout=60, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    for option in ("--sim", "--connect", "--replay", "--baud", "--takeoff-altitude", "--speedup",
                   "--ready-after", "--log-dir", "-v"):
        assert option in out.stdout
