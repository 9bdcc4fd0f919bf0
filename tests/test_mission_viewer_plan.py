"""Plan mode in the real window on the real driver and simulated vehicle: planned with the mouse on the map and
in the list, as a pilot does (issue 22, the viewer)."""
from __future__ import annotations

import math

import pytest
from PyQt5.QtCore import QEvent, QPoint, QPointF, Qt
from PyQt5.QtGui import QContextMenuEvent, QMouseEvent
from PyQt5.QtWidgets import QApplication, QMenu
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.core.frames import offset_ned
from driver.mission.plan import PlanKind
from uavviewer.plan.survey import SurveySpec

from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)


def screen(view, north: float, east: float) -> QPoint:
    return view.to_screen(east, north).toPoint()


def click(qtbot, view, north: float, east: float) -> None:
    qtbot.mouseClick(view, Qt.LeftButton, pos=screen(view, north, east))


def drag(view, start: QPoint, end: QPoint) -> None:
    post = QApplication.postEvent
    post(view, QMouseEvent(QEvent.MouseButtonPress, QPointF(start), Qt.LeftButton, Qt.LeftButton, Qt.NoModifier))
    for i in range(1, 11):
        p = QPointF(start) + (QPointF(end) - QPointF(start)) * i / 10
        post(view, QMouseEvent(QEvent.MouseMove, p, Qt.NoButton, Qt.LeftButton, Qt.NoModifier))
    post(view, QMouseEvent(QEvent.MouseButtonRelease, QPointF(end), Qt.LeftButton, Qt.NoButton, Qt.NoModifier))


def right_click(qtbot, view, north: float, east: float) -> QMenu:
    pos = screen(view, north, east)
    QApplication.postEvent(view, QContextMenuEvent(QContextMenuEvent.Mouse, pos, view.mapToGlobal(pos)))
    qtbot.waitUntil(lambda: view.findChild(QMenu, "mapMenu") is not None
                    and view.findChild(QMenu, "mapMenu").isVisible())
    return view.findChild(QMenu, "mapMenu")


def planning_window(qtbot, vehicle, window_factory):
    w = window_factory(vehicle, takeoff_altitude=3.0)
    view, plan = w.mapPanel.mapView, w.plan
    qtbot.waitUntil(lambda: plan.home is not None and view.frame is not None, timeout=15000)
    qtbot.mouseClick(w.mapPanel.homeButton, Qt.LeftButton)           # home in the middle, not following
    view.zoom_to(0.5)
    qtbot.mouseClick(w.findChild(type(w.mapPanel.followButton), "planButton"), Qt.LeftButton)
    assert plan.layer.editing and plan.panel.editCheck.isChecked() and plan.dock.isVisible()
    assert not w.telemetryDock.isVisible()                              # the Plan dock in its place
    settle(view)
    return w, view, plan


def settle(view) -> None:
    """Let the docks lay out (the Plan dock came to the front) before clicking at computed points."""
    for _ in range(5):
        QApplication.sendPostedEvents()
        QApplication.processEvents()


