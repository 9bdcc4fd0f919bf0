"""ADS-B traffic says one thing: the banner (and the voice) and Messages give the same aircraft's threat in the
same words, from the driver's one text (driver.traffic ``Contact.threat``), its height at the closest approach as
its distance is; and a contact's label on the map moves clear of the range rings' labels and of other contacts'."""
from __future__ import annotations

import pytest
from PyQt5.QtCore import QPointF
from PyQt5.QtGui import QFont, QImage, QPainter

from uavviewer.alerts.model import AlertKind
from uavviewer.map.geometry import nice_scale
from uavviewer.map.labels import Labels
from uavviewer.map.traffic_overlay import LABEL_SPOTS, contact_label

from test_traffic_window import alerts_heard
from viewer_fixtures import app_style, viewer_settings, window, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def test_the_banner_and_messages_say_the_same_threat(qtbot, sim, vehicle, window):
    alerts = alerts_heard(vehicle, window)
    ground = sim.autopilot.home_alt
    # head on from the north, 170 m below and climbing: its height now is not its height when closest
    sim.autopilot.add_aircraft(4646, north=2500.0, east=30.0, alt=ground - 170.0, heading=180.0, speed=60.0,
                               climb=1.5)
    qtbot.waitUntil(lambda: any(a.kind is AlertKind.TRAFFIC for a in alerts), timeout=20000)
    said = next(a.text for a in alerts if a.kind is AlertKind.TRAFFIC)
    assert said.startswith("Traffic SIM4646: ") and "metres below, closest " in said, said
    lines = [m.text for m in window.adapter.state.messages if m.text.startswith("Traffic SIM4646")]
    assert lines == [said]                                   # Messages: the same words, once
    assert window.alert_banner.text.endswith(said) or said in window.alert_banner.text


def test_a_contacts_label_moves_clear_of_the_rings_labels(qtbot, sim, vehicle, window):
    assert vehicle.wait_for(lambda s: s.position is not None and s.home is not None, 30)
    view = window.map.traffic.view
    qtbot.waitUntil(lambda: view.frame is not None, timeout=10000)
    view.set_follow(False)
    view.centre = (0.0, 0.0)
    step = nice_scale(view.mpp, min(view.width(), view.height()) / 5.0)
    ground = sim.autopilot.home_alt
    for k, icao in ((1, 4701), (2, 4702)):                   # each right where a ring writes its distance
        sim.autopilot.add_aircraft(icao, north=k * step, east=0.0, alt=ground + 80.0, heading=None, speed=0.0)
    qtbot.waitUntil(lambda: {c.icao for _e, _n, c in window.map.traffic.marks()} >= {4701, 4702}, timeout=20000)
    view.repaint()
    texts = {contact_label(c) for _e, _n, c in window.map.traffic.marks()}
    traffic = [(box, text) for box, text in view.labels.boxes if text in texts]
    assert len(traffic) == 2
    others = [box for box, text in view.labels.boxes if text not in texts]
    assert others                                            # the rings' distances, the scale, N
    for box, text in traffic:
        assert not any(box.intersects(o) for o in others), text
    assert not traffic[0][0].intersects(traffic[1][0])


def test_labels_take_the_first_free_place(qapp):
    img = QImage(200, 100, QImage.Format_RGB888)
    p = QPainter(img)
    p.setFont(QFont("DejaVu Sans", 8))
    labels = Labels()
    ring = labels.draw(p, QPointF(53, 47), "100 m")
    first = labels.place(p, QPointF(50, 50), "SIM1 +80 m 1 s", LABEL_SPOTS)    # upper right is taken
    second = labels.place(p, QPointF(50, 50), "SIM2 +80 m 1 s", LABEL_SPOTS)
    p.end()
    assert not first.intersects(ring) and not second.intersects(ring) and not second.intersects(first)
