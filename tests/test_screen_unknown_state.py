"""What is not known is said to be unknown: after leaving a vehicle in the air (File › Disconnect, "Leave it
flying") the window holds no vehicle, and the HUD must not say DISARMED of one that may well still fly."""
from __future__ import annotations

import pytest
from PyQt5.QtCore import QRectF
from PyQt5.QtGui import QColor, QImage, QPainter

from uavviewer.camera.hud import paint_hud

from test_connect_window import connecting  # noqa: F401  (fixture)
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


class TextsPainted(QPainter):
    """A painter that keeps every text the HUD draws."""

    def __init__(self, device) -> None:
        super().__init__(device)
        self.texts: list[str] = []

    def drawText(self, *args) -> None:  # noqa: N802 (Qt's name)
        self.texts.append(args[-1])
        super().drawText(*args)


def hud_texts(state) -> list[str]:
    img = QImage(448, 336, QImage.Format_RGB888)
    img.fill(QColor(0, 0, 0))
    p = TextsPainted(img)
    paint_hud(p, QRectF(0, 0, 448, 336), state)
    p.end()
    return p.texts


def test_after_leaving_an_airborne_vehicle_the_hud_says_its_arming_is_unknown(qtbot, sim, flying, connecting):
    w = connecting(flying)
    qtbot.waitUntil(lambda: w.adapter.state.flying and w.adapter.state.connected, timeout=10000)
    assert {"GUIDED", "ARMED"} <= set(hud_texts(w.adapter.state))
    w.actionDisconnect.trigger()
    qtbot.waitUntil(lambda: w.tools.leave_box is not None and w.tools.leave_box.isVisible(), timeout=3000)
    next(b for b in w.tools.leave_box.buttons() if b.text() == "Leave it flying").click()
    qtbot.waitUntil(lambda: w.adapter.description == "Not connected", timeout=5000)
    assert sim.truth().armed                             # it still flies...
    texts = hud_texts(w.adapter.state)
    assert "Not connected" in texts and "ARMING UNKNOWN" in texts    # ...and the HUD does not say otherwise
    assert "DISARMED" not in texts and "ARMED" not in texts
