"""The window on a laptop: its first size fits the screen it opens on (1366×768, 1280×720), and what a pilot
needs in flight stays in view down to :data:`MIN_SIZE` (tests/test_screen_layout.py checks it).

Nothing moves under the cursor as the state changes (tests/test_screen_steady.py): what comes and goes has a slot
of its own that is always there, sized for its largest content: the banners (link, alerts) one row above the
instruments, the stick line or the replay bar one row under the controls. No dock stands under or above the flight
controls (:func:`docks_beside`): View › Messages hidden and shown again moved every button and both sticks by 103 px.
"""
from __future__ import annotations

from PyQt5.QtCore import QSize, Qt
from PyQt5.QtWidgets import QApplication, QDockWidget, QSizePolicy, QWidget

from ..widgets.dialog_fit import FRAME_ALLOWANCE

__all__ = ["FIRST_SIZE", "MIN_SIZE", "fit_screen", "fit_restored", "essential_widgets", "steady_slots",
           "BANNER_HEIGHT", "docks_beside"]

FIRST_SIZE = QSize(1366, 768)      # at most: a laptop's screen
MIN_SIZE = QSize(1024, 600)        # a netbook's: still flyable
CONTROLS_WIDTH = 270               # px: the buttons' column between the sticks, fixed (it fits 1024×600)
BANNER_HEIGHT = 26                 # px: the row the link and alert banners share, there when both are hidden


def steady_slots(window) -> None:
    """Fix the heights of what comes and goes, so that showing it moves nothing else."""
    window.bannerRow.setFixedHeight(BANNER_HEIGHT)
    window.linkBanner.setFixedHeight(BANNER_HEIGHT)
    slot = window.bottomSlot
    slot.setFixedHeight(max(window.replayBar.sizeHint().height(), window.stickLine.sizeHint().height()))
    slot.setSizePolicy(QSizePolicy.Preferred, QSizePolicy.Fixed)
    # the stick and input lines never widen the window: at worst they are cut at the end (they repeat the sticks)
    for label in (window.setpointLabel, window.inputLabel):
        label.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Preferred)
    # the buttons' column keeps its width whatever the phase says (a long phase wrapped wider and moved every
    # button and both sticks): the phase wraps inside it
    window.phaseLabel.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Preferred)
    # Arm (in the air Disarm, the emergency motor stop behind a menu) in the mode's row, away from Stop; the mode
    # list says "Mode" itself while empty, and its tooltip: the row's label gave its width to Arm
    window.modeLabel.hide()
    window.modeRow.addWidget(window.flightControls.arm_button)
    frame = window.controlsFrame
    frame.setFixedWidth(max(frame.minimumSizeHint().width(), CONTROLS_WIDTH))
    # two lines, always: a long phase ("waiting for GPS fix, EKF, pre-arm checks") wraps without pushing the
    # buttons below it (layouts do not ask a wrapping label its height for a width); all of it is in its tooltip
    window.phaseLabel.setObjectName("phaseLabel")
    window.phaseLabel.ensurePolished()        # the style sheet's font, not the default one
    window.phaseLabel.setFixedHeight(2 * window.phaseLabel.fontMetrics().lineSpacing() + 2)   # a third is cut


def docks_beside(window) -> None:
    """Every dock beside the flight area, never under or above it: one shown or hidden there (View › Messages)
    changed the central column's height and moved every flight control. Messages is a tab beside Map and Plots (the
    latest autopilot message is in the status strip anyway); a layout saved with it at the bottom is set right."""
    for dock in window.findChildren(QDockWidget):
        dock.setAllowedAreas(Qt.LeftDockWidgetArea | Qt.RightDockWidgetArea)
    messages = window.messagesDock
    if window.dockWidgetArea(messages) not in (Qt.LeftDockWidgetArea, Qt.RightDockWidgetArea) \
            and not messages.isFloating():
        shown = not messages.isHidden()
        window.tabifyDockWidget(window.mapDock, messages)
        messages.setVisible(shown)
        window.mapDock.raise_()
        window.layout().activate()                # the smaller minimum now: the first size is chosen from it


def fit_screen(window: QWidget) -> None:
    """A first size (no saved geometry) that fits the available screen, title bar included. A fresh profile on a
    1024×600 screen opened at 1024×629 before, its bottom cut; now at 1024×560."""
    free = _free(window)
    if free is None:
        return
    room = free.height() - FRAME_ALLOWANCE
    width = max(MIN_SIZE.width(), min(FIRST_SIZE.width(), free.width()))
    height = max(window.minimumSizeHint().height(), min(FIRST_SIZE.height(), room))
    window.resize(width, height)
    window.move(free.topLeft())


def fit_restored(window: QWidget) -> None:
    """A geometry saved on a larger screen is clamped to this one's available area (title bar included) and moved
    inside it: a window restored at 1366×728 on a 1280×720 screen had its bottom and right edge off screen."""
    free = _free(window)
    if free is None or window.isMaximized() or window.isFullScreen():
        return
    least = window.minimumSizeHint()
    width = max(least.width(), min(window.width(), free.width()))
    height = max(least.height(), min(window.height(), free.height() - FRAME_ALLOWANCE))
    if (width, height) != (window.width(), window.height()):
        window.resize(width, height)
    x = min(max(window.x(), free.left()), max(free.left(), free.right() + 1 - width))
    y = min(max(window.y(), free.top()), max(free.top(), free.bottom() + 1 - height - FRAME_ALLOWANCE))
    if (x, y) != (window.x(), window.y()):
        window.move(x, y)


def _free(window: QWidget):
    screen = window.screen() if hasattr(window, "screen") else None
    screen = screen or QApplication.primaryScreen()
    return screen.availableGeometry() if screen is not None else None


def essential_widgets(window) -> dict[str, QWidget]:
    """What a pilot needs in view at every size, by name: attitude, sticks, Take off/Land, Stop, RTL, mode,
    battery, link, the latest autopilot message, what the vehicle is doing."""
    fc, strip = window.flightControls, window.statusStrip
    return {"attitude": window.attitude, "left stick": window.leftStick, "right stick": window.rightStick,
            "take off / land": fc.main_button, "stop": fc.stop_button, "rtl": fc.rtl_button,
            "arm": fc.arm_button, "mode": window.modeSelector, "phase": window.phaseLabel,
            "battery": strip.battery, "link": strip.link, "latest message": strip.message,
            "flight time": strip.flight_time}
