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
