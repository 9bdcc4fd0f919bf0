"""The screen never says "ready to arm" while the vehicle refuses: the simulator clears its pre-arm bit as ArduPilot
does after a failed calibration (tests/data/recordings/arducopter-4.6-sitl-setup: the bit stays clear through "Arm:
3D Accel calibration needed"), repeats its "PreArm:" reasons every 30 s (-calib: 64 s and 94 s), and the window
shows those reasons, in the vehicle's words, until the vehicle says its checks pass."""
from __future__ import annotations

import pytest
from PyQt5.QtCore import Qt

from driver.vehicle.prearm import FORGET_AFTER, PreArmReasons
from uavviewer.flight.phase import readiness_text

from test_setup_calibration import T, confirm_each
from viewer_fixtures import app_style, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)


def test_the_reasons_stand_until_the_vehicle_says_its_checks_pass():
    r = PreArmReasons()
    assert r.heard("PreArm: 3D Accel calibration needed", 100.0)
    assert r.heard("PreArm: Compass calibrated requires reboot", 100.01)        # the same round: both stand
    assert r.reasons == ("3D Accel calibration needed", "Compass calibrated requires reboot")
    assert not r.heard("Arming motors", 100.5) and not r.heard("Disarm to allow calibration", 100.5)
    assert not r.checked(True, False, 100.3)           # a SYS_STATUS sent before a check ran again says nothing
    assert r.reasons
    assert not r.checked(False, False, 110.0)          # the vehicle still fails them
    r.heard("PreArm: 3D Accel calibration needed", 130.0)                     # 30 s later, one fails still
    assert r.reasons == ("3D Accel calibration needed",)
    assert r.checked(True, False, 132.0) and r.reasons == ()                   # a fresh run passes: gone


def test_a_refusal_stands_after_the_arming_and_goes_when_armed_or_forgotten():
    r = PreArmReasons()
    r.heard("Arm: Mode not armable", 10.0)             # an arming check: the pre-arm bit never went clear
    assert not r.checked(True, False, 10.1) and r.reasons == ("Mode not armable",)
    assert r.checked(False, True, 11.0) and not r.reasons                      # it armed after all
    r.heard("PreArm: Hardware safety switch", 20.0)
    assert not r.checked(None, False, 20.0 + FORGET_AFTER - 1)                 # a firmware without the bit
    assert r.checked(None, False, 20.0 + FORGET_AFTER + 1) and not r.reasons   # not said again: forgotten


def test_a_failed_accel_calibration_leaves_the_vehicle_unready_in_its_own_words(sim_factory, vehicle_factory):
    sim = sim_factory(speedup=20.0)
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert v.wait_for(lambda s: s.readiness.ready_to_arm, T)
    cal = v.setup.accel_calibration()
    assert confirm_each(cal, v) == [1, 2]
    assert cal.verdict.result(T).reason == "Calibration FAILED"
    s = v.wait_for(lambda s: s.readiness.reasons, T)
    assert s is not None and s.readiness.reasons == ("3D Accel calibration needed",)
    assert not s.readiness.prearm_ok and not s.readiness.ready_to_arm          # the bit is clear, as ArduPilot's
    assert s.readiness.missing == ("pre-arm checks: 3D Accel calibration needed",)
    said = [m for m in s.messages if m.text == "PreArm: 3D Accel calibration needed"]
    # said again 30 vehicle seconds later (1.5 s at this speed), and still standing
    again = v.wait_for(lambda s: len([m for m in s.messages if m.text == "PreArm: 3D Accel calibration needed"])
                       > len(said), T)
    assert again is not None and again.readiness.reasons == ("3D Accel calibration needed",)
    assert readiness_text(again) == "not ready to arm: 3D Accel calibration needed"


def test_the_window_never_says_ready_while_the_vehicle_refuses(qtbot, sim_factory, vehicle_factory,
                                                                window_factory):
    sim = sim_factory(speedup=20.0)
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    w = window_factory(v)
    qtbot.waitUntil(lambda: w.phaseLabel.text() == "On the ground · ready to arm", timeout=30000)
    assert w.flightControls.main_button.text() == "Take off"
    cal = v.setup.accel_calibration()
    confirm_each(cal, v)
    assert cal.verdict.result(T).reason == "Calibration FAILED"
    qtbot.waitUntil(lambda: "3D Accel calibration needed" in w.phaseLabel.text(), timeout=10000)
    assert w.phaseLabel.text() == "Not ready to arm: 3D Accel calibration needed"
    button = w.flightControls.main_button
    assert button.text() == "Take off when ready" and "3D Accel calibration needed" in button.toolTip()
    panel = w.preflight_panel
    # the panel redraws on its own refresh: it may show NO GO a beat before the vehicle's reason
    qtbot.waitUntil(lambda: panel.verdict_of("Pre-arm") == "NO GO"
                    and panel.reason_of("Pre-arm") == "3D Accel calibration needed", timeout=10000)
    snapshots = []
    w.adapter.stateChanged.connect(snapshots.append)
    qtbot.waitUntil(lambda: len([m for m in w.adapter.state.messages
                                 if m.text == "PreArm: 3D Accel calibration needed"]) >= 2, timeout=20000)
    assert snapshots and not any("ready to arm" == readiness_text(s) for s in snapshots)   # never in between
    qtbot.mouseClick(button, Qt.LeftButton)             # the question says why it waits
    qtbot.waitUntil(lambda: w.flight.takeoff_box is not None and w.flight.takeoff_box.isVisible(), timeout=3000)
    assert "3D Accel calibration needed" in w.flight.takeoff_box.text()
    w.flight.takeoff_box.reject()
