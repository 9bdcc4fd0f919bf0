"""The window on a laptop: its first size fits the screen it opens on (1366×768, 1280×720), and what a pilot
needs in flight stays in view down to :data:`MIN_SIZE` (tests/test_screen_layout.py checks it)."""
from __future__ import annotations

from PyQt5.QtCore import QSize
from PyQt5.QtWidgets import QApplication, QWidget

__all__ = ["FIRST_SIZE", "MIN_SIZE", "fit_screen", "essential_widgets"]

FIRST_SIZE = QSize(1366, 768)      # at most: a laptop's screen
MIN_SIZE = QSize(1024, 600)        # a netbook's: still flyable
FRAME_ALLOWANCE = 40               # px a window manager's title bar and borders take


def fit_screen(window: QWidget) -> None:
    """A first size (no saved geometry) that fits the available screen, title bar included."""
    screen = window.screen() if hasattr(window, "screen") else None
    screen = screen or QApplication.primaryScreen()
    if screen is None:
        return
    free = screen.availableGeometry()
    width = max(MIN_SIZE.width(), min(FIRST_SIZE.width(), free.width()))
    height = max(MIN_SIZE.height(), min(FIRST_SIZE.height(), free.height() - FRAME_ALLOWANCE))
    window.resize(width, height)
    window.move(free.topLeft())


def essential_widgets(window) -> dict[str, QWidget]:
    """What a pilot needs in view at every size, by name: attitude, sticks, Take off/Land, Stop, RTL, mode,
    battery, link, the latest autopilot message, what the vehicle is doing."""
    fc, strip = window.flightControls, window.statusStrip
    return {"attitude": window.attitude, "left stick": window.leftStick, "right stick": window.rightStick,
            "take off / land": fc.main_button, "stop": fc.stop_button, "rtl": fc.rtl_button,
            "arm": fc.arm_button, "mode": window.modeSelector, "phase": window.phaseLabel,
            "battery": strip.battery, "link": strip.link, "latest message": strip.message,
            "flight time": strip.flight_time}
