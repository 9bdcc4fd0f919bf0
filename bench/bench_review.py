#!/usr/bin/env python3
"""Review figures (issue 31): a large DataFlash .BIN opened to its tree, and one field plotted.

    QT_QPA_PLATFORM=offscreen python bench/bench_review.py [--mb 100] [--keep FILE] [--write-docs]

The log is made here with driver.review.writer (FMT + records in ArduCopter's layouts: ATT, CTUN, BAT, VIBE, GPS,
MODE, EV, ERR, MSG, PARM), grown to the size asked. Printed: its size and records, the time to open it to its tree
(index), the time to read ATT.Roll, and to read and draw it in a pyqtgraph plot (the window painted), the peak
memory allocated while opening it again to its tree (tracemalloc, numpy's arrays included; the memory-mapped file
itself is not counted), plus pymavlink's DFReader_binary opening the same file for comparison (skipped above
--dfreader-mb).
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
import tables  # bench/tables.py: this script runs from bench/

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)


def make_log(path: str, mb: float) -> None:
    from driver.review.writer import sample_flight
    rate = 50.0
    seconds = 60.0
    w = sample_flight(seconds=seconds, rate_hz=rate)
    per_second = len(w.bytes()) / seconds
    w = sample_flight(seconds=mb * 1e6 / per_second, rate_hz=rate)
    w.save(path)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--mb", type=float, default=100.0)
    ap.add_argument("--keep", default="")
    ap.add_argument("--dfreader-mb", type=float, default=30.0)
    tables.add_write_docs(ap)
    args = ap.parse_args()
    path = args.keep or os.path.join(tempfile.mkdtemp(), "large.BIN")
    if not os.path.exists(path):
        t = time.perf_counter()
        make_log(path, args.mb)
        print(f"made {path} in {time.perf_counter() - t:.1f} s")
    size = os.path.getsize(path)

    from driver.review import open_log
    t = time.perf_counter()
    log = open_log(path)
    tree = log.tree()
    opened = time.perf_counter() - t
    records = sum(log.count(n) for n in tree)
    print(f"log: {size / 1e6:.1f} MB, {records:,} records, {len(tree)} types")
    print(f"open to its tree (index): {opened:.2f} s")
    t = time.perf_counter()
    x, y = log.series("ATT", "Roll")
    read = time.perf_counter() - t
    print(f"read ATT.Roll ({len(y):,} points): {read:.3f} s")

    from PyQt5.QtWidgets import QApplication
    import pyqtgraph as pg
    app = QApplication.instance() or QApplication([])
    plot = pg.PlotWidget()
    plot.resize(1200, 500)
    plot.show()
    app.processEvents()
    t = time.perf_counter()
    x, y = log.series("ATT", "DesRoll")
    curve = plot.plot(x, y)
    curve.setDownsampling(auto=True, method="peak")
    curve.setClipToView(True)
    plot.grab()
    app.processEvents()
    drawn = time.perf_counter() - t
    print(f"read and draw ATT.DesRoll: {drawn:.3f} s")
    t = time.perf_counter()
    events = log.events()
    print(f"events ({len(events)}): {(time.perf_counter() - t) * 1000:.1f} ms", end="; ")
    t = time.perf_counter()
    log.flight_path()
    print(f"path {time.perf_counter() - t:.3f} s")
    import tracemalloc
    tracemalloc.start()
    again = open_log(path)
    again.tree()
    _now, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    again.close()
    print(f"peak memory opening to its tree (tracemalloc): {peak / 1e6:.0f} MB")
    if size / 1e6 <= args.dfreader_mb:
        from pymavlink import DFReader
        t = time.perf_counter()
        DFReader.DFReader_binary(path)
        print(f"pymavlink DFReader_binary open (its index): {time.perf_counter() - t:.2f} s")
    log.close()
    if not args.keep:
        os.remove(path)


if __name__ == "__main__":
    with tables.publishing("review"):
        main()
