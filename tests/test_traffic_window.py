"""Issue 32, the viewer's traffic: ADS-B contacts from the simulated ArduCopter drawn on the map with callsign,
relative height and age, faded once stale; a head-on aircraft's closest approach said aloud and in the banner."""
from __future__ import annotations

import pytest
from PyQt5.QtGui import QColor

from uavviewer.alerts.model import AlertKind
from uavviewer.map.traffic_overlay import contact_label

from viewer_fixtures import app_style, viewer_settings, window, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def alerts_heard(vehicle, window) -> list:
    """The window's alerts from now on, once the vehicle knows where it is (traffic is judged from there)."""
    assert vehicle.wait_for(lambda s: s.position is not None and s.home is not None and s.readiness.prearm_ok, 30)
    alerts = []
    window.alerts.alerted.connect(alerts.append)
    return alerts


def test_contacts_on_the_map_and_a_head_on_one_alerted_in_the_banner_and_aloud(qtbot, sim, vehicle, window):
    alerts = alerts_heard(vehicle, window)
    ground = sim.autopilot.home_alt
    sim.autopilot.add_aircraft(4242, north=2500.0, east=0.0, alt=ground + 50.0, heading=180.0, speed=60.0)
    passing = sim.autopilot.add_aircraft(4343, north=-800.0, east=0.0, alt=ground + 50.0, heading=180.0, speed=60.0)
    overlay = window.map.traffic
    qtbot.waitUntil(lambda: {c.icao for _e, _n, c in overlay.marks()} >= {4242, 4343}, timeout=20000)
    head_on = next(c for _e, _n, c in overlay.marks() if c.icao == 4242)
    assert contact_label(head_on).startswith("SIM4242 +") and contact_label(head_on).endswith(" s")
    qtbot.waitUntil(lambda: any(a.kind is AlertKind.TRAFFIC for a in alerts), timeout=20000)
    said = [a.text for a in alerts if a.kind is AlertKind.TRAFFIC]
    assert said[0].startswith("Traffic SIM4242: ") and "metres above" in said[0], said
    assert all("4343" not in text for text in said)
    assert "Traffic SIM4242" in window.alert_banner.text
    sim.autopilot.aircraft.remove(passing)                      # no longer heard: faded on the map, then gone
    qtbot.waitUntil(lambda: any(c.icao == 4343 and c.stale for _e, _n, c in overlay.marks()), timeout=20000)


def test_a_contact_without_a_heading_is_a_round_mark_not_an_arrow_to_the_north(qtbot, sim, vehicle, window):
    from uavviewer.map.traffic_overlay import AIRCRAFT

    assert vehicle.wait_for(lambda s: s.position is not None and s.home is not None and s.readiness.prearm_ok, 30)
    ground = sim.autopilot.home_alt
    sim.autopilot.add_aircraft(4545, north=40.0, east=40.0, alt=ground + 400.0, heading=None, speed=0.0)
    overlay, view = window.map.traffic, window.map.traffic.view
    qtbot.waitUntil(lambda: any(c.icao == 4545 for _e, _n, c in overlay.marks()), timeout=20000)
    east, north, contact = next(m for m in overlay.marks() if m[2].icao == 4545)
    assert contact.heading_deg is None
    view.update()
    at = view.to_screen(east, north)
    qtbot.waitUntil(lambda: QColor(view.grab().toImage().pixel(int(at.x()), int(at.y()))) == AIRCRAFT,
                    timeout=5000)
    image = view.grab().toImage()
    # 6 px north of the contact: inside an arrow pointing north (a heading guessed as 0), outside the round mark
    north_of = QColor(image.pixel(int(at.x()), int(at.y()) - 6))
    assert max(abs(north_of.red() - AIRCRAFT.red()), abs(north_of.green() - AIRCRAFT.green()),
               abs(north_of.blue() - AIRCRAFT.blue())) > 60, north_of.name()
