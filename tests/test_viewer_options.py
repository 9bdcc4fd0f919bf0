"""main.py's options: the remembered connection, and a takeoff altitude from the command line
that is checked and kept for that run only."""
from __future__ import annotations

import pytest

import main
from uavviewer.settings import TAKEOFF_ALTITUDE_RANGE

from test_viewer_window import silent_vehicle  # noqa: F401  (fixture)
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)


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

    from uavviewer.dialogs import SettingsDialog
    from uavviewer.settings import load_settings
    w = window_factory(silent_vehicle, takeoff_altitude=25.0)
    w.edit_settings()
    dialog = w.findChild(SettingsDialog)
    assert dialog.takeoffAltitude.value() == 25.0                 # what is in force is what is shown
    dialog.maxHorizontal.setValue(3.0)
    dialog.buttons.button(QDialogButtonBox.Ok).click()
    assert w.takeoff_altitude == 25.0
    saved = load_settings(viewer_settings)
    assert saved.takeoff_altitude == 3.0 and saved.max_horizontal == 3.0
    w.edit_settings()                                             # now the pilot does choose an altitude
    dialog = w.findChild(SettingsDialog)
    dialog.takeoffAltitude.setValue(7.0)
    dialog.buttons.button(QDialogButtonBox.Ok).click()
    assert w.takeoff_altitude == 7.0 and load_settings(viewer_settings).takeoff_altitude == 7.0
