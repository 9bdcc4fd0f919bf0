"""Vehicle › Setup over a remote drone (Ice): the server offers no calibrations, motor test, radio channels nor
banner, so every page says why not, and no control on any page raises or hangs (its parameters still work)."""
from __future__ import annotations

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QApplication, QCheckBox, QPushButton

from ice_fixtures import drone_factory, server_factory  # noqa: F401  (fixtures)
from uavviewer.setup.controller import NO_SETUP
from viewer_fixtures import app_style, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)

#: Each page's own words for what it cannot do here ("" : the notice above the pages says it for that page)
PAGE_REASON = {
    "Summary": lambda p: p.firmware.text(),
    "Sensors": lambda p: p.notes.text(),
    "Radio": lambda p: p.status.text(),
    "Flight modes": lambda p: p.channel.text(),
    "Motors": lambda p: p.reason.text(),
}


def test_every_setup_page_of_a_remote_drone_says_why_and_no_control_raises(qtbot, vehicle, server_factory,
                                                                          drone_factory, window_factory):
    drone = drone_factory(server_factory(vehicle))
    w = window_factory(drone)
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=15000)
    dialog = w.setup.open()
    assert set(dialog.pages) == {"Summary", "Frame", "Sensors", "Radio", "Flight modes", "Power", "Failsafes",
                                 "Motors"}
    for title, page in dialog.pages.items():
        dialog.turn_to(title)
        qtbot.waitUntil(lambda: dialog.notice.isVisible() and NO_SETUP in dialog.notice.text(), timeout=5000)
        if title in PAGE_REASON:
            qtbot.waitUntil(lambda p=page, t=title: NO_SETUP in PAGE_REASON[t](p), timeout=5000)
        for box in page.findChildren(QCheckBox):
            box.setChecked(not box.isChecked())
            box.setChecked(not box.isChecked())
        for button in page.findChildren(QPushButton):             # enabled or not: none may raise or block
            qtbot.mouseClick(button, Qt.LeftButton)
            QApplication.processEvents()
        for window in QApplication.topLevelWidgets():              # what a button opened (the Parameters review)
            if window.isVisible() and window is not w and window is not dialog:
                window.close()
    summary = dialog.pages["Summary"]
    assert summary.verdict("Radio") == summary.verdict("Motors") == "not applicable"
    assert "board: not reported on this link" in summary.firmware.text()
    motors = dialog.pages["Motors"]
    motors.props_off.setChecked(True)
    assert not motors.test.isEnabled() and motors.reason.text().startswith("No motor test on this connection")
    sensors = dialog.pages["Sensors"]
    assert not any(b.isEnabled() for b in (sensors.gyro, sensors.baro, sensors.level, sensors.accel_start,
                                           sensors.compass_start))
    sensors.gyro.clicked.emit(False)                           # a calibration asked anyway: answered why not
    assert sensors.result.text() == f"gyro: rejected ({NO_SETUP})"
