"""Issue 29, item 8: every dialog the app has fits a 1024×600 screen, title bar included, with its buttons in
reach (Preferences was 780 px tall: at 1280×720 its OK button was off the screen). The test screen (Qt's offscreen
platform) is 600 px tall. Real dialogs, opened as the window opens them, in the app's style.
"""
from __future__ import annotations

import pytest
from PyQt5.QtCore import QPoint, QRect
from PyQt5.QtWidgets import QAbstractButton, QApplication, QDialog, QDialogButtonBox, QMessageBox

from uavviewer.fleet.dock import all_vehicles_question
from uavviewer.flight.questions import arm_question, emergency_stop_question, mode_question, takeoff_question
from uavviewer.input.keys_dialog import KeysDialog
from uavviewer.map.controller import fly_here_question
from uavviewer.plan.controller import mission_start_question
from uavviewer.preferences.dialog import signing_setup_question
from uavviewer.window.layout import FRAME_ALLOWANCE
from uavviewer.params.compare_dialog import CompareDialog
from uavviewer.params.review_dialog import ReviewDialog
from uavviewer.params.rows import FileRow, ReviewRow

from secondary_windows import netbook_screen, netbook_window
from test_viewer_window import silent_vehicle  # noqa: F401  (fixture)
from viewer_fixtures import app_style, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = [pytest.mark.timeout(60), pytest.mark.usefixtures("app_style")]

# The window as on a 1024×600 netbook (secondary_windows.netbook_window); each dialog inside that screen.


def buttons(d: QDialog) -> list[QAbstractButton]:
    if isinstance(d, QMessageBox):
        return d.buttons()
    return [b for box in d.findChildren(QDialogButtonBox) for b in box.buttons()]


def dialog_problems(d: QDialog) -> list[str]:
    problems = []
    parent = d.parentWidget()
    main = parent.window() if parent is not None else None
    screen = netbook_screen(main) if main is not None else QApplication.primaryScreen().availableGeometry()
    if d.width() > screen.width() or d.height() + FRAME_ALLOWANCE > screen.height():
        problems.append(f"{d.size()} does not fit {screen.size()} with a title bar")
    if not screen.contains(d.geometry()):
        problems.append(f"{d.geometry()} is not inside the screen {screen}")
    shown = buttons(d)
    if not shown:
        problems.append("no buttons found")
    for b in shown:
        rect = QRect(b.mapTo(d, QPoint(0, 0)), b.size())
        if not b.isVisible() or not d.rect().contains(rect) or b.visibleRegion().boundingRect() != b.rect():
            problems.append(f"{b.text()!r} out of reach: {rect} in {d.rect()}")
    return problems


def opened(qtbot, d: QDialog) -> QDialog:
    d.show()
    qtbot.waitExposed(d)
    QApplication.processEvents()
    return d


def _questions(w) -> dict:
    return {"takeoff": lambda: takeoff_question(w, 3.0, ("GPS fix", "EKF", "pre-arm checks"), 60.0),
            "arm": lambda: arm_question(w, "STABILIZE", "The motors start. " * 8),
            "mode": lambda: mode_question(w, "ALT_HOLD", "It takes its throttle from an RC transmitter."),
            "emergency stop": lambda: emergency_stop_question(w),
            "signing setup": lambda: signing_setup_question(w),
            "all vehicles": lambda: all_vehicles_question(w, "takeoff", [f"solo-{i}" for i in range(8)], 3.0),
            "fly here": lambda: fly_here_question(w, "Fly 120 m north-east at 10 m?"),
            "mission start": lambda: mission_start_question(w, "Start the mission from item 1?")}


def test_preferences_fits_with_ok_in_reach(qtbot, silent_vehicle, window_factory):
    w = netbook_window(qtbot, window_factory, silent_vehicle)
    w.actionPreferences.trigger()
    d = opened(qtbot, w.preferences.dialog)
    problems = dialog_problems(d)
    assert not problems, "\n".join(problems)
    d.reject()


def test_help_keys_fits(qtbot, silent_vehicle, window_factory):
    w = netbook_window(qtbot, window_factory, silent_vehicle)
    w.show_keys()
    d = next(x for x in w.findChildren(KeysDialog) if x.isVisible())
    qtbot.waitExposed(d)
    problems = dialog_problems(d)
    assert not problems, "\n".join(problems)
    d.reject()


def test_connect_fits(qtbot, silent_vehicle, window_factory):
    w = netbook_window(qtbot, window_factory, silent_vehicle)
    w.actionConnect.trigger()
    d = opened(qtbot, w.tools.connect_dialog)
    problems = [p for p in dialog_problems(d) if p != "no buttons found"]
    assert not problems and d.connect_button.isVisible(), "\n".join(problems)
    d.reject()


def test_parameter_review_and_compare_fit(qtbot, silent_vehicle, window_factory):
    w = netbook_window(qtbot, window_factory, silent_vehicle)
    review = opened(qtbot, ReviewDialog([ReviewRow(f"PARAM_{i}", "1", "2", "a note") for i in range(60)], w))
    compare = opened(qtbot, CompareDialog("/tmp/a-long-folder-name/copter.param",
                                          [FileRow(f"PARAM_{i}", "1", "2", 2.0) for i in range(60)], 500, 3, w))
    problems = [f"review: {p}" for p in dialog_problems(review)] + \
        [f"compare: {p}" for p in dialog_problems(compare)]
    assert not problems, "\n".join(problems)
    review.reject()
    compare.reject()


def test_every_question_fits(qtbot, silent_vehicle, window_factory):
    w = netbook_window(qtbot, window_factory, silent_vehicle)
    problems = []
    for name, make in _questions(w).items():
        box = opened(qtbot, make())
        problems += [f"{name}: {p}" for p in dialog_problems(box)]
        box.reject()
    assert not problems, "\n".join(problems)


def test_the_guided_altitude_question_and_the_folder_chooser_fit(qtbot, silent_vehicle, window_factory):
    w = netbook_window(qtbot, window_factory, silent_vehicle)
    w.guided.ask_altitude()
    problems = [f"altitude: {p}" for p in dialog_problems(opened(qtbot, w.guided.question))]
    w.guided.question.reject()
    w.actionPreferences.trigger()
    chooser = opened(qtbot, w.preferences.dialog.browse_media_folder())
    problems += [f"folder: {p}" for p in dialog_problems(chooser)]
    chooser.reject()
    w.preferences.dialog.reject()
    assert not problems, "\n".join(problems)


def test_vehicle_setup_fits_on_every_page(qtbot, silent_vehicle, window_factory):
    w = netbook_window(qtbot, window_factory, silent_vehicle)
    d = opened(qtbot, w.setup.open())
    for title in d.pages:
        d.turn_to(title)
        QApplication.processEvents()
        assert dialog_problems(d) == [], title
