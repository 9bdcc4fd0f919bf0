"""Plan mode never loses work (issue 29, items 11-16), in the real window on the real driver and simulated
vehicle: the file type chosen is the type written, Delete in the list, Clear vs Remove from vehicle, New plan,
questions before edits are lost, undo and redo, moving items, a survey kept a survey in a .plan, items after RTL
or LAND, and the vehicle's own cruise speed."""
from __future__ import annotations

import json

import pytest
from PyQt5.QtCore import QPoint, Qt
from PyQt5.QtWidgets import QApplication, QMessageBox
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.mission.plan import PlanKind
from uavviewer.plan.survey import SurveySpec

from test_mission_viewer_plan import click, logged, planning_window, settle
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)
WP, RTL = mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH


def choose(qtbot, plan, action, path, wpl: bool = False) -> None:
    """File › Open / Save plan…, a file typed in (and the WPL type picked), accepted."""
    action.trigger()
    dialog = plan.files.dialog
    qtbot.waitUntil(dialog.isVisible)
    if wpl:
        dialog.selectNameFilter(next(f for f in dialog.nameFilters() if "WPL" in f))
    dialog.selectFile(str(path))
    dialog.accept()


def answer(qtbot, get_box, button_text: str) -> None:
    qtbot.waitUntil(lambda: get_box() is not None and get_box().isVisible())
    box = get_box()
    qtbot.mouseClick(next(b for b in box.buttons() if b.text() == button_text), Qt.LeftButton)


def row_rect(table, row: int):
    return table.visualRect(table.model().index(row, 1))


def test_save_as_wpl_writes_the_mission_whatever_the_tab(qtbot, vehicle, window_factory, tmp_path):
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    for n, e in ((30, 0), (30, 30)):
        click(qtbot, view, n, e)
    plan.panel.tabs.setCurrentIndex(1)
    plan.panel.toolCombo.setCurrentText("Exclusion circle")
    click(qtbot, view, -20, 20)                     # the Fence tab is the one shown when saving
    mission = plan.doc.plan(PlanKind.MISSION)
    # the WPL type picked, a name typed without its ending: a WPL file of the mission, not a .plan
    choose(qtbot, plan, plan.save_action, tmp_path / "field", wpl=True)
    qtbot.waitUntil(lambda: (tmp_path / "field.waypoints").exists())
    assert not (tmp_path / "field.plan").exists()
    lines = (tmp_path / "field.waypoints").read_text().splitlines()
    assert lines[0] == "QGC WPL 110" and len(lines) == 2 + len(mission)
    assert [int(line.split("\t")[3]) for line in lines[2:]] == [i.command for i in mission.items]
    # said plainly: the fence is not in it
    said = next(t for t in logged(w) if t.startswith("Plan saved to"))
    assert "cannot hold the fence (1 items)" in said and "save a .plan" in said


def test_delete_key_deletes_the_rows_clicked_in_the_list(qtbot, vehicle, window_factory):
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    for n, e in ((30, 0), (30, 30), (0, 30), (0, 60)):
        click(qtbot, view, n, e)
    table = plan.panel.tables["mission"]
    settle(view)
    assert len(plan.doc.entries) == 5
    # a click on a row, then the Delete key: where the focus went, as a pilot's key press goes
    qtbot.mouseClick(table.viewport(), Qt.LeftButton, pos=row_rect(table, 4).center())
    qtbot.keyClick(QApplication.focusWidget(), Qt.Key_Delete)
    assert len(plan.doc.entries) == 4
    # two rows (Ctrl+click): both go
    qtbot.mouseClick(table.viewport(), Qt.LeftButton, pos=row_rect(table, 1).center())
    qtbot.mouseClick(table.viewport(), Qt.LeftButton, Qt.ControlModifier, pos=row_rect(table, 3).center())
    qtbot.keyClick(QApplication.focusWidget(), Qt.Key_Delete)
    assert [e.command for e in plan.doc.entries] == [mavlink.MAV_CMD_NAV_TAKEOFF, WP]


