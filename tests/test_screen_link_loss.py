"""Issue 21, problem 6: on link loss every live value shows it is stale (greyed, with its age) on the video HUD,
in Telemetry and in the status strip, and the phase says "link lost" rather than "Flying · GUIDED".

Real simulator (its link cut by fault injection), real driver, real window.
"""
from __future__ import annotations

import pytest

from driver.vehicle.state import LinkStatus
from uavviewer.telemetry.status_strip import DIM as STRIP_DIM
from uavviewer.telemetry.panel import DIM
from uavviewer.camera.hud import STALE_COLOUR, hud_colour, stale_text

from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def test_a_lost_link_greys_every_live_value_and_says_its_age(qtbot, sim, vehicle_factory, window_factory):
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", loss_timeout=1.0)
    assert v.takeoff(3.0).result(timeout=60).ok
    w = window_factory(v)
    qtbot.waitUntil(lambda: w.phaseLabel.text().startswith("Flying"), timeout=10000)
    assert not stale_text(v.state())
    sim.faults.link_down = True
    qtbot.waitUntil(lambda: v.state().link.status is LinkStatus.LOST, timeout=10000)
    qtbot.waitUntil(lambda: w.phaseLabel.text().startswith("Link lost"), timeout=5000)
    assert "last heard flying in GUIDED" in w.phaseLabel.text()
    s = w.adapter.state
    assert stale_text(s).startswith("LINK LOST · values") and hud_colour(s) == STALE_COLOUR      # the video HUD
    for key in ("altitude", "ground_speed", "climb", "home", "battery", "mode"):
        assert w.telemetry.color(key) == DIM, key
    qtbot.waitUntil(lambda: w.telemetry.stale_label.isVisible() and "s old" in w.telemetry.stale_label.text(),
                    timeout=3000)
    strip = w.statusStrip
    qtbot.waitUntil(lambda: "s old" in strip.battery.text(), timeout=3000)
    assert strip.colour(strip.battery) == STRIP_DIM and strip.link.text().startswith("LINK LOST")
    sim.faults.link_down = False
    qtbot.waitUntil(lambda: w.phaseLabel.text().startswith("Flying"), timeout=10000)
    assert not w.telemetry.stale_label.isVisible()
