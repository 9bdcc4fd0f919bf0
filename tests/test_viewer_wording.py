"""The window's words (issue 29, items 19-21) in the real window on the real driver and simulated vehicle: one
wording for Disconnect, one log line per gesture, repeated lines counted, and the small things."""
from __future__ import annotations

import pytest
from PyQt5.QtCore import QPoint, QPointF, Qt
from PyQt5.QtGui import QWheelEvent
from PyQt5.QtWidgets import QApplication

from driver.state import LinkStatus, Severity

from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)


def test_disconnect_is_said_one_way(qtbot, vehicle, window_factory):
    w = window_factory(vehicle)
    w.connections.adopt(vehicle)
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=10000)
    w.actionDisconnect.trigger()
    qtbot.waitUntil(lambda: w.adapter.drone is not vehicle, timeout=5000)
    qtbot.waitUntil(lambda: w.statusStrip.link.text() == "Not connected", timeout=5000)
    qtbot.waitUntil(lambda: w.attitude.values["flag"] == "NOT CONNECTED", timeout=5000)
    shown = {"banner": w.linkBanner.text(), "phase": w.phaseLabel.text(), "strip": w.statusStrip.link.text(),
             "flag": w.attitude.values["flag"], "title": w.window_name(), "status bar": w.link_status.text(),
             "heartbeat": w.telemetry.text("heartbeat"), "sticks": w.leftStick._hint}
    for where, text in shown.items():
        assert "not connected" in text.lower(), (where, text)
        for other in ("no vehicle", "link lost", "link closed", "no link", "disconnected"):
            assert other not in text.lower(), (where, text)
    w.connections.close()