def test_undo_redo_move_new_clear_and_remove(qtbot, vehicle, window_factory):
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    p, doc = plan.panel, plan.doc
    for n, e in ((30, 0), (30, 30), (0, 30)):
        click(qtbot, view, n, e)
    third = doc.entries[3]
    # Ctrl+Z takes back the last click, Ctrl+Shift+Z brings it again
    qtbot.keyClick(w, Qt.Key_Z, Qt.ControlModifier)
    assert len(doc.entries) == 3 and p.tables["mission"].rowCount() == 3
    qtbot.keyClick(w, Qt.Key_Z, Qt.ControlModifier | Qt.ShiftModifier)
    assert doc.entries[3] == third
    # moved up, then undone
    p.tables["mission"].selectRow(3)
    qtbot.mouseClick(p.upButton, Qt.LeftButton)
    assert doc.entries[2] == third
    plan.undo_action.trigger()
    assert doc.entries[3] == third
    # a typed altitude is one step
    p.tables["mission"].item(1, 2).setText("22")
    assert doc.entries[1].alt == 22
    plan.undo_action.trigger()
    assert doc.entries[1].alt != 22

    # upload it; Clear the list empties the editor only; the vehicle keeps its mission
    qtbot.mouseClick(p.uploadButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: p.progressBar.format() == "upload mission: accepted", timeout=20000)
    held = plan.vehicle_plan(PlanKind.MISSION)
    assert len(held) == 4
    p.clearListRequested.emit("mission")
    assert doc.entries == [] and plan.vehicle_plan(PlanKind.MISSION) == held
    plan.undo_action.trigger()
    assert len(doc.entries) == 4
    # Remove from vehicle asks first; Cancel keeps it there
    qtbot.mouseClick(p.clearButton, Qt.LeftButton)
    answer(qtbot, lambda: plan.remove_question, "Cancel")
    assert plan.vehicle_plan(PlanKind.MISSION) == held
    qtbot.mouseClick(p.clearButton, Qt.LeftButton)
    answer(qtbot, lambda: plan.remove_question, "Remove from vehicle")
    qtbot.waitUntil(lambda: plan.vehicle_plan(PlanKind.MISSION) is not None
                    and len(plan.vehicle_plan(PlanKind.MISSION)) == 0, timeout=20000)
    assert len(doc.entries) == 4                   # the list stays

    # New plan asks before unsaved edits go: Cancel keeps them, Discard empties
    plan.new_action.trigger()
    answer(qtbot, lambda: plan.discard_question, "Cancel")
    assert len(doc.entries) == 4
    plan.new_action.trigger()
    answer(qtbot, lambda: plan.discard_question, "Discard edits")
    assert doc.entries == [] and not plan.history.modified
    # Open asks too
    click(qtbot, view, 10, 10)
    plan.open_action.trigger()
    answer(qtbot, lambda: plan.discard_question, "Cancel")
    assert plan.files.dialog is None or not plan.files.dialog.isVisible()
    # and quitting: the window stays until the edits may go
    w.close()
    answer(qtbot, lambda: plan.discard_question, "Cancel")
    assert w.isVisible()
    w.close()
    answer(qtbot, lambda: plan.discard_question, "Discard edits")
    qtbot.waitUntil(lambda: not w.isVisible())


