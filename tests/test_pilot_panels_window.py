"""In the window, on the simulated vehicle: the critical banner and the mute, the preflight dock, the home arrow."""
from __future__ import annotations

import math

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QMessageBox

from driver.vehicle.state import LinkStatus
from uavviewer.alerts.model import AlertKind
from lockstep_fixtures import lockstep_window  # noqa: F401  (fixtures)
from viewer_fixtures import viewer_settings, window, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def test_link_loss_is_spoken_and_bannered_until_it_recovers(qtbot, sim, vehicle_factory, window_factory):
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", loss_timeout=1.0)
    w = window_factory(v)
    spoken, raised = [], []
    w.alerts.speaker.spoken.connect(spoken.append)
    w.alerts.alerted.connect(lambda a: raised.append(a.kind))
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=10000)   # the alerts took it as their baseline
    assert w.alert_banner.isHidden()                     # connecting is said, not bannered
    sim.faults.link_down = True
    qtbot.waitUntil(lambda: AlertKind.LINK_LOST in raised, timeout=10000)
    assert w.alert_banner.isVisible() and "Link lost" in w.alert_banner.text
    qtbot.waitUntil(lambda: "Link lost" in spoken, timeout=3000)
    sim.faults.link_down = False
    qtbot.waitUntil(lambda: AlertKind.LINK_RECOVERED in raised, timeout=10000)
    qtbot.waitUntil(lambda: "Link recovered" in spoken, timeout=3000)
    qtbot.waitUntil(w.alert_banner.isHidden, timeout=3000)


def test_a_critical_autopilot_message_goes_to_the_banner_and_can_be_dismissed(qtbot, sim, window):
    w = window
    sim.faults.refuse_arm = "Compass not calibrated"
    qtbot.waitUntil(lambda: w.flightControls.arm_button.isEnabled(), timeout=15000)
    qtbot.mouseClick(w.flightControls.arm_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.flight.arm_box is not None and w.flight.arm_box.isVisible(), timeout=3000)  # Arm asks first
    qtbot.mouseClick(w.flight.arm_box.button(QMessageBox.Yes), Qt.LeftButton)
    qtbot.waitUntil(lambda: w.alert_banner.isVisible() and "Compass not calibrated" in w.alert_banner.text,
                    timeout=15000)
    banner_bottom = w.alert_banner.mapTo(w, w.alert_banner.rect().bottomLeft()).y()
    for essential in (w.attitude, w.leftStick, w.rightStick, w.flightControls.main_button,
                      w.flightControls.stop_button):          # a strip above them, covering none
        assert essential.mapTo(w, essential.rect().topLeft()).y() >= banner_bottom
    qtbot.mouseClick(w.alert_banner.close_button, Qt.LeftButton)
    assert w.alert_banner.isHidden()
    assert any("Compass not calibrated" in t for t in w.messages.texts())   # still in Messages


def test_mute_is_a_menu_toggle_kept_for_the_next_run(qtbot, window, viewer_settings):
    w = window
    assert w.actionMute in w.menuFile.actions() and not w.alerts.speaker.muted
    w.actionMute.trigger()
    assert w.alerts.speaker.muted and viewer_settings.value("alerts/muted", type=bool)
    said = []
    w.alerts.speaker.spoken.connect(said.append)
    snapshots = []
    w.adapter.stateChanged.connect(snapshots.append)     # after the alerts' own slot: each has been judged
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=10000)
    seen = len(snapshots)
    qtbot.waitUntil(lambda: len(snapshots) >= seen + 5, timeout=10000)   # snapshots go by: nothing may be said
    assert said == []


def test_preflight_dock_turns_from_no_go_to_go_with_reasons(lockstep_window):
    """In lockstep: the window is up before the vehicle's 4 s of start-up are over, however slow it is to build
    (over a socket at 4x, a loaded machine built it after the EKF was already GO)."""
    steps = lockstep_window(ready_after=4.0)
    w = steps.window
    panel = w.preflight_panel
    assert w.preflightDock.windowTitle() == "Preflight"
    steps.until(lambda: panel.verdict_of("Link") == "GO", 2, "the link GO")
    assert panel.verdict_of("EKF") == "NO GO" and steps.autopilot.t < 4.0
    assert panel.headline.text() == "NO GO"
    steps.until(lambda: panel.verdict_of("EKF") == "GO" and panel.verdict_of("GPS") == "GO"
                and panel.verdict_of("Pre-arm") == "GO", 30, "EKF, GPS and pre-arm GO")
    steps.until(lambda: panel.verdict_of("GCS failsafe") == "CAUTION", 15, "the GCS failsafe's caution")   # FS_GCS_ENABLE 0
    assert "FS_GCS_ENABLE 0" in panel.reason_of("GCS failsafe")
    assert "satellites" in panel.reason_of("GPS")
    assert panel.headline.text() != "NO GO"


def test_home_arrow_points_home_from_the_nose(qtbot, sim, vehicle_factory, window_factory):
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", loss_timeout=1.0)
    assert v.wait_for(lambda s: s.connected, 10) and v.takeoff(3.0).result(timeout=60).ok
    w = window_factory(v)
    arrow = w.home_arrow
    assert arrow.parentWidget() is w.attitude and arrow.isVisible()
    assert w.adapter.send(w.adapter.drone.go_to, 12.0, 0.0, 3.0) is not None       # 12 m north, nose to the north
    qtbot.waitUntil(lambda: math.hypot(sim.truth().north - 12.0, sim.truth().east) < 0.5, timeout=30000)
    qtbot.waitUntil(lambda: arrow.text == "home 12 m", timeout=5000)
    nose = math.degrees(sim.truth().yaw)
    expected = (180.0 - nose + 180.0) % 360.0 - 180.0                   # home is due south
    assert abs((arrow.relative - expected + 180.0) % 360.0 - 180.0) < 5.0
    sim.faults.link_down = True
    qtbot.waitUntil(lambda: w.adapter.state.link.status is LinkStatus.LOST, timeout=15000)
    qtbot.waitUntil(lambda: arrow.stale, timeout=3000)                   # greyed: the last known, not live
