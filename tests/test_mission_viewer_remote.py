"""Plan mode on a remote drone (the MAVLinkServer over Ice) and on the Solo's ArduCopter 3.3: the same window plans,
uploads and flies; what a vehicle cannot hold is refused with its reason, shown where the pilot looks."""
from __future__ import annotations

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QMessageBox

from driver.mission.plan import PlanKind

from conftest import LAST_LEG_SPEEDUP
from ice_fixtures import drone_factory, server_factory  # noqa: F401  (fixtures)
from test_mission_viewer_plan import click, planning_window, settle
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(180)


def plan_and_upload(qtbot, w, view, plan) -> None:
    """Takeoff (by itself), two waypoints, RTL; uploaded and read back the same."""
    for north, east in ((12, 0), (12, 12)):
        click(qtbot, view, north, east)
    next(a for a in plan.panel.addMenu.actions() if a.text() == "RTL").trigger()
    settle(view)
    qtbot.waitUntil(plan.panel.uploadButton.isEnabled)
    qtbot.mouseClick(plan.panel.uploadButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: plan.panel.syncLabel.text().startswith("Same as the vehicle's mission (4 items)"),
                    timeout=30000)


def start(qtbot, plan) -> None:
    qtbot.waitUntil(plan.panel.startButton.isEnabled, timeout=10000)
    with qtbot.waitSignal(plan.startAsked) as asked:
        qtbot.mouseClick(plan.panel.startButton, Qt.LeftButton)
    qtbot.mouseClick(asked.args[0].button(QMessageBox.Yes), Qt.LeftButton)


def test_the_remote_viewer_plans_and_flies_through_ice(qtbot, sim_factory, vehicle_factory,
                                                       server_factory, drone_factory, window_factory):  # noqa: F811
    sim = sim_factory(speedup=8.0)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.connected and s.home is not None, 20)
    drone = drone_factory(server_factory(vehicle))
    assert drone.wait_for(lambda s: s.connected and s.home is not None, 20)
    w, view, plan = planning_window(qtbot, drone, window_factory)
    plan_and_upload(qtbot, w, view, plan)
    assert len(sim.autopilot.plans[PlanKind.MISSION]) == 5                 # the home slot and the four items
    start(qtbot, plan)
    qtbot.waitUntil(lambda: plan.panel.progressLabel.text().startswith("Item 2 of 4"), timeout=60000)
    qtbot.waitUntil(lambda: plan.layer.current == 2)
    qtbot.waitUntil(plan.panel.pauseButton.isEnabled)
    qtbot.mouseClick(plan.panel.pauseButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: "paused (BRAKE)" in plan.panel.progressLabel.text(), timeout=10000)
    qtbot.mouseClick(plan.panel.resumeButton, Qt.LeftButton)
    sim.speedup = LAST_LEG_SPEEDUP                       # the rest of the mission is only waited out
    qtbot.waitUntil(lambda: plan.panel.progressLabel.text() == "Mission complete (4 items)", timeout=120000)
    assert not sim.truth().armed


def test_the_solo_takes_the_mission_and_refuses_a_fence_with_its_reason(qtbot, sim_factory, vehicle_factory,
                                                                         window_factory):  # noqa: F811
    sim = sim_factory(speedup=8.0, profile="solo")
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.connected and s.home is not None and s.firmware, 20)
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    plan_and_upload(qtbot, w, view, plan)                                  # float MISSION_ITEMs, read back the same
    assert "MISSION_ITEM_INT" not in {kind for _, kind, _ in sim.received_messages}

    p = plan.panel
    p.tabs.setCurrentIndex(1)
    p.toolCombo.setCurrentText("Inclusion circle")
    click(qtbot, view, 0, 0)
    qtbot.mouseClick(p.uploadButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: p.progressBar.format() == "upload fence: rejected", timeout=10000)
    assert "FENCE_RADIUS" in p.syncLabel.text() and p.tabs.tabText(1).startswith("●")

    # ArduCopter 3.3 says no mission_state: the buttons follow its mode and MISSION_CURRENT
    p.tabs.setCurrentIndex(0)
    start(qtbot, plan)
    qtbot.waitUntil(lambda: plan.layer.current == 2 and p.pauseButton.isEnabled(), timeout=60000)
    assert p.progressLabel.text().startswith("Item 2 of 4")


def test_a_replayed_mission_shows_its_progress_and_cannot_be_commanded(qtbot, vehicle_factory,
                                                                       window_factory):  # noqa: F811
    from recordings import MISSION
    replay = vehicle_factory(MISSION + ".tlog", tlog_path=None, replay_speed=20.0)
    replay.replay.pause()                                # held until the window listens
    w = window_factory(replay)
    plan = w.plan
    plan.show_plan(True)
    replay.replay.resume()
    qtbot.waitUntil(lambda: plan.panel.progressLabel.text().startswith("Item "), timeout=60000)
    p = plan.panel
    assert not any(b.isEnabled() for b in (p.uploadButton, p.downloadButton, p.clearButton, p.startButton,
                                            p.pauseButton, p.resumeButton))
    assert not p.skip_allowed


def test_picking_another_vehicle_forgets_what_the_first_one_holds(qtbot, sim_factory, vehicle_factory,
                                                                   window_factory):  # noqa: F811
    first, second = (vehicle_factory(f"tcp:127.0.0.1:{sim_factory(speedup=8.0).tcp_port}") for _ in range(2))
    for v in (first, second):
        assert v.wait_for(lambda s: s.connected and s.home is not None, 20)
    w, view, plan = planning_window(qtbot, first, window_factory)
    plan_and_upload(qtbot, w, view, plan)
    qtbot.waitUntil(plan.panel.startButton.isEnabled, timeout=5000)     # once MISSION_CURRENT counts it too
    w.adapter.use(second)                              # what the window does when the Fleet panel picks another
    qtbot.waitUntil(lambda: "not known yet" in plan.panel.syncLabel.text() and plan.panel.tabs.tabText(0)[0] == "●")
    assert not plan.panel.startButton.isEnabled() and plan.panel.progressBar.format() == "No transfer yet"
