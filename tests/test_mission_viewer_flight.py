"""A mission planned on the map, uploaded, started, paused, resumed and skipped through the real window, flown by
the real driver and simulated ArduCopter to the end (issue 22, the viewer's "Transfers" and "Flying it")."""
from __future__ import annotations

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtGui import QContextMenuEvent
from PyQt5.QtWidgets import QApplication, QMenu, QMessageBox
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.mission.plan import MissionRunState, PlanKind

from conftest import LAST_LEG_SPEEDUP
from test_mission_viewer_plan import click, planning_window, right_click, settle
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(180)


@pytest.fixture
def fast_sim(sim_factory):
    return sim_factory(speedup=8.0)


@pytest.fixture
def fast_vehicle(fast_sim, vehicle_factory):
    v = vehicle_factory(f"tcp:127.0.0.1:{fast_sim.tcp_port}")
    assert v.wait_for(lambda s: s.connected and s.home is not None, 20)
    return v


def test_plan_upload_start_pause_resume_skip_and_land(qtbot, fast_sim, fast_vehicle, window_factory):
    vehicle = fast_vehicle
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    p = plan.panel
    # the plan: takeoff (added by itself), three waypoints, RTL
    for north, east in ((15, 0), (15, 15), (0, 15)):
        click(qtbot, view, north, east)
    next(a for a in p.addMenu.actions() if a.text() == "RTL").trigger()
    settle(view)
    assert len(plan.doc.entries) == 5
    qtbot.waitUntil(lambda: p.tabs.tabText(0).startswith("●"), timeout=5000)    # not on the vehicle yet

    # Upload: the progress bar runs, then the vehicle's read-back makes it "the same"
    qtbot.mouseClick(p.uploadButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: p.progressBar.format() == "upload mission: accepted", timeout=30000)
    assert "read back" in p.progressBar.toolTip()
    qtbot.waitUntil(lambda: p.syncLabel.text().startswith("Same as the vehicle's mission (5 items)"), timeout=5000)
    assert p.tabs.tabText(0) == "Mission" and not p.pauseButton.isEnabled()
    assert vehicle.state().mission.vehicle_plan(PlanKind.MISSION) is not None

    # an edit makes it differ again; undoing it by the list makes it the same
    p.tables["mission"].item(2, 2).setText("12")
    qtbot.waitUntil(lambda: p.tabs.tabText(0).startswith("●") and "altitude" in p.syncLabel.text())
    p.tables["mission"].item(2, 2).setText("10")
    qtbot.waitUntil(lambda: p.syncLabel.text().startswith("Same"))

    # Start mission: one confirmation, Cancel by default; then it flies item by item
    qtbot.waitUntil(p.startButton.isEnabled, timeout=10000)
    with qtbot.waitSignal(plan.startAsked) as asked:
        qtbot.mouseClick(p.startButton, Qt.LeftButton)
    box = asked.args[0]
    assert box.defaultButton() is box.button(QMessageBox.Cancel) and "5 items" in box.text()
    assert "takes off" in box.text()
    qtbot.mouseClick(box.button(QMessageBox.Yes), Qt.LeftButton)
    qtbot.waitUntil(lambda: vehicle.state().mission.current == 2 and vehicle.state().mode == "AUTO", timeout=60000)
    qtbot.waitUntil(lambda: plan.layer.current == 2, timeout=5000)        # highlighted on the map ...
    table = p.tables["mission"]
    assert table.item(1, 0).background().color() == Qt.darkGreen          # ... and in the list
    qtbot.waitUntil(lambda: p.progressLabel.text().startswith("Item 2 of 5") and " s to it" in p.progressLabel.text())
    assert plan.layer.progress.startswith("Item ")                       # on the map too
    assert p.pauseButton.isEnabled() and not p.resumeButton.isEnabled() and not p.startButton.isEnabled()

    # Pause: BRAKE, the current item kept; Resume: AUTO again
    qtbot.mouseClick(p.pauseButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: vehicle.state().mode == "BRAKE", timeout=10000)
    qtbot.waitUntil(lambda: "paused (BRAKE)" in p.progressLabel.text() and p.resumeButton.isEnabled())
    assert vehicle.state().mission.current == 2 and plan.layer.current == 2
    qtbot.mouseClick(p.resumeButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: vehicle.state().mode == "AUTO" and p.pauseButton.isEnabled(), timeout=10000)

    # Skip to item 4 by a right click on its marker on the map
    qtbot.waitUntil(lambda: vehicle.state().mission.current == 3, timeout=60000)
    menu = right_click(qtbot, view, 0, 15)
    skip = next(a for a in menu.actions() if a.text() == "Skip to item 4")
    assert skip.isEnabled()
    skip.trigger()
    menu.close()
    qtbot.waitUntil(lambda: vehicle.state().mission.current == 4, timeout=10000)
    assert vehicle.state().mission.last_reached == 2                      # item 3 was skipped, not reached
    qtbot.waitUntil(lambda: plan.layer.current == 4 and table.item(3, 0).background().color() == Qt.darkGreen)

    # paused again, skipped back to item 2 by the list's right click: the vehicle holds and says 2 is current;
    # resumed, it flies item 2 again
    qtbot.mouseClick(p.pauseButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: vehicle.state().mode == "BRAKE", timeout=10000)
    row = table.visualItemRect(table.item(1, 1)).center()
    QApplication.postEvent(table.viewport(), QContextMenuEvent(QContextMenuEvent.Mouse, row,
                                                               table.viewport().mapToGlobal(row)))
    qtbot.waitUntil(lambda: table.findChild(QMenu, "planMenu") is not None
                    and table.findChild(QMenu, "planMenu").isVisible())
    menu = table.findChild(QMenu, "planMenu")
    skip = next(a for a in menu.actions() if a.text() == "Skip to item 2")
    skip.trigger()
    menu.close()
    qtbot.waitUntil(lambda: vehicle.state().mission.current == 2, timeout=10000)
    qtbot.waitUntil(lambda: plan.layer.current == 2 and p.progressLabel.text().startswith("Item 2 of 5"))
    def reached_2() -> int:
        return sum(m.text == "Reached command #2" for m in vehicle.state().messages)
    before = reached_2()
    qtbot.mouseClick(p.resumeButton, Qt.LeftButton)
    fast_sim.speedup = LAST_LEG_SPEEDUP                  # item 2 again, 4, the way home and the landing
    qtbot.waitUntil(lambda: reached_2() > before, timeout=60000)

    # the RTL item brings it home, it lands and disarms in AUTO: the mission is complete
    qtbot.waitUntil(lambda: vehicle.state().mission.state is MissionRunState.COMPLETE and not vehicle.state().armed,
                    timeout=120000)
    qtbot.waitUntil(lambda: p.progressLabel.text() == "Mission complete (5 items)")
    assert plan.layer.current is None and not p.pauseButton.isEnabled()
    reached = [m.text for m in vehicle.state().messages if m.text.startswith("Mission: ")]
    assert any(t.startswith("Mission: 5 RTL") for t in reached)


