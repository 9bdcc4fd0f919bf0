"""Plan files: QGroundControl's .plan and QGC WPL 110 round-trip; a WPL we write loads in pymavlink's mavwp."""
from __future__ import annotations

import json
import math

import pytest
from pymavlink import mavwp
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.mission.files import PlanFileError, load_plan_file, save_plan_file
from driver.mission.plan import MissionItem, Plan, PlanKind

HOME = (-35.363261, 149.165230, 584.09)


def mission() -> Plan:
    return Plan(PlanKind.MISSION, (
        MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=10),
        MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, param1=2, lat=-35.3629915, lon=149.1652299, alt=10),
        MissionItem(mavlink.MAV_CMD_DO_CHANGE_SPEED, frame=mavlink.MAV_FRAME_MISSION, param1=1, param2=3, param3=-1),
        MissionItem(mavlink.MAV_CMD_NAV_LOITER_TIME, param1=3, param3=1, lat=-35.363261, lon=149.1655603, alt=12),
        MissionItem(mavlink.MAV_CMD_CONDITION_YAW, frame=mavlink.MAV_FRAME_MISSION, param1=90, param4=math.nan),
        MissionItem(mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH, frame=mavlink.MAV_FRAME_MISSION),
    ))


def fence() -> Plan:
    corners = ((-35.3636203, 149.1647892), (-35.3629016, 149.1647892), (-35.362722, 149.1658908),
               (-35.3636203, 149.1656705))
    items = tuple(MissionItem(mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION, mavlink.MAV_FRAME_GLOBAL, 4,
                              lat=lat, lon=lon) for lat, lon in corners)
    return Plan(PlanKind.FENCE, items + (MissionItem(mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION,
                                                     mavlink.MAV_FRAME_GLOBAL, 5, lat=-35.3635484, lon=149.1648774),))


def rally() -> Plan:
    return Plan(PlanKind.RALLY, (MissionItem(mavlink.MAV_CMD_NAV_RALLY_POINT, lat=-35.3634406, lon=149.1654502,
                                             alt=15),))


def same(a: Plan, b: Plan) -> bool:
    return a.kind is b.kind and len(a) == len(b) and all(
        x.command == y.command and x.frame == y.frame and x.autocontinue == y.autocontinue
        and all((math.isnan(p) and math.isnan(q)) or p == pytest.approx(q) for p, q in zip(x.params, y.params))
        and (x.lat, x.lon, x.alt) == pytest.approx((y.lat, y.lon, y.alt), abs=1e-7) for x, y in zip(a.items, b.items))


def test_qgc_plan_round_trips_every_plan_and_home(tmp_path):
    path = tmp_path / "flight.plan"
    save_plan_file(path, (mission(), fence(), rally()), HOME)
    data = json.loads(path.read_text())
    assert data["fileType"] == "Plan" and len(data["geoFence"]["polygons"]) == 1
    assert data["mission"]["items"][4]["params"][3] is None                # NaN is null, as QGC writes it
    loaded = load_plan_file(path)
    assert loaded.home == pytest.approx(HOME)
    for plan in (mission(), fence(), rally()):
        assert same(loaded.plan(plan.kind), plan), plan.kind


def test_qgc_survey_items_are_read_as_their_waypoints(tmp_path):
    data = json.loads(json.dumps({"fileType": "Plan", "mission": {"items": [
        {"type": "ComplexItem", "complexItemType": "survey", "TransectStyleComplexItem": {"Items": [
            {"type": "SimpleItem", "command": 16, "frame": 3, "params": [0, 0, 0, None, -35.36, 149.16, 30]},
            {"type": "SimpleItem", "command": 206, "frame": 2, "params": [25, 0, 1, 0, 0, 0, 0]}]}}]}}))
    (tmp_path / "survey.plan").write_text(json.dumps(data))
    plan = load_plan_file(tmp_path / "survey.plan").plan(PlanKind.MISSION)
    assert [i.command for i in plan.items] == [16, 206]


