"""Questions that never block the window: window-modal, opened with ``open()``, answered through a callback.

Every question before something that cannot be taken back (the motors start, the vehicle leaves, a key travels
in clear) has one shape: Cancel is the focused default and the Escape button, the action never takes the focus,
so Space (Stop) or Enter can never say yes: a click does, or, where the question names one, its own key (T takes
off, as T asked: a pilot flying by keyboard needs no mouse). A key held down (its repeats) never answers.
"""
from __future__ import annotations

from collections.abc import Callable

from PyQt5.QtCore import QEvent, QObject, Qt
from PyQt5.QtWidgets import QMessageBox, QWidget

__all__ = ["ask", "cautious_question", "warning_question"]


def ask(box: QMessageBox, answered: Callable[[QMessageBox], None]) -> QMessageBox:
    """Open a question window-modal without blocking (the window keeps flying meanwhile); ``answered(box)`` runs
    once it closes, however it closes."""
    box.setWindowModality(Qt.WindowModal)
    box.finished.connect(lambda _result: answered(box))
    box.open()
    return box


class _NoRepeats(QObject):
    """A key held down: its repeats never reach the question (T held after asking must not say yes)."""

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:  # noqa: N802 (Qt's name)
        return event.type() in (QEvent.KeyPress, QEvent.ShortcutOverride) and event.isAutoRepeat()


def cautious_question(parent: QWidget, title: str, text: str, yes: str, name: str,
                      icon: QMessageBox.Icon = QMessageBox.Question, key: str = "") -> QMessageBox:
    """A yes/cancel question whose yes is ``yes`` and only a click away, or its ``key`` (a letter in ``yes``, said
    in the text; pressed on its own or with Alt); Cancel is the default and Escape."""
    if key:
        at = yes.lower().index(key.lower())
        text += f"\n\n{key.upper()}: {yes.lower()}. Enter or Esc: cancel."
        yes = f"{yes[:at]}&{yes[at:]}"
    box = QMessageBox(icon, title, text, QMessageBox.Yes | QMessageBox.Cancel, parent)
    box.setObjectName(name)
    go = box.button(QMessageBox.Yes)
    go.setText(yes)
    go.setFocusPolicy(Qt.NoFocus)
    go.setAutoDefault(False)
    box.setDefaultButton(QMessageBox.Cancel)
    box.setEscapeButton(QMessageBox.Cancel)
    box.installEventFilter(_NoRepeats(box))
    return box


def warning_question(parent: QWidget, name: str, title: str, text: str, *buttons) -> tuple[QMessageBox, list]:
    """A warning with ``buttons`` ((label, role) each, returned as made) and Cancel, the default for Enter and
    Escape: nothing is lost by a key pressed too soon."""
    box = QMessageBox(QMessageBox.Warning, title, text, QMessageBox.NoButton, parent)
    box.setObjectName(name)
    added = [box.addButton(label, role) for label, role in buttons]
    box.addButton(QMessageBox.Cancel)
    box.setDefaultButton(QMessageBox.Cancel)
    box.setEscapeButton(QMessageBox.Cancel)
    return box, added
