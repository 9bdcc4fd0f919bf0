"""Issue 29, item 9: the Parameters window opened over Stop, RTL and the attitude indicator, with no Close button
and no Esc. It now stands beside the flight controls at every laptop size, closes with Esc and with Close, and
opens where the pilot left it. Real window on the real driver and simulated vehicle.
"""
from __future__ import annotations

import pytest
from PyQt5.QtCore import QPoint, QRect, Qt
from PyQt5.QtWidgets import QAction

from viewer_fixtures import app_style, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = [pytest.mark.timeout(60), pytest.mark.usefixtures("app_style")]

SIZES = [(1366, 768), (1280, 720), (1024, 600)]


def open_parameters(qtbot, w):
    w.findChild(QAction, "actionParameters").trigger()          # Vehicle › Parameters…
    page = w.params.page
    qtbot.waitUntil(page.isVisible, timeout=3000)
    return page


def on_screen(widget) -> QRect:
    return QRect(widget.mapToGlobal(QPoint(0, 0)), widget.size())


@pytest.mark.parametrize("size", SIZES, ids=[f"{w}x{h}" for w, h in SIZES])
def test_parameters_stands_beside_the_flight_controls_and_closes_with_esc_or_close(qtbot, vehicle, window_factory,
                                                                                    size):
    w = window_factory(vehicle)
    w.move(0, 0)
    w.resize(*size)
    qtbot.waitUntil(lambda: (w.width(), w.height()) == size, timeout=3000)
    page = open_parameters(qtbot, w)
    fc = w.flightControls
    covered = [name for name, widget in (("Take off", fc.main_button), ("Stop", fc.stop_button),
                                         ("RTL", fc.rtl_button), ("Arm", fc.arm_button), ("mode", w.modeSelector),
                                         ("attitude", w.attitude))
               if page.frameGeometry().intersects(on_screen(widget))]
    assert not covered, f"at {size}: Parameters {page.frameGeometry()} covers {covered}"
    assert page.width() >= page.minimumSizeHint().width()

    qtbot.keyClick(page.search, Qt.Key_Escape)                   # Esc closes, from its search field too
    qtbot.waitUntil(lambda: not page.isVisible(), timeout=3000)
    page = open_parameters(qtbot, w)
    assert page.close_button.text() == "Close" and page.close_button.isVisible()
    qtbot.mouseClick(page.close_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: not page.isVisible(), timeout=3000)


def test_parameters_opens_where_the_pilot_left_it(qtbot, vehicle, window_factory):
    w = window_factory(vehicle)
    page = open_parameters(qtbot, w)
    left_at = QRect(60, 40, 620, 480)
    page.setGeometry(left_at)
    qtbot.waitUntil(lambda: page.geometry() == left_at, timeout=3000)
    qtbot.keyClick(page.search, Qt.Key_Escape)
    qtbot.waitUntil(lambda: not page.isVisible(), timeout=3000)

    again = window_factory(vehicle)                             # the next run: the same settings file
    page = open_parameters(qtbot, again)
    assert page.geometry() == left_at
