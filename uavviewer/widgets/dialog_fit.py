"""Every window besides the flying one fits the screen it opens on, closes with Esc and a Close button, and can stand
clear of what must stay in view (Preferences was taller than a 1280×720 screen, its OK button off it; Review opened
at 1366×768 on a 1024×600 screen; the MAVLink inspector had neither Close nor Esc; Setup covered Land and Stop).

The parts, none knowing any feature:

- :func:`scrollable` puts a window's content in a scroll area (its buttons stay outside, always shown), so the
  window can be as small as the room it is given;
- :func:`close_buttons` is the row with the Close button, :func:`closes_with_esc` gives a window that is not a
  dialog the Esc a dialog has;
- :func:`fit_window` clamps a window to an area of the screen (a title bar's room left) and moves it inside, and,
  given rectangles to keep clear, puts it in the largest part of the area beside them.

The flying window's own piece (``uavviewer/window/secondary.py``) calls :func:`fit_window` for every window as it
is shown, whichever part of the program opened it: our own windows, message boxes, Qt's input and file dialogs.
"""
from __future__ import annotations

from collections.abc import Sequence

from PyQt5.QtCore import QEvent, QObject, QRect, QSize, Qt
from PyQt5.QtWidgets import QApplication, QDialog, QDialogButtonBox, QFrame, QScrollArea, QSplitter, QWidget

FRAME_ALLOWANCE = 40               # px a window manager's title bar and borders take
GAP = 8                            # px between a window and what it keeps clear of
NARROW = 760                       # px: a window narrower than this stacks its side-by-side parts

__all__ = ["FRAME_ALLOWANCE", "GAP", "NARROW", "close_buttons", "closes_with_esc", "fit_dialog", "fit_window",
           "room_beside", "scrollable", "stack_when_narrow"]


def scrollable(content: QWidget, horizontal: bool = False) -> QScrollArea:
    """``content`` in a frameless scroll area that scrolls vertically only when the screen is too short for it;
    ``horizontal``: sideways too, when the room it is given is narrower than ``content`` needs (else the area is
    as wide as ``content`` needs at least)."""
    area = QScrollArea()
    area.setFrameShape(QFrame.NoFrame)
    area.setWidgetResizable(True)
    area.setWidget(content)
    if horizontal:
        area.setMinimumWidth(0)
    else:
        area.setHorizontalScrollBarPolicy(Qt.ScrollBarAlwaysOff)
        area.setMinimumWidth(content.minimumSizeHint().width() + area.verticalScrollBar().sizeHint().width())
    return area


def stack_when_narrow(splitter: QSplitter, width: int, wide: list[int], narrow: list[int]) -> None:
    """A window ``width`` px wide: its ``splitter``'s parts side by side (``wide`` sizes) when roomy, one above the
    other (``narrow`` sizes) beside the flight controls, each as wide as the window (side by side at 430 px, a
    table or a field tree was left 50 px)."""
    stacked = width < NARROW
    if stacked != (splitter.orientation() == Qt.Vertical):
        splitter.setOrientation(Qt.Vertical if stacked else Qt.Horizontal)
        splitter.setSizes(narrow if stacked else wide)


def close_buttons(window: QWidget) -> QDialogButtonBox:
    """The row with the window's Close button (a dialog is rejected, any other window closed): Esc's twin."""
    box = QDialogButtonBox(QDialogButtonBox.Close)
    box.rejected.connect(window.reject if isinstance(window, QDialog) else window.close)
    return box


class _EscCloses(QObject):
    """Watches the window itself: an Esc reaches it only when no widget inside took it, as a dialog's does."""

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:  # noqa: N802 (Qt's name)
        if event.type() == QEvent.KeyPress and event.key() == Qt.Key_Escape and not event.modifiers():
            watched.close()
            return True
        return False


def closes_with_esc(window: QWidget) -> QObject:
    """Esc closes ``window`` as it closes a dialog (a field that uses Esc itself, an open list, takes it first)."""
    closer = _EscCloses(window)
    window.installEventFilter(closer)
    return closer


def room_beside(area: QRect, keep_clear: Sequence[QRect], least: QSize) -> QRect | None:
    """The largest part of ``area`` beside the rectangles ``keep_clear`` (right of them, left, below, above: as
    wide or tall as the area) that is at least ``least``; None if none is."""
    clear = [r.intersected(area) for r in keep_clear]
    clear = [r for r in clear if not r.isEmpty()]
    if not clear:
        return area
    block = clear[0]
    for r in clear[1:]:
        block = block.united(r)
    rooms = [QRect(block.right() + 1 + GAP, area.top(), area.right() - block.right() - GAP, area.height()),
             QRect(area.left(), area.top(), block.left() - GAP - area.left(), area.height()),
             QRect(area.left(), block.bottom() + 1 + GAP, area.width(), area.bottom() - block.bottom() - GAP),
             QRect(area.left(), area.top(), area.width(), block.top() - GAP - area.top())]
    fitting = [r for r in rooms if r.width() >= least.width() and r.height() >= least.height()]
    return max(fitting, key=lambda r: r.width() * r.height()) if fitting else None


def fit_window(window: QWidget, keep_clear: Sequence[QRect] = (), area: QRect | None = None) -> bool:
    """Clamp ``window`` to ``area`` (its screen's available area if not given), title bar included, and move it
    inside; with ``keep_clear`` (screen rectangles), into the largest room beside them, as large as that room allows
    (never below its minimum size). False if no room beside them holds the window (it is then only fitted)."""
    if area is None:
        screen = window.screen() if hasattr(window, "screen") else None
        screen = screen or QApplication.primaryScreen()
        if screen is None:
            return False
        area = screen.availableGeometry()
    frame = window.frameGeometry()
    sides = frame.width() - window.width()           # the frame's borders, where the platform already knows them
    least = window.minimumSizeHint().expandedTo(window.minimumSize())
    room = room_beside(area, keep_clear, QSize(least.width() + sides, least.height() + FRAME_ALLOWANCE)) \
        if keep_clear else area
    placed = room is not None
    room = room if room is not None else area
    width = max(least.width(), min(window.width(), room.width() - sides))
    height = max(least.height(), min(window.height(), room.height() - FRAME_ALLOWANCE))
    if (width, height) != (window.width(), window.height()):
        window.resize(width, height)
    x = min(max(frame.x(), room.left()), room.right() + 1 - width - sides)
    y = min(max(frame.y(), room.top()), room.bottom() + 1 - height - FRAME_ALLOWANCE)
    x, y = max(x, room.left()), max(y, room.top())
    if (x, y) != (frame.x(), frame.y()):
        window.move(x, y)
    return placed


def fit_dialog(dialog: QWidget) -> None:
    """Clamp ``dialog`` to its screen's available area, title bar included, and move it inside."""
    fit_window(dialog)
