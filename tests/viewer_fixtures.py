"""Fixtures for the viewer's end-to-end tests: the real window on the real driver and simulator.

The simulator and driver fixtures come from conftest.py (``sim``, ``vehicle_factory``); here the
window is added, with its own settings file so tests never touch the user's.
"""
from __future__ import annotations

import pytest
from PyQt5.QtCore import QSettings

from uavviewer.main_window import MainWindow


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