def test_a_saved_survey_opens_as_a_survey(qtbot, vehicle, window_factory, tmp_path):
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    p = plan.panel
    click(qtbot, view, 0, 30)
    p.toolCombo.setCurrentText("Survey area")
    p.altitudeSpin.setValue(30)
    for n, e in ((10, 10), (10, 90), (70, 90), (70, 10)):
        click(qtbot, view, n, e)
    qtbot.mouseClick(p.finishButton, Qt.LeftButton)
    next(a for a in p.addMenu.actions() if a.text() == "RTL").trigger()
    spec = plan.doc.entries[2]
    assert isinstance(spec, SurveySpec)
    mission = plan.doc.plan(PlanKind.MISSION)
    choose(qtbot, plan, plan.save_action, tmp_path / "survey.plan")
    qtbot.waitUntil(lambda: (tmp_path / "survey.plan").exists())
    data = json.loads((tmp_path / "survey.plan").read_text())
    kinds = [i["type"] for i in data["mission"]["items"]]
    assert kinds == ["SimpleItem", "SimpleItem", "ComplexItem", "SimpleItem"]
    survey_json = data["mission"]["items"][2]
    assert survey_json["complexItemType"] == "survey" and len(survey_json["polygon"]) == 4
    assert survey_json["TransectStyleComplexItem"]["CameraCalc"]["DistanceToSurface"] == 30
    assert not plan.history.modified                               # saved: nothing to lose

    plan.new_action.trigger()
    assert plan.doc.entries == []
    choose(qtbot, plan, plan.open_action, tmp_path / "survey.plan")
    qtbot.waitUntil(lambda: len(plan.doc.entries) == 4)
    assert plan.doc.entries[2] == spec and plan.doc.plan(PlanKind.MISSION) == mission
    assert p.tables["mission"].item(2, 1).text().startswith("Survey:")
    # editable again: its altitude re-plans it
    p.tables["mission"].selectRow(2)
    p.altitudeSpin.setValue(40)
    assert plan.doc.entries[2].altitude == 40


def test_items_after_rtl_are_marked_never_flown(qtbot, vehicle, window_factory):
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    click(qtbot, view, 30, 0)
    next(a for a in plan.panel.addMenu.actions() if a.text() == "RTL").trigger()
    click(qtbot, view, 30, 30)
    table = plan.panel.tables["mission"]
    assert [e.command for e in plan.doc.entries][1:] == [WP, RTL, WP]
    assert table.item(3, 1).text().startswith("⚠")
    assert "Never flown: item 3 (RTL)" in table.item(3, 1).toolTip()
    assert not table.item(1, 1).toolTip()
    # moved before the RTL, it is flown: the mark goes
    table.selectRow(3)
    plan.editor.move_selected(-1)
    assert not table.item(2, 1).toolTip() and not table.item(3, 1).toolTip()


def test_cruise_speed_is_the_vehicles_from_the_start(qtbot, vehicle, window_factory):
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    label = plan.panel.totalsLabel
    # never opened Parameters: WPNAV_SPEED is read by name at connect (the simulated ArduCopter's 1000 cm/s)
    qtbot.waitUntil(lambda: "cruise 10 m/s (WPNAV_SPEED)" in label.text(), timeout=15000)
    assert plan.editor.perf.cruise == 10.0
    click(qtbot, view, 40, 0)
    assert plan.panel.tables["mission"].item(1, 3).text() == "10"


def test_upload_sends_every_plan_that_changed(qtbot, vehicle, window_factory):
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    p = plan.panel
    for n, e in ((30, 0), (30, 30)):
        click(qtbot, view, n, e)
    p.tabs.setCurrentIndex(1)
    p.toolCombo.setCurrentText("Inclusion circle")
    click(qtbot, view, 0, 0)
    p.tables["fence"].item(0, 2).setText("200")
    p.tabs.setCurrentIndex(0)                        # the Mission tab shown; the fence changed too
    qtbot.mouseClick(p.uploadButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: all(plan.vehicle_plan(k) is not None for k in (PlanKind.MISSION, PlanKind.FENCE)),
                    timeout=30000)
    assert plan.vehicle_plan(PlanKind.FENCE).items[0].param1 == 200
    qtbot.waitUntil(lambda: not plan.how_it_differs(PlanKind.MISSION) and not plan.how_it_differs(PlanKind.FENCE),
                    timeout=10000)
    rally = plan.vehicle_plan(PlanKind.RALLY)     # nothing here, nothing sent (read, to say whether it keeps some)
    assert rally is None or not rally.items


