"""The window before any vehicle answers: waiting banner, settings (camera ones too) remembered, keys dialog, --help."""
from __future__ import annotations

import os
import socket
import subprocess
import sys
from pathlib import Path

import pytest
from PyQt5.QtWidgets import QApplication, QDialogButtonBox

from driver.vehicle import Vehicle, VehicleConfig
from uavviewer.input.keys_dialog import KeysDialog
from uavviewer.preferences.dialog import SettingsDialog
from uavviewer.settings import ViewerSettings, split_uris
from uavviewer.input.sticks import StickMode, pad_labels

from camera_media import write_clip
from test_camera_view import nearest, painted_rgb
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
    address = silent_vehicle.description.split(":", 1)[1]
    assert w.linkBanner.text() == f"No vehicle yet — listening on UDP {address}…"
    assert not w.flightControls.main_button.isEnabled()
    assert not w.leftStick.isEnabled() and not w.rightStick.isEnabled()
    assert not w.attitude.values["valid"]


def test_settings_are_remembered(qtbot, silent_vehicle, window_factory):
    w = window_factory(silent_vehicle)
    w.preferences.set_settings(ViewerSettings(stick_mode=StickMode.MODE1.value, max_horizontal=3.5, max_vertical=0.5,
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
    shown = [(dialog.table.item(r, 0).text(), dialog.table.item(r, 1).text())
             for r in range(dialog.table.rowCount())]
    assert shown == [("W", "Forward"), ("S", "Back"), ("A", "Left"), ("D", "Right"),
                     ("↑", "Climb"), ("↓", "Descend"), ("←", "Yaw left"), ("→", "Yaw right"),
                     ("Space", "Stop: hover where you are"), ("Esc", "Stop: cancel a Fly here, hover where you are"),
                     ("T", "Take off"), ("L", "Land"), ("R", "Return to launch (RTL)"),
                     ("PgUp", "Tilt the drone's camera up 5° (or the mouse wheel / drag on the video)"),
                     ("PgDn", "Tilt the drone's camera down 5°"),
                     ("(release)", "Releasing a key centres its axis"),
                     ("Space T L R", "Also from Setup, Parameters and every other window (not while typing in a field)"),
                     ("Gamepad A", "Stop (hover)"), ("Gamepad B", "Land"), ("Gamepad START", "Take off (asks)"),
                     ("Gamepad BACK", "Return to launch"),
                     ("Gamepad sticks", "As the on-screen sticks (mode and mapping: Preferences › Gamepad)")]
    dialog.reject()


def test_help_documents_every_option():
    out = subprocess.run([sys.executable, str(ROOT / "main.py"), "--help"], capture_output=True, text=True,
                         timeout=60, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    for option in ("--sim", "--connect", "--replay", "--baud", "--takeoff-altitude", "--speedup",
                   "--ready-after", "--log-dir", "-v"):
        assert option in out.stdout


def test_camera_preferences_reopen_the_camera_and_are_remembered(qtbot, silent_vehicle, window_factory, tmp_path):
    """Preferences: sources, media folder (chosen with Browse…) and HUD; applied on OK, kept for the next run,
    and --camera overrides the saved sources for its run."""
    red = write_clip(str(tmp_path / "red.mp4"), [(255, 0, 0)], repeat=60)
    blue = write_clip(str(tmp_path / "blue.mp4"), [(0, 0, 255)], repeat=60)
    media = tmp_path / "media"
    media.mkdir()
    w = window_factory(silent_vehicle)
    assert w.camera_view.message().startswith("No video: no camera configured")
    w.actionPreferences.trigger()
    qtbot.waitUntil(lambda: w.findChild(SettingsDialog) is not None and w.findChild(SettingsDialog).isVisible(),
                    timeout=3000)
    dialog = w.findChild(SettingsDialog)
    assert dialog.hudDefault.isChecked() and dialog.cameraUris.toPlainText() == ""
    dialog.cameraUris.setPlainText(f"{red}?loop=1\n")
    dialog.browseMediaFolder.click()
    chooser = dialog.folder_dialog
    qtbot.waitUntil(chooser.isVisible, timeout=3000)
    chooser.setDirectory(str(tmp_path))
    chooser.selectFile(str(media))
    chooser.accept()
    assert Path(dialog.mediaFolder.text()) == media
    dialog.hudDefault.setChecked(False)
    dialog.buttons.button(QDialogButtonBox.Ok).click()

    assert not w.camera_view.hud_visible() and not w.camera_panel.hud_button.isChecked()
    qtbot.waitUntil(lambda: w.camera_view.frame() is not None and nearest(painted_rgb(w.camera_view)) == (255, 0, 0),
                    timeout=10000)
    with qtbot.waitSignal(w.camera.snapshotSaved, timeout=3000) as saved:
        w.camera_panel.snapshot_button.click()
    assert Path(saved.args[0]).parent == media and Path(saved.args[0]).suffix == ".png"
    assert [p.name for p in media.iterdir()] == [Path(saved.args[0]).name]
    w.close()

    again = window_factory(silent_vehicle)
    assert (again.settings.camera_uris, again.settings.media_folder, again.settings.hud) == \
        ([f"{red}?loop=1"], str(media), False)
    assert again.camera.uris == [f"{red}?loop=1"] and again.camera.folder == str(media)
    assert not again.camera_view.hud_visible()
    again.close()

    override = window_factory(silent_vehicle, cameras=[f"{blue}?loop=1"])      # main.py --camera blue.mp4?loop=1
    assert override.camera.uris == [f"{blue}?loop=1"]
    qtbot.waitUntil(lambda: override.camera_view.frame() is not None
                    and nearest(painted_rgb(override.camera_view)) == (0, 0, 255), timeout=10000)


def test_camera_uris_may_be_comma_separated():
    assert split_uris(" sim, 0\nudp://0.0.0.0:5600,\n\nvideo.mp4?loop=1 ") == \
        ["sim", "0", "udp://0.0.0.0:5600", "video.mp4?loop=1"]


COLLECT_AFTER_PREFERENCES = """
import gc, socket, sys
from PyQt5.QtCore import QSettings
from PyQt5.QtWidgets import QApplication
app = QApplication([])
from driver.vehicle import Vehicle, VehicleConfig
from uavviewer.preferences.dialog import SettingsDialog
from uavviewer.main_window import MainWindow
with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
vehicle = Vehicle(VehicleConfig(connection=f"udpin:127.0.0.1:{port}")).start()
w = MainWindow(vehicle, qsettings=QSettings(sys.argv[1], QSettings.IniFormat))
w.show()
app.processEvents()
w.actionPreferences.trigger()
app.processEvents()
w.findChild(SettingsDialog).reject()       # its deletion is still pending when the window goes
w.quit_without_asking()
del w
gc.collect()                               # the window (in reference cycles) and its children are deleted here
for _ in range(10):
    app.processEvents()
vehicle.close()
print("collected")
"""


def test_a_window_collected_after_preferences_were_open_does_not_crash(tmp_path):
    """A slot on the dialog's ``destroyed`` once ran inside the collector on a half-deleted window: a
    segmentation fault at a random later moment (in CI, two tests later). A subprocess, so a crash fails
    only this test."""
    out = subprocess.run([sys.executable, "-X", "faulthandler", "-c", COLLECT_AFTER_PREFERENCES,
                          str(tmp_path / "settings.ini")], capture_output=True, text=True, timeout=60, cwd=ROOT,
                         env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert out.returncode == 0 and "collected" in out.stdout, out.stderr[-3000:]
