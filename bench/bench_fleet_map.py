#!/usr/bin/env python3
"""What showing the fleet costs the map on the UI thread: placing the other vehicles (``fleet_marks``, done at the
Fleet panel's 4 Hz) and one paint of the map with 0, 3 and 10 other vehicles.

    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/bench_fleet_map.py [--paints 300] [--write-docs]

Prints microseconds per placement and milliseconds per paint (median of the runs), the paint's extra cost per
vehicle, and both against the 33 ms of a 30 fps frame.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
import tables  # bench/tables.py: this script runs from bench/

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)


def fleet(count: int):
    """``count`` vehicles (the first picked) 10 m apart eastwards and 5 m northwards, as the Fleet panel reads them."""
    from driver.core import frames
    from driver.vehicle.state import GlobalPosition, VehicleState
    from uavviewer.fleet.controller import row_for
    seen = []
    for i in range(count):
        lat, lon = frames.offset_latlon(47.0, 8.0, 5.0 * i, 10.0 * i)
        s = VehicleState(position=GlobalPosition(lat, lon, 400.0), heading_deg=30.0 * i)
        seen.append((row_for(f"solo-{i + 1}", s, i == 0, True), s))
    return tuple(seen)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paints", type=int, default=300, help="paints timed for each fleet size")
    tables.add_write_docs(ap)
    args = ap.parse_args()
    from PyQt5.QtWidgets import QApplication
    app = QApplication(sys.argv[:1])  # noqa: F841 - the widgets need it
    from uavviewer.map.geometry import MapFrame
    from uavviewer.map.controller import fleet_marks
    from uavviewer.map.map_view import MapView

    frame = MapFrame(47.0, 8.0)
    view = MapView()
    view.resize(460, 330)
    view.frame, view.mpp, view.home_visible = frame, 0.25, True
    view.set_vehicle((0.0, 0.0, 30.0))
    base = None
    print(f"{'others':>6} | {'placing us':>10} | {'paint ms':>8} | {'extra ms':>8} | {'% of 33 ms':>10}")
    for others in (0, 3, 10):
        seen = fleet(others + 1)
        t0 = time.perf_counter()
        for _ in range(2000):
            marks = fleet_marks(frame, seen)
        placing = (time.perf_counter() - t0) / 2000 * 1e6
        view.set_fleet("solo-1" if others else "", False, marks)
        for _ in range(20):                                   # warm up: fonts, caches
            view.grab()
        runs = []
        for _ in range(5):
            t0 = time.perf_counter()
            for _ in range(args.paints // 5):
                view.grab()
            runs.append((time.perf_counter() - t0) / (args.paints // 5) * 1e3)
        paint = statistics.median(runs)
        base = paint if base is None else base
        print(f"{others:>6} | {placing:>10.1f} | {paint:>8.3f} | {paint - base:>8.3f} | {100 * paint / 33.3:>9.1f} %")
    return 0


if __name__ == "__main__":
    with tables.publishing("fleet_map"):
        sys.exit(main())