def drag(qtbot, w, table, start: QPoint, end: QPoint) -> None:
    """Press, move and release the left button in ``table`` as a mouse does: through the window, as the platform
    delivers them (a move sent to a widget alone carries no button)."""
    win, vp = w.windowHandle(), table.viewport()
    at = lambda p: vp.mapTo(w, p)                                               # noqa: E731
    qtbot.mousePress(win, Qt.LeftButton, pos=at(start))
    for k in range(1, 5):                                                       # a few steps on the way
        qtbot.mouseMove(win, at(start + (end - start) * k / 4))
    qtbot.mouseRelease(win, Qt.LeftButton, pos=at(end))


def test_rows_dragged_in_the_list_move_their_items(qtbot, vehicle, window_factory):
    """Dragging a row only stretched the selection (its items were not draggable; the test handed the list a
    made-up drop). Real mouse events now: one row, then two selected rows together; the drop says where."""
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    for n, e in ((30, 0), (30, 30), (0, 30)):
        click(qtbot, view, n, e)
    table = plan.panel.tables["mission"]
    settle(view)
    before = list(plan.doc.entries)                  # takeoff, A, B, C
    upper_half_of = lambda row: row_rect(table, row).center() - QPoint(0, row_rect(table, row).height() // 4)  # noqa
    drag(qtbot, w, table, row_rect(table, 3).center(), upper_half_of(1))
    qtbot.waitUntil(lambda: plan.doc.entries == [before[0], before[3], before[1], before[2]], timeout=3000)
    assert table.rowCount() == 4 and plan.panel.selected_rows("mission") == [1]     # C went before A
    assert table.before is None                                                  # no line left over
    plan.undo_action.trigger()
    assert plan.doc.entries == before

    qtbot.mouseClick(table.viewport(), Qt.LeftButton, pos=row_rect(table, 1).center())
    qtbot.mouseClick(table.viewport(), Qt.LeftButton, Qt.ControlModifier, pos=row_rect(table, 2).center())
    assert plan.panel.selected_rows("mission") == [1, 2]
    below_last = row_rect(table, 3).center() + QPoint(0, row_rect(table, 3).height() // 4)
    drag(qtbot, w, table, row_rect(table, 2).center(), below_last)              # A and B after C
    qtbot.waitUntil(lambda: plan.doc.entries == [before[0], before[3], before[1], before[2]], timeout=3000)
    drag(qtbot, w, table, row_rect(table, 1).center(), row_rect(table, 1).center() + QPoint(0, 1))
    assert plan.doc.entries == [before[0], before[3], before[1], before[2]]     # a click, not a drag: no move


def test_a_survey_planned_elsewhere_opens_as_its_waypoints_and_says_so(qtbot, vehicle, window_factory, tmp_path):
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    items = [{"type": "SimpleItem", "command": 16, "frame": 3, "params": [0, 0, 0, None, 40.2842, -3.794, 30]},
             {"type": "SimpleItem", "command": 206, "frame": 2, "params": [25, 0, 1, 0, 0, 0, 0]}]
    qgc = {"type": "ComplexItem", "complexItemType": "survey", "angle": 0,
           "polygon": [[40.284, -3.794], [40.284, -3.793], [40.285, -3.793]],
           "TransectStyleComplexItem": {"CameraCalc": {"CameraName": "Sony a6000 16 mm", "DistanceToSurface": 50,
                                                       "FrontalOverlap": 70, "SideOverlap": 60}, "Items": items}}
    (tmp_path / "qgc.plan").write_text(json.dumps({"fileType": "Plan", "mission": {"items": [qgc]}}))
    plan.files.open(str(tmp_path / "qgc.plan"))
    assert [e.command for e in plan.doc.entries] == [16, 206]       # flown as the file says
    assert any("the survey at item 1 is opened as its 2 items (its settings make other passes here)" in t
               for t in logged(w))
