"""The plan being edited and the survey generator, without Qt: numbers checked against hand calculations."""
from __future__ import annotations

import math
from dataclasses import replace

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.core.frames import offset_latlon, offset_ned
from driver.mission.plan import MissionItem, Plan, PlanKind
from driver.params.model import Parameter, ParameterTable
from uavviewer.plan.model import (
    ITEM_KINDS, FenceShape, Performance, PlanDocument, new_item,
)
from uavviewer.plan.survey import CAMERAS, GOPRO_HERO4_BLACK, SurveySpec, survey

HOME = (40.2839, -3.7940)


def at(north: float, east: float) -> tuple[float, float]:
    return offset_latlon(*HOME, north, east)


def square(n0: float, e0: float, size_n: float, size_e: float) -> tuple:
    return (at(n0, e0), at(n0, e0 + size_e), at(n0 + size_n, e0 + size_e), at(n0 + size_n, e0))


def test_gopro_hero4_black_footprint_and_ground_sample_distance():
    cam = GOPRO_HERO4_BLACK
    assert cam in CAMERAS and CAMERAS[0] is cam and "HERO4 Black" in cam.name
    assert (cam.sensor_width, cam.sensor_height, cam.image_width, cam.image_height, cam.focal_length) == \
        (6.17, 4.55, 4000, 3000, 2.98)
    across, along = cam.footprint(30.0)
    assert across == pytest.approx(30 * 6.17 / 2.98) and along == pytest.approx(30 * 4.55 / 2.98)   # 62.1 x 45.8 m
    # the worse axis: 6.17 mm / 4000 px (1.54 um) against 4.55 mm / 3000 px (1.52 um): 1.55 cm a pixel at 30 m
    assert cam.gsd(30.0) == pytest.approx(100 * 30 * (6.17 / 4000) / 2.98) == pytest.approx(1.553, abs=1e-3)


