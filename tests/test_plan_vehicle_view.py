"""What the Plan panel shows of the vehicle, read from its view model without Qt: the vehicle's snapshot and the plan
being edited in, texts and buttons (enabled, or why not) out, the same whatever was updated first."""
from __future__ import annotations

from dataclasses import replace

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.mission.plan import (MissionItem, MissionProgress, MissionRunState, Plan, PlanKind, TransferDirection,
                                 TransferProgress)
from driver.vehicle.state import Fence, LandedState, LinkHealth, LinkStatus, VehicleState
from uavviewer.plan.vehicle_view import PlanFacts, vehicle_view

WP = mavlink.MAV_CMD_NAV_WAYPOINT
MISSION = Plan(PlanKind.MISSION, (MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=10.0),
                                  MissionItem(WP, lat=-35.3620, lon=149.1650, alt=20.0),
                                  MissionItem(WP, lat=-35.3630, lon=149.1660, alt=20.0),
                                  MissionItem(mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH)))
FENCE = Plan(PlanKind.FENCE, (MissionItem(mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION, param1=200.0,
                                          lat=-35.3632, lon=149.1652),))
NOTHING = {k: Plan(k, ()) for k in PlanKind}


def vehicle(mode: str = "LOITER", flying: bool = False, link: LinkStatus = LinkStatus.OK, **mission) -> VehicleState:
    """A vehicle holding MISSION (as read back), in ``mode``, in the air or on the ground."""
    progress = MissionProgress(**{"count": 4, "state": MissionRunState.NOT_STARTED, "on_vehicle": (MISSION,),
                                  **mission})
    return VehicleState(link=LinkHealth(status=link), mode=mode, armed=flying,
                        landed_state=LandedState.IN_AIR if flying else LandedState.ON_GROUND, mission=progress)


def facts(shown: PlanKind = PlanKind.MISSION, here: Plan = MISSION, **more) -> PlanFacts:
    """The plan here: the vehicle's mission, sent and read back the same, unless ``here`` replaces its kind's."""
    plans = {**NOTHING, PlanKind.MISSION: MISSION, here.kind: here}
    synced = {PlanKind.MISSION: (MISSION, MISSION)} if plans[PlanKind.MISSION] == MISSION else {}
    return PlanFacts(**{"shown": shown, "here": plans, "confirmed": {}, "synced": synced, "outcomes": {}, **more})


def test_a_mission_on_the_ground_may_be_started_and_the_transfers_are_free():
    view = vehicle_view(vehicle(), facts())
    assert view.start.enabled and view.upload.enabled and view.download.enabled and view.remove.enabled
    assert not view.pause.enabled and view.pause.why_not == "The mission is not flying"
    assert not view.resume.enabled and view.resume.why_not == "No mission paused"
    assert not view.cancel.enabled and view.skip.enabled
    assert view.tab_titles == ("Mission", "Fence", "Rally") and not view.warning
    assert view.comparison == "Same as the vehicle's mission (4 items)"
    assert view.progress == "Mission of 4 items on the vehicle, not flying" and view.on_map == ""
    assert view.current is None and view.transfer.text == "No transfer yet" and not view.transfer.active


def test_a_mission_flying_may_be_paused_and_its_item_is_marked():
    view = vehicle_view(vehicle("AUTO", flying=True, current=2, state=MissionRunState.ACTIVE), facts())
    assert view.pause.enabled and not view.start.enabled and view.start.why_not == "The mission is flying"
    assert not view.resume.enabled
    assert view.current == 2 and view.progress.startswith("Item 2 of 4") and view.on_map == view.progress


def test_a_mission_held_in_another_mode_may_be_resumed():
    view = vehicle_view(vehicle("BRAKE", flying=True, current=3, state=MissionRunState.PAUSED), facts())
    assert view.resume.enabled and not view.pause.enabled and view.start.enabled
    assert "paused (BRAKE)" in view.progress and view.current == 3 and view.on_map == view.progress


def test_no_item_is_marked_on_a_plan_that_is_not_the_vehicles():
    """The vehicle flies its own mission: its item 2 is not the second row of another plan."""
    edited = replace(MISSION, items=MISSION.items[:2])
    view = vehicle_view(vehicle("AUTO", flying=True, current=2, state=MissionRunState.ACTIVE), facts(here=edited))
    assert view.current is None and view.pause.enabled                 # the vehicle's mission can still be paused
    assert view.tab_titles[0] == "● Mission" and view.warning
    assert view.comparison == "Differs from the vehicle's: 4 items there, 2 here"


