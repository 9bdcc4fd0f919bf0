"""main.py's options: the remembered connection, and a takeoff altitude from the command line
that is checked and kept for that run only."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from PyQt5.QtCore import Qt

from uavviewer import app as main
from uavviewer.settings import TAKEOFF_ALTITUDE_RANGE

from test_viewer_window import silent_vehicle  # noqa: F401  (fixture)
from viewer_fixtures import viewer_settings, window, window_factory  # noqa: F401  (fixtures)

ROOT = Path(__file__).resolve().parent.parent


def test_no_vehicle_option_uses_the_last_connection():
    parse = main.build_parser().parse_args
    assert main.choose_connection(parse([]), "tcp:10.0.0.7:5760") == "tcp:10.0.0.7:5760"
    assert main.choose_connection(parse([]), "") == main.SOLO_CONNECTION
    assert main.choose_connection(parse(["--connect", "udpin:0.0.0.0:14551"]), "tcp:10.0.0.7:5760") == \
        "udpin:0.0.0.0:14551"
    assert "last connection" in main.build_parser().format_help()


@pytest.mark.parametrize("value", ["-5", "0", "0.5", "51", "nan", "inf", "high"])
def test_takeoff_altitude_out_of_range_is_refused(value, capsys):
    with pytest.raises(SystemExit):
        main.build_parser().parse_args(["--takeoff-altitude", value])
    low, high = TAKEOFF_ALTITUDE_RANGE
    assert f"{low:g}" in capsys.readouterr().err


def test_takeoff_altitude_from_the_command_line_is_not_saved(qtbot, silent_vehicle, window_factory):
    assert main.build_parser().parse_args(["--takeoff-altitude", "12"]).takeoff_altitude == 12.0
    w = window_factory(silent_vehicle, takeoff_altitude=12.0)        # main.py --takeoff-altitude 12
    assert w.takeoff_altitude == 12.0
    w.close()
    again = window_factory(silent_vehicle)
    assert again.takeoff_altitude == again.settings.takeoff_altitude == 3.0


def test_preferences_left_alone_do_not_save_the_command_line_altitude(qtbot, silent_vehicle, viewer_settings,
                                                                       window_factory):
    from PyQt5.QtWidgets import QDialogButtonBox

    from uavviewer.preferences.dialog import SettingsDialog
    from uavviewer.settings import load_settings
    w = window_factory(silent_vehicle, takeoff_altitude=25.0)
    w.preferences.edit()
    dialog = w.findChild(SettingsDialog)
    assert dialog.takeoffAltitude.value() == 25.0                 # what is in force is what is shown
    dialog.maxHorizontal.setValue(3.0)
    dialog.buttons.button(QDialogButtonBox.Ok).click()
    assert w.takeoff_altitude == 25.0
    saved = load_settings(viewer_settings)
    assert saved.takeoff_altitude == 3.0 and saved.max_horizontal == 3.0
    w.preferences.edit()                                             # now the pilot does choose an altitude
    dialog = w.findChild(SettingsDialog)
    dialog.takeoffAltitude.setValue(7.0)
    dialog.buttons.button(QDialogButtonBox.Ok).click()
    assert w.takeoff_altitude == 7.0 and load_settings(viewer_settings).takeoff_altitude == 7.0


@pytest.mark.parametrize("argv,words", [
    (["--connect", "foo:bar"], "not a connection string"),
    (["--connect", "tcp:127.0.0.1"], "needs HOST:PORT"),
    (["--connect", "udpin:0.0.0.0:99999"], "1 to 65535"),
    (["--connect", "/nope/flight.tlog"], "no such flight log"),
    (["--sim", "--speedup", "0"], "positive"),
    (["--sim", "--speedup", "-1"], "positive"),
    (["--sim", "--ready-after", "nan"], "zero or a positive"),
])
def test_bad_options_are_refused_in_one_line(argv, words, capsys):
    with pytest.raises(SystemExit) as exit_:
        main.build_parser().parse_args(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err


def test_a_remembered_connection_that_is_no_longer_one_falls_back_to_the_solo():
    assert main.choose_connection(main.build_parser().parse_args([]), "foo:bar") == main.SOLO_CONNECTION


def test_an_unwritable_log_folder_is_an_error_not_a_traceback(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    out = subprocess.run([sys.executable, str(ROOT / "main.py"), "--sim", "--log-dir", str(blocker / "logs")],
                         capture_output=True, text=True, timeout=60, cwd=ROOT)
    assert out.returncode == 2 and "--log-dir" in out.stderr and "Traceback" not in out.stderr


def test_the_connection_is_remembered_only_once_a_vehicle_answers(qtbot, sim, vehicle_factory, silent_vehicle,
                                                                   viewer_settings, window_factory):
    from uavviewer.connect.choice import Choice, Kind
    from uavviewer.settings import load_settings
    w = window_factory(silent_vehicle)
    w.connections.adopt(silent_vehicle, Choice(Kind.MAVLINK, "udpin:127.0.0.1:1"))   # nobody answers there
    qtbot.waitUntil(lambda: w.linkBanner.isVisible(), timeout=3000)
    w.quit_without_asking()
    assert load_settings(viewer_settings).last_connection == ""
    url = f"tcp:127.0.0.1:{sim.tcp_port}"
    v = vehicle_factory(url)
    w = window_factory(v)
    w.connections.adopt(v, Choice(Kind.MAVLINK, url))                # as app.py does with the command line's
    qtbot.waitUntil(lambda: load_settings(viewer_settings).last_connection == url, timeout=10000)


def test_closing_in_flight_asks_and_land_lands(qtbot, sim, flying, window):
    w = window
    qtbot.waitUntil(lambda: w.flightControls.main_button.text() == "Land", timeout=20000)
    sent: list[str] = []
    w.adapter.commandSent.connect(sent.append)
    w.close()
    qtbot.waitUntil(lambda: w.closing.quit_box is not None and w.closing.quit_box.isVisible(), timeout=3000)
    assert w.isVisible()                                     # still there: nobody would command the vehicle
    qtbot.mouseClick(next(b for b in w.closing.quit_box.buttons() if b.text() == "Land"), Qt.LeftButton)
    assert sent == ["land"] and w.isVisible()
    qtbot.waitUntil(lambda: not sim.truth().armed, timeout=40000)
    w.close()                                                # on the ground: closes without a question
    assert not w.isVisible() and w.closing.quit_box is None


def test_sigterm_closes_the_app_cleanly(tmp_path):
    """kill on `main.py --sim`: the window closes through its own close path and the process exits 0."""
    env = dict(os.environ, XDG_CONFIG_HOME=str(tmp_path / "config"), QT_QPA_PLATFORM="offscreen")
    proc = subprocess.Popen([sys.executable, "-u", str(ROOT / "main.py"), "--sim", "--no-log", "-v"], cwd=ROOT,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        for line in proc.stdout:                             # the driver says when the vehicle is there
            if "connected on tcp:" in line:
                break
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=30)
    finally:
        proc.kill()
    assert proc.returncode == 0, out
    assert "Traceback" not in out
    assert (tmp_path / "config" / "JdeRobot" / "UavViewerPy.conf").is_file()     # closeEvent saved the settings
