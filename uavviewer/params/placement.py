"""Where the Parameters window stands: beside the flight controls, never over them.

A pilot may open Parameters in flight (a warning's Fix…). It used to open centred on the main window, over Stop,
RTL and the attitude indicator. Now it opens to the right of the attitude indicator and the buttons' column, as
tall as the screen allows, so that Land, Stop, RTL, Arm, the mode and the attitude stay in view and in reach. Where
the pilot moves or resizes it is remembered (``parameters/geometry``) and used the next time, clamped to the
screen it opens on.
"""
from __future__ import annotations

from PyQt5.QtCore import QPoint, QRect, QSettings
from PyQt5.QtWidgets import QWidget

from ..widgets.dialog_fit import FRAME_ALLOWANCE, fit_dialog

__all__ = ["GEOMETRY_KEY", "GAP", "keep_clear", "place", "remember"]

GEOMETRY_KEY = "parameters/geometry"
GAP = 8                                   # px between the flight controls and the window


def keep_clear(window: QWidget) -> list[QRect]:
    """What the Parameters window must never cover, in screen coordinates: the attitude indicator and the
    column of Take off/Land, Stop, RTL, Arm and the mode (a window without them: nothing)."""
    rects = []
    for name in ("attitude", "controlsFrame"):
        widget = getattr(window, name, None)
        if isinstance(widget, QWidget) and widget.isVisible():
            rects.append(QRect(widget.mapToGlobal(QPoint(0, 0)), widget.size()))
    return rects


def place(page: QWidget, window: QWidget, settings: QSettings | None) -> None:
    """Its remembered place, else beside the flight controls; clamped to the screen either way."""
    saved = settings.value(GEOMETRY_KEY) if settings is not None else None
    if saved is not None and page.restoreGeometry(saved):
        fit_dialog(page)
        return
    screen = window.screen() if window.screen() is not None else page.screen()
    free = screen.availableGeometry()
    if not free.contains(window.frameGeometry()):   # a window larger than its screen (a virtual one): its area
        free = free.united(window.frameGeometry())
    clear = keep_clear(window)
    left = max([r.right() + 1 + GAP for r in clear], default=free.left())
    width = max(page.minimumSizeHint().width(), free.right() + 1 - left)
    left = min(left, free.right() + 1 - width)
    top = window.frameGeometry().top() if window.isVisible() else free.top()
    height = free.bottom() + 1 - top - FRAME_ALLOWANCE
    page.resize(width, max(page.minimumSizeHint().height(), height))
    page.move(max(left, free.left()), max(top, free.top()))


def remember(page: QWidget, settings: QSettings | None) -> None:
    if settings is not None:
        settings.setValue(GEOMETRY_KEY, page.saveGeometry())