def test_download_clear_and_a_fence(qtbot, fast_vehicle, window_factory):
    vehicle = fast_vehicle
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    p = plan.panel
    for north, east in ((20, 0), (20, 20)):
        click(qtbot, view, north, east)
    qtbot.mouseClick(p.uploadButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: p.syncLabel.text().startswith("Same"), timeout=30000)
    sent = plan.doc.plan(PlanKind.MISSION)

    # another plan here; Download brings the vehicle's back into the editor
    plan.doc.entries.clear()
    plan.editor.refresh()
    qtbot.waitUntil(lambda: p.tabs.tabText(0).startswith("●") and p.downloadButton.isEnabled())
    qtbot.mouseClick(p.downloadButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: len(plan.doc.entries) == 3, timeout=30000)
    assert [e.command for e in plan.doc.entries] == [i.command for i in sent.items]
    assert p.tables["mission"].rowCount() == 3 and p.syncLabel.text().startswith("Same")

    # Remove from vehicle (asked first): the vehicle holds no mission; the plan here is kept and now differs
    qtbot.waitUntil(p.clearButton.isEnabled)
    qtbot.mouseClick(p.clearButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: plan.remove_question is not None and plan.remove_question.isVisible())
    qtbot.mouseClick(next(b for b in plan.remove_question.buttons() if b.text() == "Remove from vehicle"),
                     Qt.LeftButton)
    qtbot.waitUntil(lambda: p.progressBar.format() == "clear mission: accepted", timeout=30000)
    qtbot.waitUntil(lambda: "0 items there, 3 here" in p.syncLabel.text())
    assert not p.startButton.isEnabled()

    # a fence: an inclusion polygon around home, drawn, uploaded, the same on the vehicle
    p.tabs.setCurrentIndex(1)
    p.toolCombo.setCurrentText("Inclusion polygon")
    for north, east in ((-60, -60), (-60, 60), (60, 60), (60, -60)):
        click(qtbot, view, north, east)
    qtbot.mouseClick(p.finishButton, Qt.LeftButton)
    qtbot.waitUntil(p.uploadButton.isEnabled)
    qtbot.mouseClick(p.uploadButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: p.syncLabel.text().startswith("Same as the vehicle's fence (4 items)"), timeout=30000)
    fence = vehicle.state().mission.vehicle_plan(PlanKind.FENCE)
    assert [i.command for i in fence.items] == [mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION] * 4


def test_start_is_refused_while_the_vehicles_mission_goes_beyond_the_limits(qtbot, sim_factory, vehicle_factory,
                                                                           window_factory):
    """Another ground station left a mission with a waypoint 900 m out on the vehicle: downloaded, the driver
    names that item, and the Start button stays off with that reason (the driver refuses it too)."""
    from driver.core import frames
    from driver.sim.missions import stored_as
    sim = sim_factory(speedup=8.0)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.connected and s.home is not None, 20)
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    autopilot = sim.autopilot
    home = vehicle.state().home
    lat, lon = frames.offset_latlon(home.lat, home.lon, 900, 0)
    autopilot.plans[PlanKind.MISSION] = [
        autopilot.mission_home_item(),
        stored_as(PlanKind.MISSION, mavlink.MAV_CMD_NAV_TAKEOFF, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT, (0,) * 4,
                  0, 0, 10),
        stored_as(PlanKind.MISSION, mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT, (0,) * 4,
                  round(lat * 1e7), round(lon * 1e7), 20)]
    p = plan.panel
    qtbot.waitUntil(p.downloadButton.isEnabled)
    qtbot.mouseClick(p.downloadButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: "item 2 (WAYPOINT): 900 m from home" in p.startButton.toolTip(), timeout=30000)
    assert not p.startButton.isEnabled()
    refused = vehicle.start_mission().result(5)
    assert refused.reason == "the mission is not started: item 2 (WAYPOINT): 900 m from home, beyond the 500 m limit"
