"""The console's param verbs (MAVProxy's) on the real driver and the simulated vehicle."""
from __future__ import annotations

import io

from driver.console.console import Console, run_commands

from ice_fixtures import eventually


def test_fetch_show_set_save_diff_and_load(vehicle, sim, tmp_path):
    out = io.StringIO()
    console = Console(vehicle, stdout=out)
    console.onecmd("param fetch")
    assert eventually(lambda: "parameters: accepted" in out.getvalue(), 30), out.getvalue()
    console.onecmd("param show fs_gcs*")
    assert "FS_GCS_ENABLE    0  (Disabled/NoAction)" in out.getvalue(), out.getvalue()
    console.onecmd("param help RTL_ALT")
    assert "RTL_ALT: RTL Altitude" in out.getvalue() and "range 200 to 300000 cm" in out.getvalue()
    saved = tmp_path / "solo.param"
    console.onecmd(f"param save {saved}")
    assert "saved 1392 parameters" in out.getvalue()
    console.onecmd("param set RTL_ALT 1e9")
    assert eventually(lambda: "param RTL_ALT: rejected (RTL_ALT = 1e+09 is outside 200 to 300000 cm" in out.getvalue(),
                      10), out.getvalue()
    console.onecmd("param set RTL_ALT 2500")
    console.onecmd("param set FS_GCS_ENABLE 1")
    assert eventually(lambda: "param RTL_ALT=2500: accepted" in out.getvalue()
                      and "param FS_GCS_ENABLE=1: accepted" in out.getvalue(), 10), out.getvalue()
    assert sim.autopilot.params["RTL_ALT"] == 2500
    console.onecmd(f"param diff {saved}")
    text = out.getvalue()
    assert "FS_GCS_ENABLE               0            1" in text and "RTL_ALT                  1500         2500" in text
    assert "2 differences" in text
    console.onecmd(f"param load {saved} RTL*")                  # only what the pattern names goes back
    assert eventually(lambda: "param RTL_ALT=1500: accepted" in out.getvalue(), 10), out.getvalue()
    assert "1 of" in out.getvalue() and sim.autopilot.params["RTL_ALT"] == 1500
    assert sim.autopilot.params["FS_GCS_ENABLE"] == 1
    console.onecmd("param set BATT_MONITOR 3")
    assert "BATT_MONITOR takes effect after a reboot" in out.getvalue()
    console.onecmd("param frobnicate")
    console.onecmd(f"param diff {tmp_path / 'missing.param'}")
    assert "usage: param fetch" in out.getvalue() and "cannot read" in out.getvalue()


def test_save_diff_and_show_at_connect_read_the_whole_list_first(vehicle, sim, tmp_path):
    """``--cmd "param save FILE; param diff FILE; param show RTL_ALT"`` right after connecting: nothing is known
    yet, so each reads the list first (saying how far it is) and then acts on all 1,392 parameters."""
    out = io.StringIO()
    console = Console(vehicle, stdout=out)
    saved, mine = tmp_path / "at-connect.param", tmp_path / "mine.param"
    mine.write_text("RTL_ALT 2500\nFS_GCS_ENABLE 0\n")
    run_commands(console, f"param save {saved}; param diff {mine}; param show RTL_ALT")
    assert eventually(lambda: all(w in out.getvalue() for w in ("RTL_ALT          1500", "differences", "saved ")),
                      60), out.getvalue()
    text = out.getvalue()
    assert "param save: reading the vehicle's parameters first" in text
    assert f"saved {len(sim.autopilot.params)} parameters" in text and "saved 0 parameters" not in text
    assert len([line for line in saved.read_text().splitlines() if line.strip()]) == len(sim.autopilot.params)
    assert "RTL_ALT                  2500         1500" in text and "1 differences" in text
