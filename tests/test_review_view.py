"""The review view (issue 31): File › Open log… opens a .BIN made here or a recorded .tlog off the window's
thread; the tree searches, presets plot, the cursor moves the path's marker and back, the events and the
parameters as flown (and their differences) show, CSV exports; a bad log says why and the window flies on."""
from __future__ import annotations

import gc
import os
import threading
import weakref

import pytest
from PyQt5.QtCore import Qt

from driver.review import open_log
from driver.review.writer import sample_flight
from uavviewer.review.view import ReviewWindow
from test_review_log import bin_path  # noqa: F401  (fixture: a 20 s flight)
from viewer_fixtures import viewer_settings, window_factory, window  # noqa: F401  (fixtures)

RECORDINGS = os.path.join(os.path.dirname(__file__), "data", "recordings")


@pytest.fixture()
def view(qtbot, bin_path):
    current = {"RTL_ALT": 2000.0, "WPNAV_SPEED": 500.0}
    v = ReviewWindow(open_log(bin_path), lambda: dict(current))
    v.current = current
    qtbot.addWidget(v)
    v.resize(1366, 768)
    v.show()
    qtbot.waitExposed(v)
    return v


def test_the_tree_searches_and_a_double_click_plots(qtbot, view):
    tree = view.tree.tree
    assert tree.topLevelItemCount() == 10
    view.tree.search.setText("vibez")
    shown = [tree.topLevelItem(i) for i in range(tree.topLevelItemCount()) if not tree.topLevelItem(i).isHidden()]
    assert [t.text(0) for t in shown] == ["VIBE"]
    field = next(shown[0].child(k) for k in range(shown[0].childCount()) if not shown[0].child(k).isHidden())
    assert field.text(0) == "VibeZ"
    tree.itemDoubleClicked.emit(field, 0)
    assert list(view.plots.curves) == [("VIBE", "VibeZ")]
    view.add_field("BAT", "Curr", 1)
    assert view.plots.curves[("BAT", "Curr")][1] == 1 and view.plots.curves[("BAT", "Curr")][0] in view.plots.right.addedItems


def test_presets_plot_what_the_log_has(view):
    assert view.apply_preset("Attitude") == 4
    assert set(view.plots.curves) == {("ATT", "DesRoll"), ("ATT", "Roll"), ("ATT", "DesPitch"), ("ATT", "Pitch")}
    assert view.apply_preset("Battery") == 2 and view.plots.curves[("BAT", "Curr")][1] == 1
    for name in ("Altitude", "Vibration", "GPS"):
        assert view.apply_preset(name) > 0


def test_two_gps_and_imus_show_apart_and_presets_take_the_first(qtbot, tmp_path):
    path = str(tmp_path / "dual.BIN")
    sample_flight(seconds=20, rate_hz=10, sensors=2).save(path)
    v = ReviewWindow(open_log(path))
    qtbot.addWidget(v)
    tops = [v.tree.tree.topLevelItem(i).text(0) for i in range(v.tree.tree.topLevelItemCount())]
    assert {"GPS[0]", "GPS[1]", "VIBE[0]", "VIBE[1]"} <= set(tops) and "GPS" not in tops
    assert v.apply_preset("Vibration") == 3 and {k[0] for k in v.plots.curves} == {"VIBE[0]"}
    v.add_field("GPS[1]", "Lat")
    assert ("GPS[1]", "Lat") in v.plots.curves
    assert len(v.path_overlay._times) == v.log.count("GPS[0]")           # the path: one receiver's fixes


def test_the_cursor_moves_the_marker_along_the_path_and_back(qtbot, view):
    overlay = view.path_overlay
    assert overlay.marker == 0 and view.map.frame is not None
    start = overlay.marker_place()
    view.plots.set_cursor(15.0)
    later = overlay.marker_place()
    assert overlay.marker > 0 and later != start
    view.plots.set_cursor(0.0)
    assert overlay.marker == 0 and overlay.marker_place() == start
    paints = view.map.paints
    view.plots.set_cursor(10.0)
    qtbot.waitUntil(lambda: view.map.paints > paints)
    view.side.setCurrentWidget(view.map)
    qtbot.waitUntil(lambda: view.map.isVisible())
    index = len(overlay._points) * 3 // 4                  # a click on the path puts the cursor at its time
    qtbot.mouseClick(view.map, Qt.LeftButton, pos=view.map.to_screen(*overlay._points[index]).toPoint())
    assert overlay.marker == index
    assert view.plots.cursor.value() == pytest.approx(overlay._times[index])