def test_a_complex_item_keeps_its_settings_and_is_written_back_as_one(tmp_path):
    """A QGroundControl survey: read as its waypoints, and where they are with its own settings (polygon, camera);
    saved again, it is a ComplexItem again, its settings as they were."""
    survey = {"type": "ComplexItem", "complexItemType": "survey", "version": 5, "angle": 30,
              "polygon": [[-35.36, 149.16], [-35.36, 149.17], [-35.37, 149.17]],
              "TransectStyleComplexItem": {"CameraCalc": {"DistanceToSurface": 30, "CameraName": "Sony"}, "Items": [
                  {"type": "SimpleItem", "command": 16, "frame": 3, "params": [0, 0, 0, None, -35.36, 149.16, 30]},
                  {"type": "SimpleItem", "command": 206, "frame": 2, "params": [25, 0, 1, 0, 0, 0, 0]}]}}
    takeoff = {"type": "SimpleItem", "command": 22, "frame": 3, "params": [0, 0, 0, None, 0, 0, 10]}
    (tmp_path / "in.plan").write_text(json.dumps({"fileType": "Plan", "mission": {"items": [takeoff, survey]}}))
    got = load_plan_file(tmp_path / "in.plan")
    assert [i.command for i in got.plan(PlanKind.MISSION).items] == [22, 16, 206]
    (group,) = got.complex_items
    assert (group.start, group.count, group.kind) == (1, 2, "survey")
    assert group.settings["polygon"] == survey["polygon"] and group.settings["angle"] == 30
    assert group.settings["TransectStyleComplexItem"]["CameraCalc"]["CameraName"] == "Sony"
    assert "Items" not in group.settings["TransectStyleComplexItem"]
    save_plan_file(tmp_path / "out.plan", got.plans, got.home, got.complex_items)
    items = json.loads((tmp_path / "out.plan").read_text())["mission"]["items"]
    assert [i["type"] for i in items] == ["SimpleItem", "ComplexItem"]
    out = items[1]
    assert out["complexItemType"] == "survey" and out["polygon"] == survey["polygon"] and out["angle"] == 30
    assert [i["command"] for i in out["TransectStyleComplexItem"]["Items"]] == [16, 206]
    assert load_plan_file(tmp_path / "out.plan") == got
    # a structure scan carries its items at its top: written back the same way
    scan = {"type": "ComplexItem", "complexItemType": "StructureScan", "Altitude": 20,
            "Items": survey["TransectStyleComplexItem"]["Items"]}
    (tmp_path / "scan.plan").write_text(json.dumps({"fileType": "Plan", "mission": {"items": [scan]}}))
    got = load_plan_file(tmp_path / "scan.plan")
    save_plan_file(tmp_path / "scan-out.plan", got.plans, got.home, got.complex_items)
    (out,) = json.loads((tmp_path / "scan-out.plan").read_text())["mission"]["items"]
    assert out["Altitude"] == 20 and len(out["Items"]) == 2 and "TransectStyleComplexItem" not in out


def test_wpl_round_trips_and_loads_in_pymavlink(tmp_path):
    path = tmp_path / "mission.waypoints"
    save_plan_file(path, (mission(),), HOME)
    assert path.read_text().startswith("QGC WPL 110\n0\t1\t0\t16\t")
    loaded = load_plan_file(path)
    assert same(loaded.plan(PlanKind.MISSION), mission()) and loaded.home == pytest.approx(HOME)
    loader = mavwp.MAVWPLoader()
    assert loader.load(str(path)) == 7                                     # home slot + 6
    assert loader.wp(1).command == mavlink.MAV_CMD_NAV_TAKEOFF and loader.wp(2).x == pytest.approx(-35.3629915)
    fence_path = tmp_path / "fence.txt"
    save_plan_file(fence_path, (fence(),))
    assert same(load_plan_file(fence_path).plan(PlanKind.FENCE), fence())


def test_bad_files_say_why(tmp_path):
    (tmp_path / "a.plan").write_text('{"fileType": "KML"}')
    with pytest.raises(PlanFileError, match="not a QGroundControl plan"):
        load_plan_file(tmp_path / "a.plan")
    (tmp_path / "b.txt").write_text("QGC WPL 110\n0\t1\t0\t16\t0\t0\n")
    with pytest.raises(PlanFileError, match="line 2: 6 fields"):
        load_plan_file(tmp_path / "b.txt")
    with pytest.raises(PlanFileError, match="holds one plan"):
        save_plan_file(tmp_path / "c.waypoints", (mission(), fence()))