def test_survey_lawnmower_covers_the_area_with_camera_on_each_pass_only():
    spec = SurveySpec(square(0, 0, 100, 200), altitude=30.0, front_overlap=0.7, side_overlap=0.6, angle=90.0)
    s = survey(spec)
    across, along = GOPRO_HERO4_BLACK.footprint(30.0)
    assert s.spacing == pytest.approx(across * 0.4) and s.trigger_distance == pytest.approx(along * 0.3)
    assert len(s.passes) == math.ceil(100 / s.spacing)                 # passes east-west, stacked north
    assert s.area == pytest.approx(20000, rel=1e-3)
    # every pass spans the area east to west, alternating, inside the area's north extent
    for k, (a, b) in enumerate(s.passes):
        (na, ea), (nb, eb) = offset_ned(*HOME, *a), offset_ned(*HOME, *b)
        assert na == pytest.approx(nb, abs=0.01) and 0 < na < 100
        assert sorted((ea, eb)) == pytest.approx([0, 200], abs=0.05)
        assert (ea < eb) == (k % 2 == 0)
    # the items: entry, camera on at the trigger distance (first photo at once), exit, camera off
    cmds = [i.command for i in s.items]
    assert cmds == [mavlink.MAV_CMD_NAV_WAYPOINT, mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST] * 2 * len(s.passes)
    on, off = s.items[1], s.items[3]
    assert (on.param1, on.param3) == (pytest.approx(s.trigger_distance), 1.0) and off.param1 == 0.0
    assert on.frame == mavlink.MAV_FRAME_MISSION and all(i.alt == 30.0 for i in s.items[::2])
    assert s.length == pytest.approx(200 * len(s.passes), abs=0.5)
    assert s.photos == len(s.passes) * (int(200 // s.trigger_distance) + 1)


def test_survey_of_a_concave_area_and_nonsense():
    # an L: the passes cross the notch, never leave the bounding extent
    ell = (at(0, 0), at(0, 100), at(40, 100), at(40, 40), at(100, 40), at(100, 0))
    s = survey(SurveySpec(ell, altitude=40.0, angle=0.0))
    assert s.passes and all(-0.5 <= offset_ned(*HOME, *p)[1] <= 100.5 for ab in s.passes for p in ab)
    assert survey(SurveySpec(ell[:2])).items == ()                       # two corners: no area
    assert survey(SurveySpec(ell, altitude=float("nan"))).items == ()


def test_speed_is_a_change_speed_item_before_the_waypoint_and_totals_add_up():
    doc = PlanDocument()
    doc.entries += [new_item(ITEM_KINDS["Takeoff"], alt=10.0),
                    new_item(ITEM_KINDS["Waypoint"], *at(100, 0), alt=10.0),
                    new_item(ITEM_KINDS["Waypoint"], *at(100, 100), alt=10.0),
                    new_item(ITEM_KINDS["RTL"])]
    assert doc.set_speed(2, 2.0) == 3                                    # a DO_CHANGE_SPEED went in before it
    assert doc.entries[2].command == mavlink.MAV_CMD_DO_CHANGE_SPEED and doc.entries[2].param2 == 2.0
    assert doc.leg_speeds(5.0) == [5.0, 5.0, 5.0, 2.0, 2.0]
    assert doc.set_speed(3, 3.0) == 3 and doc.entries[2].param2 == 3.0   # edited, not another one
    doc.set_hold(1, 4.0)
    perf = Performance(cruise=5.0, climb=2.5, descent=1.5, land_speed=0.5, rtl_alt=15.0, capacity_mah=5200,
                       hover_amps=15.0, amps_per_ms=0.6)
    t = doc.totals(HOME, perf)
    assert t.distance == pytest.approx(100 + 100 + math.hypot(100, 100), abs=0.1)
    # climb 10 m at 2.5; 100 m at 5; hold 4; 100 m at 3; RTL: climb 5 m at 2.5, 141 m at 3, 5 m down at 1.5
    # then the last 10 m at 0.5
    expected = 4 + 20 + 4 + 100 / 3 + 2 + math.hypot(100, 100) / 3 + 5 / 1.5 + 10 / 0.5
    assert t.time == pytest.approx(expected, rel=1e-3)
    assert t.percent == pytest.approx(100 * t.mah / 5200) and 15 * t.time / 3.6 < t.mah < 17 * t.time / 3.6
    assert doc.set_speed(3, None) == 2 and len(doc.entries) == 4          # cleared: the item went
    assert not t.beyond_reserve and "reserve" not in t.text()
    # the same plan on a small pack: beyond the 20 % reserve, said in the totals
    small = doc.totals(HOME, replace(perf, capacity_mah=doc.totals(HOME, perf).mah / 0.85))
    assert small.percent == pytest.approx(85) and small.beyond_reserve and "with a 20 % reserve" in small.text()


def test_vehicle_parameters_replace_the_defaults():
    table = ParameterTable(values={n: Parameter(n, v) for n, v in
                                   (("WPNAV_SPEED", 1000.0), ("BATT_CAPACITY", 3000.0), ("RTL_ALT", 3000.0))})
    perf = Performance.from_parameters(table)
    assert (perf.cruise, perf.capacity_mah, perf.rtl_alt, perf.climb) == (10.0, 3000.0, 30.0, 2.5)


def test_plans_out_and_back():
    doc = PlanDocument()
    doc.entries += [new_item(ITEM_KINDS["Takeoff"], alt=10.0), SurveySpec(square(10, 10, 60, 60), altitude=25.0),
                    new_item(ITEM_KINDS["ROI"], *at(5, 5), alt=0.0), new_item(ITEM_KINDS["Land"])]
    plan = doc.plan()
    assert plan.kind is PlanKind.MISSION and len(plan) == 1 + len(survey(doc.entries[1]).items) + 2
    assert doc.entry_of_seq(1) == 0 and doc.entry_of_seq(2) == 1 and doc.entry_of_seq(len(plan)) == 3
    assert doc.first_seq(3) == len(plan)
    doc.fence = [FenceShape(True, square(-50, -50, 100, 100)), FenceShape(False, (at(20, 20),), 10.0)]
    doc.rally = [MissionItem(mavlink.MAV_CMD_NAV_RALLY_POINT, lat=at(-10, 0)[0], lon=at(-10, 0)[1], alt=15.0)]
    fence = doc.plan(PlanKind.FENCE)
    assert [i.command for i in fence.items] == [mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION] * 4 + \
        [mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION]
    assert all(i.param1 == 4 for i in fence.items[:4]) and fence.items[4].param1 == 10.0
    other = PlanDocument()
    for kind in PlanKind:
        other.load(doc.plan(kind))
    assert other.fence == doc.fence and other.rally == doc.rally
    assert other.plan(PlanKind.FENCE) == fence and other.plan(PlanKind.MISSION) == Plan(PlanKind.MISSION, plan.items)