def test_events_and_parameters_as_flown(qtbot, view):
    texts = [view.events.item(i).text() for i in range(view.events.count())]
    assert any("GUIDED" in t for t in texts) and any("battery failsafe triggered" in t for t in texts)
    assert any("armed" in t for t in texts)
    assert len(view.plots.event_marks) == len(texts)
    rtl = next(i for i in range(view.events.count()) if "RTL" in view.events.item(i).text())
    view.events.itemClicked.emit(view.events.item(rtl))
    assert view.plots.cursor.value() == pytest.approx(view.events.item(rtl).data(Qt.UserRole))
    p = view.params
    assert p.differences == [("BATT_LOW_VOLT", 10.5, None), ("RTL_ALT", 1500.0, 2000.0)]
    assert p.table.rowCount() == 2 and p.table.item(1, 1).text() == "1500" and p.table.item(1, 2).text() == "2000"
    p.only_diff.setChecked(False)
    assert p.table.rowCount() == 3
    view.current["BATT_LOW_VOLT"] = 10.5                  # the vehicle's table changed: read again on showing
    view.side.setCurrentWidget(view.events)
    view.side.setCurrentWidget(view.params)
    assert p.differences == [("RTL_ALT", 1500.0, 2000.0)] and p.table.rowCount() == 1


def test_export_csv_of_the_plotted_fields_off_the_window_thread(qtbot, view, tmp_path):
    """The rows are built and written on a worker (a long log takes seconds); the status line says when it is done,
    and why when it fails."""
    view.add_field("ATT", "Roll")
    view.add_field("BAT", "Volt", 1)
    writer = view.log.export_csv
    threads = []
    view.log.export_csv = lambda *a: threads.append(threading.current_thread()) or writer(*a)
    out = str(tmp_path / "chosen.csv")
    with qtbot.waitSignal(view.exported) as done:
        future = view.export(out)
        assert not view.export_button.isEnabled() and "exporting 2 fields" in view.status.text()
    rows = done.args[0]
    assert future.result() == rows and threads and threads[0] is not threading.main_thread()
    lines = open(out).read().splitlines()
    assert lines[0] == "time_s,ATT.Roll,BAT.Volt" and len(lines) == rows + 1 > 100
    assert "exported 2 fields" in view.status.text() and view.export_button.isEnabled()
    with qtbot.waitSignal(view.exported) as failed:
        view.export(str(tmp_path / "no such folder" / "x.csv"))
    assert "No such file" in failed.args[0] and "failed" in view.status.text() and view.export_button.isEnabled()


def test_file_open_log_opens_a_tlog_and_a_bad_log_says_why(qtbot, window, tmp_path):
    review = window.review
    assert review.action in window.menuFile.actions()
    empty = str(tmp_path / "empty.BIN")
    open(empty, "wb").close()
    with qtbot.waitSignal(review.failed) as failed:
        review.open(empty)
    assert "empty" in failed.args[0] and review.box.isVisible()
    review.box.close()
    with qtbot.waitSignal(review.opened, timeout=20000) as opened:
        review.open(os.path.join(RECORDINGS, "arducopter-4.6-sitl-adsb.tlog"))
    view = opened.args[0]
    assert view.isVisible() and "ATTITUDE" in [view.tree.tree.topLevelItem(i).text(0)
                                               for i in range(view.tree.tree.topLevelItemCount())]
    assert view.apply_preset("Attitude") == 2
    assert view.path_overlay.marker == 0
    qtbot.waitUntil(lambda: window.adapter.state.connected)         # the window still flies its vehicle


def test_a_closed_review_lets_its_window_and_log_go(qtbot, window, bin_path):
    """The controller kept every review it opened: each closed window held its log's arrays until the app quit."""
    review = window.review
    with qtbot.waitSignal(review.opened, timeout=20000) as opened:
        review.open(bin_path)
    view = opened.args[0]
    flight = weakref.ref(view.log)
    assert review.views == [view]
    with qtbot.waitSignal(view.destroyed):
        view.close()
    del view, opened
    assert review.views == []
    qtbot.waitUntil(lambda: gc.collect() >= 0 and flight() is None)   # once Qt has let its slots' proxies go
