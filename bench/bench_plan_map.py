#!/usr/bin/env python3
"""What the plan costs the map on the UI thread: one paint of the map with no plan, a 20-waypoint mission, a
200-waypoint one, and a 20-waypoint mission with a 1 ha survey at 30 m (the Solo's GoPro) and a fence; and the
survey generator's time for that survey and for a 25 ha one.

    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/bench_plan_map.py [--paints 300] [--write-docs]

Prints milliseconds per paint (median of five runs), the plan's extra cost, and both against the 33 ms of a
30 fps frame; the survey's passes, items and milliseconds to generate.
"""
from __future__ import annotations

import argparse
import math
import os
import statistics
import sys
import time
import tables  # bench/tables.py: this script runs from bench/

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

HOME = (47.0, 8.0)


def square(side: float, north: float = 20.0, east: float = 20.0) -> tuple:
    from driver.core.frames import offset_latlon
    return tuple(offset_latlon(*HOME, n, e) for n, e in
                 ((north, east), (north, east + side), (north + side, east + side), (north + side, east)))


def mission(doc, count: int) -> None:
    from driver.core.frames import offset_latlon
    from uavviewer.plan.model import ITEM_KINDS, new_item
    doc.entries[:] = [new_item(ITEM_KINDS["Takeoff"], alt=10.0)]
    for i in range(count):                               # a spiral out to ~150 m
        a, r = i * 0.6, 10.0 + 140.0 * i / max(1, count)
        doc.entries.append(new_item(ITEM_KINDS["Waypoint"], *offset_latlon(*HOME, r * math.cos(a), r * math.sin(a)),
                                    alt=15.0))
    doc.entries.append(new_item(ITEM_KINDS["RTL"]))


def timed_paints(view, paints: int) -> float:
    for _ in range(20):                                  # warm up: fonts, caches
        view.grab()
    runs = []
    for _ in range(5):
        t0 = time.perf_counter()
        for _ in range(paints // 5):
            view.grab()
        runs.append((time.perf_counter() - t0) / (paints // 5) * 1e3)
    return statistics.median(runs)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paints", type=int, default=300, help="paints timed for each plan")
    tables.add_write_docs(ap)
    args = ap.parse_args()
    from PyQt5.QtWidgets import QApplication
    app = QApplication(sys.argv[:1])  # noqa: F841 - the widgets need it
    from uavviewer.map.geometry import MapFrame
    from uavviewer.map.map_view import MapView
    from uavviewer.plan.layer import PlanLayer
    from uavviewer.plan.model import FenceShape, PlanDocument
    from uavviewer.plan.survey import SurveySpec, survey

    view = MapView()
    view.resize(500, 330)
    view.frame, view.mpp, view.home_visible = MapFrame(*HOME), 0.6, True
    view.set_vehicle((0.0, 0.0, 30.0))
    doc = PlanDocument()
    layer = PlanLayer(doc)
    layer.home = HOME
    layer.attach(view)

    def with_survey() -> None:
        mission(doc, 20)
        doc.entries.insert(-1, SurveySpec(square(100.0), altitude=30.0))
        doc.fence[:] = [FenceShape(True, square(300.0, -150.0, -150.0))]

    cases = [("no plan", lambda: None), ("20 waypoints", lambda: mission(doc, 20)),
             ("200 waypoints", lambda: mission(doc, 200)), ("20 + survey + fence", with_survey)]
    print(f"{'plan':>20} | {'items':>5} | {'paint ms':>8} | {'extra ms':>8} | {'% of 33 ms':>10}")
    base = None
    for name, build in cases:
        build()
        ms = timed_paints(view, args.paints)
        base = ms if base is None else base
        print(f"{name:>20} | {len(doc.plan()):>5} | {ms:>8.3f} | {ms - base:>8.3f} | {100 * ms / 33.3:>9.1f} %")
    print()
    print(f"{'survey':>20} | {'passes':>6} | {'items':>5} | {'photos':>6} | {'ms':>6}")
    for side, label in ((100.0, "1 ha at 30 m"), (500.0, "25 ha at 30 m")):
        spec = SurveySpec(square(side), altitude=30.0)
        t0 = time.perf_counter()
        for _ in range(50):
            s = survey(spec)
        ms = (time.perf_counter() - t0) / 50 * 1e3
        print(f"{label:>20} | {len(s.passes):>6} | {len(s.items):>5} | {s.photos:>6} | {ms:>6.3f}")
    return 0


if __name__ == "__main__":
    with tables.publishing("plan_map"):
        sys.exit(main())
