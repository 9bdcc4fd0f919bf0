"""Setup's Summary says what the Failsafes page says: both read one model of the vehicle's failsafe parameters, so
the Summary never says "done" while the page lists no battery failsafe action, the GCS failsafe off and the fence
off (the simulated ArduCopter's defaults, as ArduPilot's: BATT_FS_*_ACT 0, FS_GCS_ENABLE 0, FENCE_ENABLE 0)."""
from __future__ import annotations

import pytest

from test_setup_window import bench_window, open_setup, read  # noqa: F401  (fixture)
from viewer_fixtures import app_style, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)


def why(page, area: str) -> str:
    item = next(page.lines.topLevelItem(i) for i in range(page.lines.topLevelItemCount())
                if page.lines.topLevelItem(i).text(0) == area)
    return item.text(2)


def test_the_summary_says_which_failsafes_are_set_as_the_failsafes_page_does(qtbot, bench_window):
    _sim, vehicle, w = bench_window()
    summary = open_setup(w, "Summary")                # Setup reads the parameters
    assert vehicle.wait_for(lambda s: read(s), 30)
    qtbot.waitUntil(lambda: summary.verdict("Failsafes") == "needs attention", timeout=10000)
    said = why(summary, "Failsafes")
    assert said.startswith("no battery failsafe action; GCS failsafe off; fence off; "), said
    assert "radio lost: returns home (RTL)" in said                  # and what is set
    page = w.setup.dialog.turn_to("Failsafes")
    qtbot.waitUntil(lambda: "No battery failsafe action" in page.warnings.text(), timeout=5000)

    for name, value in (("BATT_FS_LOW_ACT", 2), ("FS_GCS_ENABLE", 1), ("FENCE_ENABLE", 1)):
        assert vehicle.set_parameter(name, value).result(timeout=15).ok
    summary = w.setup.dialog.turn_to("Summary")
    qtbot.waitUntil(lambda: summary.verdict("Failsafes") == "done", timeout=10000)
    said = why(summary, "Failsafes")
    assert "battery low: returns home (RTL)" in said and "ground station lost: returns home (RTL)" in said, said
    assert "fence breached" in said and "no battery" not in said
