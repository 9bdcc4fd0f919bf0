"""Issue 21, problem 2: the window fits a laptop. At 1366×768, 1280×720 and 1024×600 every essential widget
(uavviewer.window.layout.essential_widgets) lies inside the window, is shown whole (not clipped by its parents, not
narrower than its own content needs) and is not covered by anything else: the widget under its centre and under
each corner is itself or one of its children.

Real window on the real driver and simulator, in flight (the longest texts: battery with mAh and time left).
"""
from __future__ import annotations

import pytest
from PyQt5.QtCore import QPoint, QRect
from PyQt5.QtWidgets import QApplication, QWidget

from uavviewer.window.layout import MIN_SIZE, essential_widgets

from lockstep_fixtures import lockstep_window  # noqa: F401  (fixtures)
from viewer_fixtures import app_style, viewer_settings, window, window_factory  # noqa: F401  (fixtures)

pytestmark = [pytest.mark.timeout(90), pytest.mark.usefixtures("app_style")]

SIZES = [(1366, 768), (1280, 720), (1024, 600)]


def _within(child: QWidget | None, widget: QWidget) -> bool:
    while child is not None:
        if child is widget:
            return True
        child = child.parentWidget()
    return False


def layout_problems(w) -> list[str]:
    """What a pilot could not see or reach, measured on the window held still: no new state is shown meanwhile
    (a text that grew with a new value, a battery's mAh, is laid out on the next pass of the event loop, and a
    measurement between the two saw a label narrower than its text), and its layout requests are done."""
    w.adapter.stop()
    for _ in range(2):
        QApplication.processEvents()
    problems = []
    inside = w.rect()
    for name, widget in essential_widgets(w).items():
        if not widget.isVisible():
            problems.append(f"{name}: hidden")
            continue
        rect = QRect(widget.mapTo(w, QPoint(0, 0)), widget.size())
        if not inside.contains(rect):
            problems.append(f"{name}: {rect} outside the window {inside}")
        if widget.visibleRegion().boundingRect() != widget.rect():
            problems.append(f"{name}: clipped, only {widget.visibleRegion().boundingRect()} of {widget.rect()} shown")
        need = widget.minimumSizeHint()
        if widget.width() < need.width() or widget.height() < need.height():
            problems.append(f"{name}: {widget.size()} is smaller than its content needs ({need})")
        r = rect.adjusted(2, 2, -3, -3)
        for point in (r.center(), r.topLeft(), r.topRight(), r.bottomLeft(), r.bottomRight()):
            top = w.childAt(point)
            if not _within(top, widget):
                problems.append(f"{name}: covered at {point} by {type(top).__name__} {top.objectName() if top else ''}")
    return problems


def settle(qtbot, w, width: int, height: int) -> None:
    w.resize(width, height)
    qtbot.waitUntil(lambda: (w.width(), w.height()) == (width, height), timeout=3000)
    QApplication.processEvents()


def test_everything_a_pilot_needs_is_in_view_at_laptop_sizes(qtbot, lockstep_window):
    """In lockstep: the texts measured (the battery's mAh and minutes left, the link's packets a second) are those
    of the same moment of the same flight every run; over a socket they grew with the machine's load, a digit
    past what the 1024-px strip holds."""
    steps = lockstep_window(window={"takeoff_altitude": 3.0})
    w = steps.window
    steps.take_off(3.0)
    steps.until(lambda: w.adapter.state.can_fly_velocity and w.leftStick.isEnabled(), 20, "flying")
    steps.until(lambda: "mAh" in w.statusStrip.battery.text(), 10, "the battery's mAh")
    w.rightStick.hold(-0.6, -0.75)                           # the longest setpoint line: every axis, signs
    w.leftStick.hold(-0.7, -0.6)
    steps.until(lambda: "yaw -" in w.setpointLabel.text(), 3, "the setpoint line")
    for width, height in SIZES:
        settle(qtbot, w, width, height)
        problems = layout_problems(w)
        assert not problems, f"at {width}×{height}:\n" + "\n".join(problems)


def test_the_window_shrinks_to_a_netbook(qtbot, window):
    w = window
    assert w.minimumSizeHint().width() <= MIN_SIZE.width() and w.minimumSizeHint().height() <= MIN_SIZE.height()
    settle(qtbot, w, MIN_SIZE.width(), MIN_SIZE.height())
    problems = layout_problems(w)
    assert not problems, "\n".join(problems)


def test_the_first_size_fits_the_screen(qtbot, sim, vehicle, viewer_settings):
    from uavviewer.main_window import MainWindow
    w = MainWindow(vehicle, qsettings=viewer_settings)         # no saved geometry: it fits the screen
    qtbot.addWidget(w, before_close_func=MainWindow.quit_without_asking)
    free = QApplication.primaryScreen().availableGeometry()
    assert w.width() <= max(free.width(), MIN_SIZE.width()) and w.height() <= max(free.height(), MIN_SIZE.height())
    assert w.width() <= 1366 and w.height() <= 768


def _own_window(qtbot, drone, viewer_settings):
    from uavviewer.main_window import MainWindow
    w = MainWindow(drone, qsettings=viewer_settings)
    qtbot.addWidget(w, before_close_func=MainWindow.quit_without_asking)
    w.show()
    qtbot.waitExposed(w)
    return w


def test_a_fresh_profile_on_a_600_pixel_screen_fits_title_bar_included(qtbot, lockstep_window, viewer_settings):
    """Issue 29, item 7: the test screen (Qt's offscreen platform) is 600 px tall, as a 1024×600 netbook's; a fresh
    profile opened 629 px tall there, its bottom cut. Now it fits with a title bar, and everything a pilot needs is
    in view at that size (in lockstep: the same texts every run)."""
    from uavviewer.window.layout import FRAME_ALLOWANCE
    steps = lockstep_window(build=lambda vehicle: _own_window(qtbot, vehicle, viewer_settings))
    w = steps.window
    free = QApplication.primaryScreen().availableGeometry()
    assert free.height() <= 600
    assert w.height() + FRAME_ALLOWANCE <= free.height(), f"{w.size()} on {free}"
    steps.take_off(3.0)
    steps.until(lambda: w.adapter.state.can_fly_velocity, 20, "flying")
    problems = layout_problems(w)
    assert not problems, "\n".join(problems)


def test_a_window_saved_on_a_larger_screen_is_restored_inside_this_one(qtbot, vehicle, viewer_settings):
    """Issue 29, item 6: saved at 1366×728 (a larger screen), restored on a smaller one, it came back 1366×728."""
    from uavviewer.window.layout import FRAME_ALLOWANCE
    w = _own_window(qtbot, vehicle, viewer_settings)
    w.setMinimumSize(0, 0)
    w.resize(1366, 728)
    w.move(40, 30)
    qtbot.waitUntil(lambda: w.height() == 728, timeout=3000)
    w.quit_without_asking()                             # saves its geometry, as on quitting
    again = _own_window(qtbot, vehicle, viewer_settings)
    free = QApplication.primaryScreen().availableGeometry()
    least = again.minimumSizeHint()
    assert again.width() <= max(free.width(), least.width()), f"{again.geometry()} on {free}"
    assert again.height() + FRAME_ALLOWANCE <= free.height(), f"{again.geometry()} on {free}"
    assert free.contains(again.frameGeometry().topLeft())
    try:
        qtbot.waitUntil(lambda: not layout_problems(again), timeout=3000)     # laid out at its restored size
    except AssertionError:
        pass
    problems = layout_problems(again)
    assert not problems, "\n".join(problems)
