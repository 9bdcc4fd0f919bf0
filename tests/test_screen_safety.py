"""Issue 29, safety: arming in a mode that cannot be armed, the map still under the pointer while a plan is edited,
and no GCS failsafe said in the banner. Real simulated vehicle, real driver, real window.
"""
from __future__ import annotations

import pytest
from PyQt5.QtCore import Qt

from driver.sim.common import MODE_NAMES, NOT_ARMABLE

from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def test_the_window_knows_the_modes_the_simulator_refuses_to_arm_in():
    from driver.vehicle.rules import NOT_ARMABLE_MODES
    assert NOT_ARMABLE_MODES == {MODE_NAMES[n] for n in NOT_ARMABLE}


def test_arm_in_rtl_says_which_mode_arms_before_asking_and_offers_the_switch(qtbot, sim, vehicle, window_factory):
    w = window_factory(vehicle)
    qtbot.waitUntil(lambda: w.flightControls.arm_button.isEnabled() and not vehicle.state().readiness.missing,
                    timeout=15000)
    assert vehicle.set_mode("RTL").result(timeout=10).ok
    qtbot.waitUntil(lambda: "RTL" in w.phaseLabel.text() or w.adapter.state.mode == "RTL", timeout=5000)
    qtbot.waitUntil(lambda: "switch to GUIDED or LOITER to arm" in w.phaseLabel.text(), timeout=5000)
    assert "ready to arm" not in w.phaseLabel.text()

    qtbot.mouseClick(w.flightControls.arm_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.flight.arm_box is not None and w.flight.arm_box.isVisible(), timeout=3000)
    box = w.flight.arm_box
    assert "switch to GUIDED or LOITER to arm" in box.text() and "RTL" in box.text()
    assert box.defaultButton() is box.button(box.Cancel)
    switch = next(b for b in box.buttons() if b.text() == "Switch to GUIDED")
    qtbot.mouseClick(switch, Qt.LeftButton)
    qtbot.waitUntil(lambda: sim.truth().mode == "GUIDED", timeout=10000)
    assert not sim.truth().armed                              # a switch, not an arm
    qtbot.waitUntil(lambda: "ready to arm" in w.phaseLabel.text(), timeout=5000)


def test_editing_a_plan_in_flight_never_moves_the_map_under_the_pointer(qtbot, sim, flying, window_factory):
    w = window_factory(flying, takeoff_altitude=3.0)
    view = w.mapPanel.mapView
    qtbot.waitUntil(lambda: w.adapter.state.can_fly_velocity and view.vehicle is not None, timeout=20000)
    assert w.mapPanel.followButton.isChecked()
    qtbot.mouseClick(w.plan.plan_button, Qt.LeftButton)       # Plan: editing on the map
    qtbot.waitUntil(lambda: w.plan.layer.editing, timeout=3000)
    centre = view.centre
    start = sim.truth()
    w.rightStick.hold(0.0, -1.0)                               # the vehicle flies on meanwhile
    qtbot.waitUntil(lambda: abs(sim.truth().north - start.north) > 4.0, timeout=20000)
    qtbot.waitUntil(lambda: view.vehicle is not None and abs(view.vehicle[1] - centre[1]) > 3.0, timeout=5000)
    w.rightStick.hold(0.0, 0.0)
    assert view.centre == centre, "the map moved under the pointer while the plan was edited"
    assert not w.mapPanel.followButton.isEnabled() and not w.mapPanel.followButton.isChecked()
    qtbot.mouseClick(w.plan.plan_button, Qt.LeftButton)       # editing over: Follow as it was
    qtbot.waitUntil(lambda: w.mapPanel.followButton.isChecked(), timeout=3000)


def test_flying_without_a_gcs_failsafe_is_said_in_the_banner(qtbot, sim, vehicle, window_factory):
    w = window_factory(vehicle, takeoff_altitude=3.0)
    qtbot.waitUntil(lambda: w.adapter.state.gcs_failsafe == 0 and not w.adapter.state.readiness.missing,
                    timeout=15000)
    assert not w.alert_banner.isVisible()                      # on the ground it is only a preflight line
    assert vehicle.takeoff(3.0).result(timeout=60).ok
    qtbot.waitUntil(lambda: w.alert_banner.isVisible(), timeout=10000)
    assert "FS_GCS_ENABLE = 0" in w.alert_banner.text and "link loss" in w.alert_banner.text


def test_a_vehicle_found_flying_without_a_gcs_failsafe_is_said_in_the_banner(qtbot, sim, flying, window_factory):
    w = window_factory(flying)
    qtbot.waitUntil(lambda: w.alert_banner.isVisible(), timeout=10000)
    assert "FS_GCS_ENABLE = 0" in w.alert_banner.text
