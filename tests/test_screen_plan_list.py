"""Issue 29, item 10: the Plan list showed 1 row at 1366×768 and 0 rows at 1280×720 (the rest scrolled out of its
dock). Now at least 6 rows are in view at 1280×720 (and 1366×768), and the map beside stays usable: at least
MAP_USABLE of it in view. Real window, a mission planned with real clicks on the map.
"""
from __future__ import annotations

import pytest
from PyQt5.QtCore import QPoint, QRect, Qt
from PyQt5.QtWidgets import QApplication

from viewer_fixtures import app_style, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = [pytest.mark.timeout(90), pytest.mark.usefixtures("app_style")]

SIZES = [(1366, 768), (1280, 720)]
ROWS = 6
MAP_USABLE = (300, 160)           # px of map in view, at least: its own minimum (MapView), room to aim a click


def in_view(widget, w) -> QRect:
    """The part of ``widget`` shown on screen, in window coordinates (clipped by every parent)."""
    part = widget.visibleRegion().boundingRect()
    return QRect(widget.mapTo(w, part.topLeft()), part.size())


def rows_in_view(table, w) -> int:
    shown = in_view(table.viewport(), w)
    whole = 0
    for row in range(table.rowCount()):
        rect = table.visualRect(table.model().index(row, 0))
        rect = QRect(table.viewport().mapTo(w, rect.topLeft()), rect.size())
        whole += shown.contains(QRect(shown.left(), rect.top(), 1, rect.height()))
    return whole


@pytest.mark.parametrize("size", SIZES, ids=[f"{w}x{h}" for w, h in SIZES])
def test_the_plan_list_shows_six_rows_beside_a_usable_map(qtbot, vehicle, window_factory, size):
    w = window_factory(vehicle, takeoff_altitude=3.0)
    w.resize(*size)
    qtbot.waitUntil(lambda: (w.width(), w.height()) == size, timeout=3000)
    view, plan = w.mapPanel.mapView, w.plan
    qtbot.waitUntil(lambda: plan.home is not None and view.frame is not None, timeout=15000)
    qtbot.mouseClick(plan.plan_button, Qt.LeftButton)                    # Plan: the list and the map
    qtbot.waitUntil(lambda: plan.layer.editing and plan.dock.isVisible(), timeout=3000)
    for _ in range(3):
        QApplication.processEvents()
    view.zoom_to(0.5)
    for i in range(10):                                                 # a takeoff and ten waypoints
        qtbot.mouseClick(view, Qt.LeftButton, pos=view.to_screen(30.0 * (i % 5) - 60, 25.0 * (i // 5) - 12).toPoint())
    table = plan.panel.tables["mission"]
    qtbot.waitUntil(lambda: table.rowCount() == 11, timeout=3000)
    QApplication.processEvents()
    assert rows_in_view(table, w) >= ROWS, f"at {size}: {rows_in_view(table, w)} rows of the plan in view"
    shown = in_view(view, w)
    assert shown.width() >= MAP_USABLE[0] and shown.height() >= MAP_USABLE[1], f"at {size}: map {shown.size()}"


def test_quitting_in_plan_mode_brings_back_the_tabs_that_stepped_out(qtbot, vehicle, window_factory):
    w = window_factory(vehicle)
    qtbot.mouseClick(w.plan.plan_button, Qt.LeftButton)
    qtbot.waitUntil(w.plan.dock.isVisible, timeout=3000)
    assert not w.plotsDock.toggleViewAction().isChecked()             # stepped out while planning
    w.quit_without_asking()
    again = window_factory(vehicle)                                   # the next run: the same settings file
    assert again.plotsDock.toggleViewAction().isChecked() and again.preflightDock.toggleViewAction().isChecked()
