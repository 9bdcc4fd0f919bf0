"""Fixtures for the viewer's end-to-end tests: the real window on the real driver and simulator.

The simulator and driver fixtures come from conftest.py (``sim``, ``vehicle_factory``); here the
window is added, with its own settings file so tests never touch the user's.
"""
from __future__ import annotations

import pytest
from PyQt5.QtCore import QSettings, Qt

from uavviewer.main_window import MainWindow, load_style


@pytest.fixture
def app_style(qapp):
    """The style the app runs with (main.py sets it): its fonts and paddings decide what fits."""
    before = qapp.styleSheet()
    qapp.setStyleSheet(load_style())
    yield
    qapp.setStyleSheet(before)


@pytest.fixture
def viewer_settings(tmp_path):
    return QSettings(str(tmp_path / "viewer.ini"), QSettings.IniFormat)


@pytest.fixture
def window_factory(qtbot, viewer_settings):
    """Build main windows on given drones; each is closed after the test."""
    windows = []

    def make(drone, **kw) -> MainWindow:
        w = MainWindow(drone, qsettings=viewer_settings, **kw)
        qtbot.addWidget(w, before_close_func=MainWindow.quit_without_asking)   # a flying test ends unasked
        w.resize(1400, 900)
        w.show()
        qtbot.waitExposed(w)
        w.activateWindow()
        windows.append(w)
        return w

    yield make
    for w in windows:
        w.quit_without_asking()


@pytest.fixture
def window(vehicle, window_factory) -> MainWindow:
    """The window on the driver connected to the simulated vehicle."""
    w = window_factory(vehicle, takeoff_altitude=3.0)
    return w


def pick_mode(qtbot, selector, name: str) -> None:
    """Open the mode selector's list and click ``name`` in it, as the pilot does."""
    selector.showPopup()
    view = selector.view()
    qtbot.waitUntil(view.isVisible, timeout=3000)
    index = view.model().index(selector.findText(name), 0)
    view.scrollTo(index)
    qtbot.mouseClick(view.viewport(), Qt.LeftButton, pos=view.visualRect(index).center())
    qtbot.waitUntil(lambda: not view.isVisible(), timeout=3000)
