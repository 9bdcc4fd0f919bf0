"""No window takes over the flight controls. Every secondary window (Setup, Parameters, a review, Geotag, the MAVLink
inspector, Flight logs, Preferences, Connect, Keys, About) fits a 1024×600 screen, closes with Esc and with a Close
button, and comes back inside the screen when it was left larger; it opens beside the flight controls, and while the
vehicle flies none stands over them and the flight keys (Space, T, L, R) work from it. Real window on the real
driver and simulated vehicle, opened as the pilot opens them.

Found: Review opened at 1366×768 on a 1024×600 screen; the inspector was 900×600 with neither Close nor Esc; Geotag
had no Close; Parameters widened to 827 px after one write and came back so; Setup opened in flight covered Land,
Stop and RTL, and with Setup focused R did nothing.
"""
from __future__ import annotations

import pytest
from PyQt5.QtCore import QPoint, QRect, Qt
from PyQt5.QtWidgets import (QAbstractButton, QAbstractSpinBox, QApplication, QComboBox, QDialogButtonBox, QLineEdit,
                             QMessageBox, QPlainTextEdit, QTextEdit, QWidget)
from pytestqt.exceptions import TimeoutError as WaitTimedOut

from secondary_windows import OPENERS, netbook_screen, netbook_window, open_secondary
from viewer_fixtures import app_style, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = [pytest.mark.timeout(120), pytest.mark.usefixtures("app_style")]

TITLE = 40                                # px a title bar takes (uavviewer.widgets.dialog_fit.FRAME_ALLOWANCE)


def flight_area(w) -> QRect:
    central = w.centralWidget()
    return QRect(central.mapToGlobal(QPoint(0, 0)), central.size())


def close_button(window: QWidget) -> QAbstractButton | None:
    """The button that closes it without acting: Close (or a dialog's Cancel)."""
    if isinstance(window, QMessageBox):
        found = [b for b in window.buttons() if window.buttonRole(b) == QMessageBox.RejectRole]
    else:
        found = [b for box in window.findChildren(QDialogButtonBox) for b in box.buttons()
                 if box.buttonRole(b) == QDialogButtonBox.RejectRole]
        found += [b for b in window.findChildren(QAbstractButton) if b.text().replace("&", "") == "Close"]
    found = [b for b in found if b.isVisible() and b.text().replace("&", "") in ("Close", "Cancel")]
    return found[0] if found else None


def fit_problems(window: QWidget, w) -> list[str]:
    problems = []
    screen = netbook_screen(w)
    frame = window.frameGeometry()
    if window.width() > screen.width() or window.height() + TITLE > screen.height():
        problems.append(f"{window.size()} does not fit {screen.size()} with a title bar")
    if not screen.contains(frame):
        problems.append(f"{frame} is not inside the screen {screen}")
    button = close_button(window)
    if button is None:
        problems.append("no Close button")
    elif QRect(button.mapTo(window, QPoint(0, 0)), button.size()) != button.visibleRegion().boundingRect().translated(
            button.mapTo(window, QPoint(0, 0))) or not window.rect().contains(
            QRect(button.mapTo(window, QPoint(0, 0)), button.size())):
        problems.append(f"{button.text()!r} out of reach")
    return problems


def press_esc(qtbot, window: QWidget) -> None:
    QApplication.setActiveWindow(window)
    qtbot.keyClick(window.focusWidget() or window, Qt.Key_Escape)


@pytest.mark.parametrize("name", list(OPENERS))
def test_every_secondary_window_fits_closes_with_esc_and_close_and_comes_back_inside(qtbot, vehicle, window_factory,
                                                                                       tmp_path, name):
    w = netbook_window(qtbot, window_factory, vehicle)
    window = open_secondary(name, w, qtbot, tmp_path)
    problems = fit_problems(window, w)
    if window.frameGeometry().intersects(flight_area(w)):
        problems.append(f"opens over the flight controls: {window.frameGeometry()} on {flight_area(w)}")
    assert not problems, f"{name}:\n" + "\n".join(problems)

    press_esc(qtbot, window)                                    # Esc closes it
    qtbot.waitUntil(lambda: not window.isVisible(), timeout=3000)

    window = open_secondary(name, w, qtbot, tmp_path)
    qtbot.mouseClick(close_button(window), Qt.LeftButton)       # and so does Close
    qtbot.waitUntil(lambda: not window.isVisible(), timeout=3000)

    window = open_secondary(name, w, qtbot, tmp_path)           # left larger than this screen (a bigger one's size),
    window.setGeometry(QRect(300, 200, 1366, 900))              # partly off it: it comes back inside
    qtbot.waitUntil(lambda: window.width() == 1366 or window.minimumSize() == window.maximumSize(), timeout=3000)
    window.close()
    qtbot.waitUntil(lambda: not window.isVisible(), timeout=3000)
    window = open_secondary(name, w, qtbot, tmp_path)
    problems = fit_problems(window, w)
    assert not problems, f"{name} reopened:\n" + "\n".join(problems)
    window.close()