def test_plan_a_mission_with_the_mouse_and_the_list(qtbot, vehicle, window_factory):
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    home = plan.home
    table = plan.panel.tables["mission"]

    def where(i: int) -> tuple[float, float]:
        e = plan.doc.entries[i]
        return offset_ned(*home, e.lat, e.lon)

    # two clicks: a takeoff comes first by itself, then the two waypoints where clicked
    click(qtbot, view, 40, 0)
    click(qtbot, view, 40, 60)
    settle(view)
    assert [e.command for e in plan.doc.entries] == [mavlink.MAV_CMD_NAV_TAKEOFF, mavlink.MAV_CMD_NAV_WAYPOINT,
                                                     mavlink.MAV_CMD_NAV_WAYPOINT]
    assert where(1) == pytest.approx((40, 0), abs=0.6) and where(2) == pytest.approx((40, 60), abs=0.6)
    assert table.rowCount() == 3 and table.item(1, 1).text() == "Waypoint" and table.item(2, 0).text() == "3"

    # drag the second waypoint 30 m south; the map does not pan meanwhile
    centre = view.centre
    drag(view, screen(view, 40, 60), screen(view, 10, 60))
    qtbot.waitUntil(lambda: where(2) == pytest.approx((10, 60), abs=0.6))
    assert view.centre == centre and len(plan.doc.entries) == 3

    # the list: altitude, speed (a DO_CHANGE_SPEED before the item), hold
    table.item(2, 2).setText("25")
    assert plan.doc.entries[2].alt == 25.0
    table.item(2, 4).setText("7")
    assert plan.doc.entries[2].param1 == 7.0
    table.item(2, 3).setText("3")
    assert plan.doc.entries[2].command == mavlink.MAV_CMD_DO_CHANGE_SPEED and plan.doc.entries[2].param2 == 3.0
    assert table.rowCount() == 4 and table.item(3, 3).text() == "3" and table.item(1, 3).text() == "10"   # WPNAV_SPEED

    # insert: with waypoint 2 selected and Insert on, a click goes before it
    table.selectRow(1)
    plan.panel.insertCheck.setChecked(True)
    click(qtbot, view, 20, -30)
    assert plan.doc.entries[1].command == mavlink.MAV_CMD_NAV_WAYPOINT and where(1) == pytest.approx((20, -30), abs=0.6)
    assert where(2) == pytest.approx((40, 0), abs=0.6)
    plan.panel.insertCheck.setChecked(False)

    # + RTL at the end, Delete the inserted one (right click on it), ROI and Land by the tool list
    next(a for a in plan.panel.addMenu.actions() if a.text() == "RTL").trigger()
    menu = right_click(qtbot, view, 20, -30)
    delete = next(a for a in menu.actions() if a.text() == "Delete")
    delete.trigger()
    menu.close()
    assert len(plan.doc.entries) == 5 and where(1) == pytest.approx((40, 0), abs=0.6)
    assert plan.doc.entries[-1].command == mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH
    plan.panel.toolCombo.setCurrentText("ROI")
    click(qtbot, view, -20, 20)
    assert plan.doc.entries[-1].command == mavlink.MAV_CMD_DO_SET_ROI
    # the Delete key in the list deletes the selected row
    click(qtbot, view, -30, -30)
    assert len(plan.doc.entries) == 7
    table.setFocus()
    table.selectRow(6)
    qtbot.keyClick(table, Qt.Key_Delete)
    assert len(plan.doc.entries) == 6 and plan.doc.entries[4].command == mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH

    # the totals: distance, time at the cruise speed, battery, on the panel
    totals = plan.doc.totals(home, plan.editor.perf)
    assert totals.distance == pytest.approx(40 + math.hypot(30, 60) + math.hypot(10, 60), abs=2)
    text = plan.panel.totalsLabel.text()
    assert f"{totals.distance / 1000:.2f} km" in text and "mAh" in text and "%" in text

    # what the vehicle would get: home slot excluded, the takeoff first
    out = plan.doc.plan(PlanKind.MISSION)
    assert [i.command for i in out.items][:2] == [mavlink.MAV_CMD_NAV_TAKEOFF, mavlink.MAV_CMD_NAV_WAYPOINT]
    # not on the vehicle: the tab says it differs
    qtbot.waitUntil(lambda: plan.panel.tabs.tabText(0).startswith("●"))

    # an item beyond the driver's flight limits: the upload is refused with the item and the reason, shown here
    table.item(1, 2).setText("150")
    qtbot.mouseClick(plan.panel.uploadButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: plan.panel.progressBar.format() == "upload mission: rejected", timeout=10000)
    assert "item 2 (WAYPOINT): 150 m above home, above the 120 m ceiling" in plan.panel.syncLabel.text()


