"""Every secondary window a pilot opens from the flying window, opened as the window opens it: the menus' actions,
the review's own button. One table for the tests that check them all (fit, Esc, Close, placement, keys)."""
from __future__ import annotations

import os

from PyQt5.QtCore import QRect
from PyQt5.QtWidgets import QAction, QApplication, QMessageBox, QWidget

from driver.review.writer import sample_flight
from uavviewer.input.keys_dialog import KeysDialog


def _review(w, qtbot, folder) -> QWidget:
    path = os.path.join(folder, "flight.BIN")
    if not os.path.exists(path):
        sample_flight(seconds=20, rate_hz=10).save(path)
    with qtbot.waitSignal(w.review.opened, timeout=20000) as opened:
        w.review.open(path)                                  # File › Review a log…, the file picked
    return opened.args[0]


def _geotag(w, qtbot, folder) -> QWidget:
    return _review(w, qtbot, folder).open_geotag()          # the review's Geotag photos… button


def _visible(kind, name: str = ""):
    found = [x for x in QApplication.topLevelWidgets() if isinstance(x, kind) and x.isVisible()
             and (not name or x.objectName() == name)]
    return found[-1] if found else None


def _trigger(w, name: str):
    w.findChild(QAction, name).trigger()


#: name -> how the pilot opens it (the window, qtbot, a scratch folder) -> the window opened
OPENERS = {
    "setup": lambda w, qtbot, folder: w.setup.open(),
    "parameters": lambda w, qtbot, folder: w.params.open(),
    "review": _review,
    "geotag": _geotag,
    "inspector": lambda w, qtbot, folder: w.inspector.show(),
    "flight logs": lambda w, qtbot, folder: (_trigger(w, "actionFlightLogs"), w.flight_logs.dialog)[1],
    "preferences": lambda w, qtbot, folder: (w.actionPreferences.trigger(), w.preferences.dialog)[1],
    "connect": lambda w, qtbot, folder: (w.actionConnect.trigger(), w.tools.connect_dialog)[1],
    "keys": lambda w, qtbot, folder: (w.actionKeys.trigger(), _visible(KeysDialog))[1],
    "about": lambda w, qtbot, folder: (w.actionAbout.trigger(), _visible(QMessageBox, "aboutBox"))[1],
}


def open_secondary(name: str, w, qtbot, folder: str) -> QWidget:
    window = OPENERS[name](w, qtbot, str(folder))
    qtbot.waitUntil(window.isVisible, timeout=5000)
    qtbot.waitExposed(window)
    QApplication.processEvents()
    return window


NETBOOK = (1024, 560)                     # the window on a 1024×600 screen, a title bar's room left


def netbook_window(qtbot, window_factory, drone, **kw):
    """The window as it opens on a 1024×600 netbook, at the screen's top left."""
    w = window_factory(drone, **kw)
    w.move(0, 0)
    w.resize(*NETBOOK)
    qtbot.waitUntil(lambda: (w.width(), w.height()) == NETBOOK, timeout=3000)
    return w


def netbook_screen(w) -> QRect:
    """The 1024×600 screen the window's frame spans. (Qt's offscreen screen is 800×600 and gives windows 2 px
    borders: the window's own frame decides the width, as a screen at least as wide as it would.)"""
    return QRect(0, 0, max(1024, w.frameGeometry().width()), 600)
