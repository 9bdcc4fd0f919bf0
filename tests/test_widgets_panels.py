"""Telemetry colours, link banner text, message colours, button labels, mode selector, plots, replay bar."""
from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
import pytest
from PyQt5.QtCore import Qt

from driver.vehicle.state import (Battery, BatteryAlarm, CommandResult, CommandStatus, Gps, LandedState, LinkHealth, LinkStatus,
                          SequencePhase, SequenceProgress, Severity, VehicleState)
from uavviewer.flight.phase import FlightPhase, flight_phase, stick_hint
from uavviewer.flight.controls import FlightControls
from uavviewer.connect.link_banner import LinkBanner
from uavviewer.widgets.messages_view import MessagesView, severity_color
from uavviewer.flight.mode_selector import ModeSelector
from uavviewer.widgets.plots_panel import MIN_SPAN, PlotsPanel
from uavviewer.replay.bar import ReplayBar
from uavviewer.telemetry.panel import BAD, DIM, GOOD, WARN, TelemetryPanel

OK_LINK = LinkHealth(status=LinkStatus.OK, address="tcp:x", heartbeat_age=0.3, packets_per_s=42.0)


def make(widget_cls, qtbot):
    w = widget_cls()
    qtbot.addWidget(w)
    return w


def battery_from_autopilot(voltage, remaining) -> Battery:
    """A 4S pack as the driver reads it from SYS_STATUS: "low" is the driver's rule, the panel only shows it."""
    from collections import ChainMap
    from pymavlink.dialects.v20 import ardupilotmega as mavlink
    from driver.vehicle import telemetry
    msg = mavlink.MAVLink(None).sys_status_encode(
        0, 0, 0, 0, 65535 if voltage is None else int(voltage * 1000), -1, -1 if remaining is None else int(remaining),
        0, 0, 0, 0, 0, 0)
    base = VehicleState(battery=Battery(cells=4, cells_source="configured"))
    return telemetry.fold(ChainMap({}, base.__dict__), msg)["battery"]


@pytest.mark.parametrize("voltage,remaining,low", [
    (16.4, 90.0, False), (16.4, 19.0, True), (14.6, 60.0, True), (15.6, None, False), (14.9, None, True),
    (None, 15.0, True)])
def test_battery_warning_colour(qtbot, voltage, remaining, low):
    t = make(TelemetryPanel, qtbot)
    battery = battery_from_autopilot(voltage, remaining)
    assert battery.low is low
    t.set_state(VehicleState(link=OK_LINK, mode="GUIDED", battery=battery))
    colours = {BatteryAlarm.OK: GOOD, BatteryAlarm.WARNING: WARN, BatteryAlarm.CRITICAL: BAD}
    assert t.color("battery") == colours[battery.alarm]      # our thresholds, not the vehicle's "low"
    if voltage is not None:
        assert f"{voltage:.2f} V" in t.text("battery")


def test_telemetry_values(qtbot):
    t = make(TelemetryPanel, qtbot)
    t.set_state(VehicleState(link=OK_LINK, mode="LOITER", armed=True, landed_state=LandedState.IN_AIR,
                             altitude=12.345, heading_deg=271.4, gps=Gps(fix_type=3, satellites=11)))
    assert t.text("mode") == "LOITER"
    assert t.text("armed") == "ARMED"
    assert t.text("landed") == "in air"
    assert t.text("altitude") == "12.35 m"
    assert t.text("heading") == "271°"
    assert t.text("gps") == "3D fix, 11 sats" and t.color("gps") == GOOD
    assert t.text("packets") == "42"
    assert t.text("heartbeat") == "0.3 s ago"
    t.set_state(VehicleState(link=OK_LINK, mode="STABILIZE", gps=Gps(fix_type=1, satellites=3)))
    assert t.color("gps") == BAD


def test_telemetry_before_the_first_heartbeat_is_unknown(qtbot):
    t = make(TelemetryPanel, qtbot)
    t.set_state(VehicleState(link=LinkHealth(status=LinkStatus.WAITING, address="udpin:x")))
    for key in ("mode", "armed", "battery", "gps", "altitude", "heading", "loss"):
        assert t.text(key) == "--" and t.color(key) == DIM, key


def test_telemetry_with_the_link_lost_is_stale(qtbot):
    t = make(TelemetryPanel, qtbot)
    flying = VehicleState(link=OK_LINK, mode="GUIDED", armed=True, altitude=5.0, gps=Gps(fix_type=3, satellites=9),
                          battery=Battery(voltage=16.0, remaining=80.0))
    t.set_state(flying)
    assert t.color("gps") == GOOD and t.color("armed") != DIM
    lost = LinkHealth(status=LinkStatus.LOST, address="tcp:x", heartbeat_age=4.2, packets_per_s=40.0)
    t.set_state(replace(flying, link=lost))
    for key in ("mode", "armed", "battery", "gps", "altitude"):
        assert t.color(key) == DIM, key
    assert t.text("altitude") == "5.00 m"                 # the last known value, dimmed
    assert (t.text("packets"), t.color("packets")) == ("0", BAD)
    assert t.text("loss") == "link lost" and t.color("loss") == BAD
    assert t.text("heartbeat") == "4.2 s ago" and t.color("heartbeat") == BAD
    t.set_state(flying)
    assert t.color("gps") == GOOD and t.text("packets") == "42"


