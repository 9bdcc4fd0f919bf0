"""The fence as the vehicle will keep it, said before and after an upload: every waypoint and survey leg outside
the plan's inclusion zones (or inside an exclusion) is marked before it goes up; a fence uploaded while the
vehicle's FENCE_ENABLE is 0 is said to be off, with FENCE_ENABLE 1 offered through Parameters; and a plan with no
fence says that the vehicle keeps the one it had, offering to remove it."""
from __future__ import annotations

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QMessageBox
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.core.frames import offset_latlon
from driver.mission.plan import MissionItem, Plan, PlanKind
from uavviewer.plan.checks import outside_fence
from uavviewer.plan.model import FenceShape, PlanDocument
from uavviewer.plan.survey import SurveySpec

from test_mission_fence import square_fence
from test_mission_transfer import waypoint
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)

HOME = (47.397742, 8.545594)


def at(north: float, east: float) -> tuple[float, float]:
    return offset_latlon(*HOME, north, east)


def fenced_plan() -> PlanDocument:
    """A 100 m square inclusion polygon around home with a 10 m exclusion circle at 30 m north; a waypoint inside,
    one outside the square, one inside the circle, and a survey reaching out of the square to the east."""
    doc = PlanDocument()
    doc.fence = [FenceShape(True, tuple(at(n, e) for n, e in ((-50, -50), (50, -50), (50, 50), (-50, 50)))),
                 FenceShape(False, (at(30, 0),), 10.0)]
    doc.entries = [MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=10),
                   MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, lat=at(20, 20)[0], lon=at(20, 20)[1], alt=10),
                   MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, lat=at(80, 0)[0], lon=at(80, 0)[1], alt=10),
                   MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, lat=at(31, 2)[0], lon=at(31, 2)[1], alt=10),
                   SurveySpec(tuple(at(n, e) for n, e in ((-40, 10), (-10, 10), (-10, 90), (-40, 90))), altitude=20),
                   SurveySpec(tuple(at(n, e) for n, e in ((-40, -40), (-20, -40), (-20, -20), (-40, -20))),
                              altitude=20)]
    return doc


def test_every_waypoint_and_survey_leg_outside_the_fence_is_found():
    doc = fenced_plan()
    got = outside_fence(doc, [1, 2, 3, 4, 5, 30], HOME)
    assert set(got.rows) == {2, 3, 4}, got.rows            # the takeoff, the inside waypoint, the inside survey: fine
    assert got.rows[2] == "Item 3 is outside an inclusion polygon of the plan's fence: the vehicle would breach it there"
    assert got.rows[3].startswith("Item 4 is inside an exclusion circle")
    assert "legs leave the fence (outside an inclusion polygon)" in got.rows[4]
    assert len(got.points) == 2 and got.legs
    assert all(b[1] > at(0, 49)[1] or a[1] > at(0, 49)[1] for a, b in got.legs)   # the legs reaching east of it
    doc.fence = []
    assert outside_fence(doc, [1, 2, 3, 4, 5, 30], HOME).rows == {}                 # no fence, nothing to breach


def test_the_list_and_the_map_mark_them_before_the_upload(qtbot, vehicle, window_factory):
    w = window_factory(vehicle)
    plan = w.plan
    qtbot.waitUntil(lambda: plan.home is not None, timeout=15000)
    doc = fenced_plan()
    plan.editor.load(Plan(PlanKind.FENCE, doc.plan(PlanKind.FENCE).items))
    plan.editor.load_entries(doc.entries)
    table = plan.panel.tables["mission"]
    marked = {r for r in range(table.rowCount()) if table.item(r, 1).text().startswith("⚠")}
    assert marked == {2, 3, 4}
    assert "outside an inclusion polygon" in table.item(2, 1).toolTip()
    assert plan.layer.breaches.legs and len(plan.layer.breaches.points) == 2      # drawn red on the map


def upload_fence(qtbot, w, v) -> None:
    plan = w.plan
    plan.editor.load(square_fence(v, 40))
    plan.show_plan(True)
    plan.panel.tabs.setCurrentIndex(1)
    qtbot.mouseClick(plan.panel.uploadButton, Qt.LeftButton)


def test_a_fence_uploaded_while_it_is_off_says_so_and_turns_it_on_through_parameters(qtbot, vehicle, sim,
                                                                                     window_factory):
    w = window_factory(vehicle)
    qtbot.waitUntil(lambda: w.plan.home is not None and w.adapter.state.fence.enabled is False, timeout=15000)
    upload_fence(qtbot, w, vehicle)
    notices = w.plan.notices
    qtbot.waitUntil(lambda: notices.box is not None and notices.box.isVisible(), timeout=20000)
    assert notices.box.objectName() == "fenceOffQuestion" and "FENCE_ENABLE 0" in notices.box.text()
    assert "The vehicle's fence is off (FENCE_ENABLE 0)" in w.plan.panel.syncLabel.text()
    assert any("fence uploaded is not enforced" in t for t in w.messages.texts())
    assert notices.box.defaultButton() is notices.box.button(QMessageBox.Cancel)
    qtbot.mouseClick(notices.box.button(QMessageBox.Yes), Qt.LeftButton)
    qtbot.waitUntil(lambda: w.params.review is not None and w.params.review.isVisible(), timeout=10000)
    assert w.params.review.ticked() == ["FENCE_ENABLE"]
    qtbot.mouseClick(w.params.review.write_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.adapter.state.fence.enabled is True, timeout=15000)
    assert sim.autopilot.params["FENCE_ENABLE"] == 1
    qtbot.waitUntil(lambda: "fence is off" not in w.plan.panel.syncLabel.text(), timeout=5000)


def test_a_plan_without_a_fence_says_the_vehicle_keeps_its_own_and_offers_to_remove_it(
        qtbot, sim, vehicle, vehicle_factory, window_factory):
    other = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")   # another ground station put a fence there
    assert other.wait_for(lambda s: s.connected and s.home is not None, 15)
    assert other.upload_plan(square_fence(other, 40)).result(30).result.ok
    w = window_factory(vehicle)
    plan = w.plan
    qtbot.waitUntil(lambda: plan.home is not None, timeout=15000)
    plan.editor.load_entries([MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=10), waypoint(vehicle, 10, 10, 10)])
    plan.show_plan(True)
    assert plan.vehicle_plan(PlanKind.FENCE) is None             # what the vehicle holds is not known here
    qtbot.mouseClick(plan.panel.uploadButton, Qt.LeftButton)
    notices = plan.notices
    qtbot.waitUntil(lambda: notices.box is not None and notices.box.isVisible(), timeout=20000)
    assert notices.box.objectName() == "keptPlanQuestion"
    assert "keeps its fence from before (4 items)" in notices.box.text()
    assert any("keeps its fence from before" in t for t in w.messages.texts())
    assert len(plan.doc.plan(PlanKind.FENCE)) == 0               # read into what it holds, not into the plan
    qtbot.mouseClick(notices.box.button(QMessageBox.Yes), Qt.LeftButton)
    qtbot.waitUntil(lambda: plan.vehicle_plan(PlanKind.FENCE) is not None
                    and len(plan.vehicle_plan(PlanKind.FENCE)) == 0, timeout=20000)
    assert not sim.autopilot.plans[mavlink.MAV_MISSION_TYPE_FENCE]
    qtbot.waitUntil(lambda: plan.panel.syncLabel.text().startswith("Same as the vehicle's mission"), timeout=20000)