def test_survey_fence_and_rally_drawn_on_the_map(qtbot, vehicle, window_factory):
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    p = plan.panel
    p.toolCombo.setCurrentText("Survey area")
    assert p.surveyBox.isVisible() and p.finishButton.isVisible()
    p.cameraCombo.setCurrentIndex(0)
    assert "HERO4 Black" in p.cameraCombo.currentText()
    p.altitudeSpin.setValue(30)
    for n, e in ((10, 10), (10, 90), (70, 90), (70, 10)):
        click(qtbot, view, n, e)
    assert len(plan.layer.draft) == 4
    qtbot.mouseClick(p.finishButton, Qt.LeftButton)
    spec = plan.doc.entries[-1]
    assert isinstance(spec, SurveySpec) and spec.altitude == 30 and "HERO4" in spec.camera.name
    s = plan.doc.survey_of(spec)
    assert "GSD 1.55 cm/px" in p.surveyLabel.text() and f"{len(s.passes)} passes" in p.surveyLabel.text()
    assert plan.doc.entries[0].command == mavlink.MAV_CMD_NAV_TAKEOFF and len(plan.doc.entries) == 2
    # more side overlap: more passes; dragging a corner re-plans
    before = len(s.passes)
    p.sideSpin.setValue(80)
    assert len(plan.doc.survey_of(plan.doc.entries[-1]).passes) > before
    drag(view, screen(view, 70, 90), screen(view, 100, 90))
    qtbot.waitUntil(lambda: offset_ned(*plan.home, *plan.doc.entries[-1].polygon[2])
                    == pytest.approx((100, 90), abs=0.6))

    # fence: an inclusion polygon and an exclusion circle whose radius is typed in
    p.tabs.setCurrentIndex(1)
    p.toolCombo.setCurrentText("Inclusion polygon")
    for n, e in ((-50, -50), (-50, 150), (150, 150), (150, -50)):
        click(qtbot, view, n, e)
    qtbot.mouseClick(p.finishButton, Qt.LeftButton)
    p.toolCombo.setCurrentText("Exclusion circle")
    click(qtbot, view, 0, 120)
    p.tables["fence"].item(1, 2).setText("15")
    assert [(f.inclusion, f.circle) for f in plan.doc.fence] == [(True, False), (False, True)]
    assert plan.doc.fence[1].radius == 15
    fence = plan.doc.plan(PlanKind.FENCE)
    assert len(fence) == 5 and fence.items[4].command == mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION
    # rally
    p.tabs.setCurrentIndex(2)
    click(qtbot, view, -30, -30)
    p.tables["rally"].item(0, 1).setText("20")
    assert len(plan.doc.rally) == 1 and plan.doc.rally[0].alt == 20
    assert plan.doc.plan(PlanKind.RALLY).items[0].command == mavlink.MAV_CMD_NAV_RALLY_POINT


def test_file_open_and_save_plan(qtbot, vehicle, window_factory, tmp_path):
    from pymavlink import mavwp

    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    for n, e in ((30, 0), (30, 30)):
        click(qtbot, view, n, e)
    plan.panel.tabs.setCurrentIndex(1)
    plan.panel.toolCombo.setCurrentText("Exclusion circle")
    click(qtbot, view, -20, 20)
    plan.panel.tabs.setCurrentIndex(0)
    mission, fence = plan.doc.plan(PlanKind.MISSION), plan.doc.plan(PlanKind.FENCE)

    def choose(action, path) -> None:
        action.trigger()
        dialog = plan.files.dialog
        qtbot.waitUntil(dialog.isVisible)
        dialog.selectFile(str(path))
        dialog.accept()

    # File › Save plan…: a .plan holds all three plans; a .waypoints file the mission shown (QGC WPL 110)
    choose(plan.save_action, tmp_path / "field.plan")
    choose(plan.save_action, tmp_path / "field.waypoints")
    assert (tmp_path / "field.plan").exists() and (tmp_path / "field.waypoints").read_text().startswith("QGC WPL 110")
    loader = mavwp.MAVWPLoader()
    assert loader.load(str(tmp_path / "field.waypoints")) == len(mission) + 1          # and the home slot
    assert sum("Plan saved to" in t for t in logged(w)) == 2

    # File › Open plan…: everything comes back as it was planned
    plan.doc.entries.clear()
    plan.doc.fence.clear()
    plan.editor.refresh()
    choose(plan.open_action, tmp_path / "field.plan")
    qtbot.waitUntil(lambda: len(plan.doc.entries) == len(mission))
    assert plan.doc.plan(PlanKind.MISSION) == mission and plan.doc.plan(PlanKind.FENCE) == fence
    assert plan.panel.tables["mission"].rowCount() == 3

    # a file that is no plan: said, nothing replaced
    (tmp_path / "junk.plan").write_text("{ not json")
    choose(plan.open_action, tmp_path / "junk.plan")
    assert plan.doc.plan(PlanKind.MISSION) == mission
    assert any(t.startswith("Plan not opened: junk.plan: not valid JSON") for t in logged(w))


def logged(w) -> list[str]:
    """The Messages dock's lines."""
    return [w.messages.topLevelItem(i).text(2) for i in range(w.messages.topLevelItemCount())]