def test_without_a_link_no_button_asks_the_vehicle_and_each_says_why():
    view = vehicle_view(vehicle(link=LinkStatus.LOST), facts())
    for button in (view.upload, view.download, view.remove, view.start, view.pause, view.resume, view.skip):
        assert not button.enabled and button.why_not == "No link to the vehicle"


def test_a_recording_is_only_watched():
    view = vehicle_view(vehicle(), facts(replaying=True))
    assert not view.upload.enabled and view.upload.why_not == "A recording is only watched"
    assert not view.start.enabled and not view.skip.enabled


def test_a_transfer_under_way_holds_the_others_and_may_be_cancelled():
    """Whatever the link did meanwhile: the buttons follow from the snapshot, not from what they showed before."""
    upload = TransferProgress(PlanKind.MISSION, TransferDirection.UPLOAD, done=3, total=8, detail="re-asking item 4")
    busy = vehicle(transfers=(upload,))
    view = vehicle_view(busy, facts())
    assert view.transfer.text == "Uploading 3/8 · re-asking item 4" and view.transfer.active
    assert (view.transfer.done, view.transfer.total) == (3, 8) and view.cancel.enabled
    for button in (view.upload, view.download, view.remove):
        assert not button.enabled and button.why_not == "A transfer is under way"
    lost_then_back = vehicle_view(replace(busy, link=LinkHealth(status=LinkStatus.LOST)), facts())
    assert lost_then_back.upload.why_not == "No link to the vehicle"
    assert vehicle_view(busy, facts()) == view                         # the same snapshot, the same panel
    done = vehicle_view(vehicle(), facts(outcomes={PlanKind.MISSION: "upload mission: accepted"}))
    assert done.upload.enabled and not done.cancel.enabled and done.transfer.text == "upload mission: accepted"


def test_the_limits_the_driver_found_keep_the_mission_from_starting_and_say_so():
    problem = "item 2 (WAYPOINT): 900 m from home, beyond the 500 m fence"
    view = vehicle_view(vehicle(limit_problems=(problem,)), facts())
    assert not view.start.enabled and view.start.why_not == f"Not started: the mission's {problem}"
    assert view.skip.enabled                                           # the vehicle's items may still be picked


def test_a_failed_transfer_is_said_first_and_in_amber():
    refused = "upload mission: refused (MAV_MISSION_NO_SPACE)"
    view = vehicle_view(vehicle(), facts(outcomes={PlanKind.MISSION: refused}, failed=frozenset({PlanKind.MISSION})))
    assert view.comparison == f"{refused}. Same as the vehicle's mission (4 items)" and view.warning


def test_the_fence_tab_says_the_vehicles_fence_is_off():
    off = replace(vehicle(), fence=Fence(enabled=False))
    view = vehicle_view(off, facts(PlanKind.FENCE, here=FENCE))
    assert view.comparison == ("Differs from the vehicle's: the vehicle's fence is not known yet (Download reads it)."
                               " The vehicle's fence is off (FENCE_ENABLE 0)") and view.warning
    assert view.tab_titles == ("Mission", "● Fence", "Rally")
    assert "fence is off" not in vehicle_view(off, facts(PlanKind.RALLY)).comparison   # said on its own tab only


def test_nothing_known_of_the_vehicle_yet():
    s = VehicleState(link=LinkHealth(status=LinkStatus.OK))
    view = vehicle_view(s, facts(here=NOTHING[PlanKind.MISSION]))
    assert view.comparison == "No mission here; the vehicle's is not known yet"
    assert not view.start.enabled and view.start.why_not == "No mission on the vehicle" and not view.skip.enabled
    assert view.progress == "Mission: the vehicle has not said yet"


def test_the_panel_shows_the_view_all_at_once_and_a_disabled_button_says_why(qtbot):
    from uavviewer.plan.panel import PlanPanel
    panel = PlanPanel()
    qtbot.addWidget(panel)
    does = panel.uploadButton.toolTip()
    panel.show_vehicle(vehicle_view(vehicle(link=LinkStatus.LOST), facts()))
    assert not panel.uploadButton.isEnabled() and panel.uploadButton.toolTip() == f"{does}\nNo link to the vehicle"
    assert panel.startButton.toolTip() == "No link to the vehicle" and not panel.skip_allowed
    panel.show_vehicle(vehicle_view(vehicle("AUTO", flying=True, current=2, state=MissionRunState.ACTIVE), facts()))
    assert panel.uploadButton.isEnabled() and panel.uploadButton.toolTip() == does
    assert panel.pauseButton.isEnabled() and not panel.startButton.isEnabled() and panel.skip_allowed
    assert panel.startButton.toolTip() == "The mission is flying"
    assert panel.progressLabel.text().startswith("Item 2 of 4") and panel.tabs.tabText(0) == "Mission"