def test_parameters_keeps_its_width_after_a_write(qtbot, vehicle, window_factory, tmp_path):
    """One staged change ("1 change(s) pending: nothing is written…") widened Parameters to 827 px, Close off
    screen, and it came back so."""
    w = netbook_window(qtbot, window_factory, vehicle)
    page = open_secondary("parameters", w, qtbot, tmp_path)
    qtbot.waitUntil(lambda: w.params.model.parameter("RTL_ALT") is not None, timeout=20000)
    w.params.stage_text("RTL_ALT", "2500")
    QApplication.processEvents()
    assert page.minimumSizeHint().width() <= netbook_screen(w).right() - flight_area(w).right(), page.minimumSizeHint()
    assert not fit_problems(page, w) and not page.frameGeometry().intersects(flight_area(w))


def test_in_flight_no_window_covers_the_controls_and_the_flight_keys_work_from_each(qtbot, sim, flying,
                                                                                     window_factory, tmp_path):
    w = netbook_window(qtbot, window_factory, flying)
    qtbot.waitUntil(lambda: w.flightControls.stop_button.isEnabled(), timeout=10000)
    keys = [(Qt.Key_R, "RTL"), (Qt.Key_Space, "GUIDED")]      # RTL, then Stop: GUIDED and holding, and again
    for i, name in enumerate(OPENERS):
        window = open_secondary(name, w, qtbot, tmp_path)
        assert not window.frameGeometry().intersects(flight_area(w)), \
            f"{name} {window.frameGeometry()} covers the flight controls {flight_area(w)}"
        key, mode = keys[i % 2]
        QApplication.setActiveWindow(window)
        focus = window.focusWidget()
        if isinstance(focus, (QLineEdit, QAbstractSpinBox, QTextEdit, QPlainTextEdit)) or (
                isinstance(focus, QComboBox) and focus.isEditable()):   # a field there takes the letters: not on it
            focus = close_button(window)
            focus.setFocus()
        button = w.flightControls.rtl_button if key == Qt.Key_R else w.flightControls.stop_button
        qtbot.waitUntil(button.isEnabled, timeout=10000)       # the key does what its button does, when it can
        target = focus or window
        qtbot.keyClick(target, key)
        try:
            qtbot.waitUntil(lambda: sim.truth().mode == mode, timeout=10000)
        except WaitTimedOut:
            raise AssertionError(f"{name}: the key pressed in {type(target).__name__} '{target.objectName()}' "
                                 f"(active: {QApplication.activeWindow()}) did not make {mode}") from None
        window.close()
        qtbot.waitUntil(lambda: not window.isVisible(), timeout=3000)

    page = open_secondary("parameters", w, qtbot, tmp_path)      # typing in a field is typing
    qtbot.waitUntil(lambda: w.adapter.state.mode == sim.truth().mode, timeout=10000)   # the last key's mode shown
    sent = []
    w.adapter.commandSent.connect(sent.append)
    page.search.setFocus()
    qtbot.keyClick(page.search, Qt.Key_R)
    assert page.search.text() == "r" and sent == [], sent                # a letter typed, nothing flown


def test_a_window_over_the_controls_steps_aside_when_the_vehicle_takes_off(qtbot, sim, vehicle, window_factory,
                                                                           tmp_path):
    w = netbook_window(qtbot, window_factory, vehicle)
    setup = open_secondary("setup", w, qtbot, tmp_path)
    setup.setGeometry(QRect(20, 60, 700, 480))                  # the pilot put it there on the ground
    qtbot.waitUntil(lambda: setup.frameGeometry().intersects(flight_area(w)), timeout=3000)
    qtbot.waitUntil(lambda: w.adapter.state.readiness.ready_to_arm, timeout=20000)
    w.adapter.send(w.adapter.drone.takeoff, 3.0)
    qtbot.waitUntil(lambda: w.adapter.state.armed, timeout=20000)
    qtbot.waitUntil(lambda: not setup.frameGeometry().intersects(flight_area(w)), timeout=3000)
    assert not fit_problems(setup, w)