def test_link_banner_text(qtbot):
    b = make(LinkBanner, qtbot)
    b.set_link(LinkStatus.WAITING, "udpin:0.0.0.0:14550", None)
    assert not b.isHidden() and b.text() == "No vehicle yet — listening on UDP 0.0.0.0:14550…"
    b.set_link(LinkStatus.WAITING, "tcp:127.0.0.1:5760", None)            # an outgoing link never listens
    assert b.text() == "No vehicle yet — connecting to 127.0.0.1:5760…"
    b.set_link(LinkStatus.LOST, "udpin:0.0.0.0:14550", 7.4)
    assert not b.isHidden() and b.text().startswith("Link lost") and "7 s" in b.text()
    assert b.property("kind") == "lost"
    b.set_link(LinkStatus.OK, "udpin:0.0.0.0:14550", 0.2)
    assert b.isHidden()


def test_messages_colours_and_results(qtbot):
    m = make(MessagesView, qtbot)
    m.add_message(time.time(), Severity.CRITICAL, "PreArm: Compass not calibrated")
    m.add_message(time.time(), Severity.INFO, "EKF2 IMU0 is using GPS")
    m.add_result(CommandResult("arm", CommandStatus.REFUSED, "PreArm: Compass not calibrated", 1, 3))
    assert m.texts()[-1] == "arm: refused (PreArm: Compass not calibrated)"
    assert m.severities() == [Severity.CRITICAL, Severity.INFO, Severity.ERROR]
    item = m.topLevelItem(0)
    assert item.foreground(2).color().name() == severity_color(Severity.CRITICAL)
    assert severity_color(Severity.CRITICAL) != severity_color(Severity.INFO)


def test_messages_keep_a_limit(qtbot):
    m = MessagesView(limit=5)
    qtbot.addWidget(m)
    for i in range(8):
        m.add_message(time.time(), Severity.INFO, f"line {i}")
    assert m.texts() == [f"line {i}" for i in range(3, 8)]


def state(**kw) -> VehicleState:
    return VehicleState(link=OK_LINK, **kw)


@pytest.mark.parametrize("s,phase,label", [
    (VehicleState(), FlightPhase.NO_VEHICLE, "Take off"),
    (state(mode="STABILIZE", landed_state=LandedState.ON_GROUND), FlightPhase.ON_GROUND, "Take off"),
    (state(mode="GUIDED", armed=True, landed_state=LandedState.TAKEOFF, altitude=1.0,
           takeoff=SequenceProgress(SequencePhase.CLIMBING, "", 3.0)), FlightPhase.TAKING_OFF, "Land"),
    (state(mode="GUIDED", armed=True, landed_state=LandedState.IN_AIR, altitude=3.0), FlightPhase.FLYING, "Land"),
    (state(mode="LAND", armed=True, landed_state=LandedState.LANDING, altitude=2.0), FlightPhase.LANDING,
     "Landing…"),
])
def test_main_button_follows_vehicle(qtbot, s, phase, label):
    fc = make(FlightControls, qtbot)
    assert flight_phase(s) is phase
    fc.set_vehicle(phase, s.armed, s.connected, 0.4 if phase is FlightPhase.TAKING_OFF else None)
    assert fc.main_button.text() == label
    assert fc.stop_button.isEnabled() == phase.airborne
    assert fc.main_button.isEnabled() == (phase in (FlightPhase.ON_GROUND, FlightPhase.TAKING_OFF,
                                                    FlightPhase.FLYING))
    assert fc.progress.isVisibleTo(fc) == (phase is FlightPhase.TAKING_OFF)


def test_main_button_emits_intent(qtbot):
    fc = make(FlightControls, qtbot)
    fc.set_vehicle(FlightPhase.ON_GROUND, False, True)
    with qtbot.waitSignal(fc.takeoffRequested, timeout=1000):
        qtbot.mouseClick(fc.main_button, Qt.LeftButton)
    fc.set_vehicle(FlightPhase.FLYING, True, True)
    with qtbot.waitSignal(fc.landRequested, timeout=1000):
        qtbot.mouseClick(fc.main_button, Qt.LeftButton)
    with qtbot.waitSignal(fc.stopRequested, timeout=1000):
        qtbot.mouseClick(fc.stop_button, Qt.LeftButton)


def test_stick_hint():
    assert stick_hint(state(mode="STABILIZE", landed_state=LandedState.ON_GROUND)) == "Take off to fly"
    assert "GUIDED" in stick_hint(state(mode="LOITER", armed=True, landed_state=LandedState.IN_AIR, altitude=3))
    assert stick_hint(state(mode="GUIDED", armed=True, landed_state=LandedState.IN_AIR, altitude=3)) == ""


