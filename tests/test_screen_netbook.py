"""At 1024×600: "home 0.0 m" covered the ALT box's label; Messages opened at its oldest line; the Plan list showed
no row until its dock was scrolled, and then Upload scrolled away. (The video HUD's texts: test_camera_view.py.)
Real window on the real driver and simulated vehicle, at a netbook's size.
"""
from __future__ import annotations

import pytest
from PyQt5.QtCore import QPoint, QRect, QRectF, Qt
from PyQt5.QtWidgets import QApplication

from driver.vehicle.state import Severity
from secondary_windows import netbook_window
from test_screen_plan_list import in_view, rows_in_view
from viewer_fixtures import app_style, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = [pytest.mark.timeout(90), pytest.mark.usefixtures("app_style")]


def settle() -> None:
    for _ in range(5):
        QApplication.processEvents()


def test_home_distance_keeps_clear_of_the_altitude_box(qtbot, vehicle, window_factory):
    w = netbook_window(qtbot, window_factory, vehicle)
    qtbot.waitUntil(lambda: w.adapter.state.home is not None, timeout=15000)
    settle()
    arrow = QRectF(w.home_arrow.geometry())
    boxes = w.attitude.readout_rects()
    assert w.home_arrow.isVisible() and w.home_arrow.text.startswith("home ")
    covered = [name for name, box in boxes.items() if arrow.intersects(box)]
    assert not covered, f"home {arrow} covers {covered}: {boxes}"


def test_messages_open_at_the_newest_line(qtbot, vehicle, window_factory):
    w = netbook_window(qtbot, window_factory, vehicle)
    settle()
    for i in range(60):                                          # lines come in while Map is the tab in front
        w.log_message(f"line {i}", Severity.INFO)
    w.messagesDock.raise_()                                      # the pilot picks the Messages tab
    settle()
    view = w.messages
    last = view.visualItemRect(view.topLevelItem(view.topLevelItemCount() - 1))
    assert view.viewport().rect().contains(last), f"the newest line at {last}, the view {view.viewport().rect()}"


def test_the_plan_list_shows_rows_with_upload_in_view(qtbot, vehicle, window_factory):
    w = netbook_window(qtbot, window_factory, vehicle, takeoff_altitude=3.0)
    view, plan = w.mapPanel.mapView, w.plan
    qtbot.waitUntil(lambda: plan.home is not None and view.frame is not None, timeout=15000)
    qtbot.mouseClick(plan.plan_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: plan.layer.editing and plan.dock.isVisible(), timeout=3000)
    settle()
    view.zoom_to(0.5)
    for i in range(6):
        qtbot.mouseClick(view, Qt.LeftButton, pos=view.to_screen(30.0 * (i % 3) - 30, 25.0 * (i // 3)).toPoint())
    table = plan.panel.tables["mission"]
    qtbot.waitUntil(lambda: table.rowCount() == 7, timeout=3000)
    settle()
    upload = plan.panel.uploadButton
    shown = in_view(upload, w)
    assert shown.size() == upload.size(), f"Upload shows {shown.size()} of {upload.size()}"
    assert rows_in_view(table, w) >= 3, f"{rows_in_view(table, w)} rows of the plan in view"
    assert plan.dock.widget().verticalScrollBar().maximum() == 0, "the Plan dock scrolls"
    assert QRect(view.mapTo(w, QPoint(0, 0)), view.size()).height() >= 120      # the map still takes clicks
