#!/usr/bin/env python3
"""How the Parameters page copes with ArduCopter's 1,392 parameters (the recorded list, real names and types).

    QT_QPA_PLATFORM=offscreen python bench/bench_params_page.py [--write-docs]

With ArduCopter's metadata (the shipped apm.pdef.xml). Prints, in milliseconds of UI-thread time: the list arriving in 28 steps of ~50 (as a download grows it, each
step a new ParameterTable), one value changing (the echo of a write), each keystroke of a search
("W", "WP", ..., "WPNAV_SPEED"), a group picked, and the page's first showing with every row.
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
sys.path.insert(0, os.path.join(ROOT, "tests"))


def recorded_parameters():
    """Every PARAM_VALUE of the recorded list, in the order the vehicle sent them."""
    from pymavlink import mavutil

    from driver.params.model import Parameter, ParamType
    from recordings import PARAMS
    log = mavutil.mavlink_connection(PARAMS + ".tlog", dialect="ardupilotmega")
    found: dict[str, Parameter] = {}
    while (m := log.recv_match(type="PARAM_VALUE")) is not None:
        if m.param_index != 65535 and m.param_id not in found:
            found[m.param_id] = Parameter(m.param_id, m.param_value, ParamType(m.param_type), m.param_index)
    return list(found.values())


def ms(f) -> float:
    t = time.perf_counter()
    f()
    return (time.perf_counter() - t) * 1000


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    tables.add_write_docs(parser)
    parser.parse_args()
    from dataclasses import replace
    import types

    from PyQt5.QtWidgets import QApplication

    from driver.params.model import ParameterTable
    from uavviewer.main_window import load_style
    from uavviewer.params.page import ParametersPage
    from uavviewer.params.table_model import ParameterModel

    app = QApplication(sys.argv[:1])
    app.setStyleSheet(load_style())
    from driver.params.metadata import load_metadata
    params = recorded_parameters()
    model = ParameterModel()
    model.set_metadata(load_metadata())          # ArduCopter's shipped apm.pdef.xml: searched descriptions too
    page = ParametersPage(model)
    page.resize(1366, 700)
    page.show()
    app.processEvents()

    steps, values = [], {}
    for start in range(0, len(params), 50):
        values.update({p.name: p for p in params[start:start + 50]})
        table = ParameterTable(types.MappingProxyType(dict(values)), expected=len(params), downloading=True)
        steps.append(ms(lambda: (model.set_table(table), page.show_download(table, True), app.processEvents())))
    print(f"{len(params)} parameters ({len(steps)} download steps): per step median "
          f"{statistics.median(steps):.1f} ms, max {max(steps):.1f} ms")

    one = params[len(params) // 2]
    changed = dict(values)
    changed[one.name] = replace(one, value=one.value + 1)
    table = ParameterTable(types.MappingProxyType(changed), expected=len(params))
    print(f"one value changed (a write's echo): {ms(lambda: (model.set_table(table), app.processEvents())):.1f} ms")

    keys = [ms(lambda n=n: (page.search.setText("WPNAV_SPEED"[:n]), app.processEvents())) for n in range(1, 12)]
    print(f"search, per keystroke of 'WPNAV_SPEED': median {statistics.median(keys):.1f} ms, max {max(keys):.1f} ms"
          f" ({len(page.visible_names())} listed at the end)")
    page.search.clear()
    print(f"group FENCE picked: {ms(lambda: (page.pick_group('FENCE'), app.processEvents())):.1f} ms; "
          f"back to All: {ms(lambda: (page.pick_group(''), app.processEvents())):.1f} ms")
    fresh = ParameterModel()
    fresh.set_metadata(load_metadata())
    fresh.set_table(table)
    print(f"a new page over all of them, shown: "
          f"{ms(lambda: (ParametersPage(fresh).show(), app.processEvents())):.1f} ms")


if __name__ == "__main__":
    with tables.publishing("params_page"):
        main()
