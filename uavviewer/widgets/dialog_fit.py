"""Every dialog fits the screen it opens on, its buttons in reach (issue 29: Preferences was taller than a
1280×720 screen, its OK button off it).

Two parts: :func:`scrollable` puts a dialog's tall content in a scroll area (its buttons stay outside, always
shown); :func:`fit_dialog` clamps a dialog to the screen's available area (a title bar's room left) and moves it
inside. The main window's application-wide event filter calls it for every dialog as it is shown, whichever part
of the program opened it — our own dialogs, message boxes, Qt's input and file dialogs.
"""
from __future__ import annotations

from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QApplication, QFrame, QScrollArea, QWidget

FRAME_ALLOWANCE = 40               # px a window manager's title bar and borders take

__all__ = ["FRAME_ALLOWANCE", "fit_dialog", "scrollable"]


def scrollable(content: QWidget) -> QScrollArea:
    """``content`` in a frameless scroll area that scrolls vertically only when the screen is too short for it."""
    area = QScrollArea()
    area.setFrameShape(QFrame.NoFrame)
    area.setWidgetResizable(True)
    area.setHorizontalScrollBarPolicy(Qt.ScrollBarAlwaysOff)
    area.setWidget(content)
    area.setMinimumWidth(content.minimumSizeHint().width() + area.verticalScrollBar().sizeHint().width())
    return area


def fit_dialog(dialog: QWidget) -> None:
    """Clamp ``dialog`` to its screen's available area, title bar included, and move it inside."""
    screen = dialog.screen() if hasattr(dialog, "screen") else None
    screen = screen or QApplication.primaryScreen()
    if screen is None:
        return
    free = screen.availableGeometry()
    frame = dialog.frameGeometry()
    sides = frame.width() - dialog.width()           # the frame's borders, where the platform already knows them
    width = min(dialog.width(), free.width() - sides)
    height = min(dialog.height(), free.height() - FRAME_ALLOWANCE)
    if (width, height) != (dialog.width(), dialog.height()):
        dialog.resize(width, height)
    x = min(max(frame.x(), free.left()), free.right() + 1 - width - sides)
    y = min(max(frame.y(), free.top()), free.bottom() + 1 - height - FRAME_ALLOWANCE)
    if (x, y) != (frame.x(), frame.y()):
        dialog.move(max(x, free.left()), max(y, free.top()))