def test_mode_selector_shows_mode_and_emits_request(qtbot):
    ms = make(ModeSelector, qtbot)
    ms.set_mode("LOITER")
    assert ms.currentText() == "LOITER"
    with qtbot.waitSignal(ms.modeRequested, timeout=1000) as sig:
        ms.activated.emit(ms.findText("GUIDED"))
    assert sig.args == ["GUIDED"]
    assert ms.currentText() == "LOITER"        # until the vehicle reports the new mode
    ms.set_mode("GUIDED")
    assert ms.currentText() == "GUIDED"


def test_plots_receive_data(qtbot):
    p = make(PlotsPanel, qtbot)
    p.show()
    for i in range(50):
        p.append(i * 0.1, altitude=i * 0.05, forward=1.0, right=0.0, climb=0.5, roll=1.0, pitch=-2.0, heading=90)
    p.redraw()
    assert p.sample_count == 50
    assert p.curve_points("altitude") == 50
    xs, ys = p.curves["altitude"].getData()
    assert xs[-1] == 0.0 and ys[-1] == pytest.approx(49 * 0.05)


def test_plots_keep_the_last_minute(qtbot):
    p = PlotsPanel(capacity=100)
    qtbot.addWidget(p)
    p.show()
    for i in range(300):
        p.append(float(i), altitude=float(i))
    p.redraw()
    xs, ys = p.curves["altitude"].getData()
    assert len(xs) == 61 and xs[0] == -60.0 and ys[-1] == 299.0


def test_plots_have_a_minimum_y_range(qtbot):
    p = make(PlotsPanel, qtbot)
    p.show()
    for i in range(30):
        p.append(i * 0.1, altitude=0.001 * (i % 2), forward=0.0, right=0.0, climb=0.0, roll=0.0, pitch=0.0,
                 heading=0.0)
    p.redraw()
    for row, span in enumerate(MIN_SPAN):
        lo, hi = p.y_range(row)
        assert hi - lo >= span, row
        assert not p.plots[row].getAxis("left").autoSIPrefix
    for i in range(30, 60):
        p.append(i * 0.1, altitude=float(i))                 # a real climb is shown whole
    p._dirty = True
    p.redraw()
    lo, hi = p.y_range(0)
    assert lo <= 0.0 and hi >= 59.0


def test_plots_break_their_lines_at_a_gap(qtbot):
    p = make(PlotsPanel, qtbot)
    p.show()
    for i in range(10):
        p.append(float(i), altitude=1.0)
    p.gap(10.0)
    for i in range(20, 30):
        p.append(float(i), altitude=2.0)
    p.redraw()
    xs, ys = p.curves["altitude"].getData()
    assert np.isnan(ys[10]) and np.isfinite(ys[:10]).all() and np.isfinite(ys[11:]).all()


def test_the_heading_line_is_not_drawn_across_north(qtbot):
    p = make(PlotsPanel, qtbot)
    p.show()
    for i, heading in enumerate((350.0, 355.0, 2.0, 7.0, 12.0)):
        p.append(float(i), heading=heading)
    p.gap(5.0)
    p.append(6.0, heading=20.0)
    p.append(7.0, heading=25.0)
    p.redraw()
    joined = p.curves["heading"].opts["connect"]
    assert list(joined) == [True, False, True, True, False, False, True, False]


def test_replay_bar(qtbot):
    r = make(ReplayBar, qtbot)
    r.set_progress(65.0, 130.0, paused=False, speed=2.0)
    assert r.clock.text() == "01:05 / 02:10"
    assert r.play_button.text() == "Pause"
    assert r.speed.currentData() == 2.0
    with qtbot.waitSignal(r.pauseRequested, timeout=1000) as sig:
        qtbot.mouseClick(r.play_button, Qt.LeftButton)
    assert sig.args == [True]


def test_link_banner_says_when_a_replay_is_finished(qtbot):
    b = make(LinkBanner, qtbot)
    b.set_link(LinkStatus.OK, "flight.tlog", 0.0)
    assert b.isHidden()
    b.set_link(LinkStatus.OK, "flight.tlog", 0.0, replay_finished=True)
    assert not b.isHidden() and "Replay ended" in b.text() and "Restart" in b.text()


def test_replay_bar_says_when_the_log_is_finished(qtbot):
    r = make(ReplayBar, qtbot)
    r.set_progress(129.6, 130.0, paused=False, speed=1.0, finished=True)
    assert r.clock.text() == "02:10 / 02:10"      # the end is said by the banner and Restart, not a longer clock
    assert r.play_button.text() == "Play" and not r.play_button.isEnabled()     # one Restart: the button beside
    with qtbot.waitSignal(r.restartRequested, timeout=1000):
        r.restart_button.click()
    assert r.progress.value() == 1000
