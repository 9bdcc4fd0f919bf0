"""Questions that never block the window: window-modal, opened with ``open()``, answered through a callback.

Every question before something that cannot be taken back (the motors start, the vehicle leaves, a key travels
in clear) has one shape: Cancel is the focused default and the Escape button, the action never takes the focus,
so Space (Stop) or Enter can never say yes; only a click does.
"""
from __future__ import annotations

from collections.abc import Callable

from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QMessageBox, QWidget

__all__ = ["ask", "cautious_question"]


def ask(box: QMessageBox, answered: Callable[[QMessageBox], None]) -> QMessageBox:
    """Open a question window-modal without blocking (the window keeps flying meanwhile); ``answered(box)`` runs
    once it closes, however it closes."""
    box.setWindowModality(Qt.WindowModal)
    box.finished.connect(lambda _result: answered(box))
    box.open()
    return box


def cautious_question(parent: QWidget, title: str, text: str, yes: str, name: str,
                      icon: QMessageBox.Icon = QMessageBox.Question) -> QMessageBox:
    """A yes/cancel question whose yes is ``yes`` and only a click away; Cancel is the default and Escape."""
    box = QMessageBox(icon, title, text, QMessageBox.Yes | QMessageBox.Cancel, parent)
    box.setObjectName(name)
    go = box.button(QMessageBox.Yes)
    go.setText(yes)
    go.setFocusPolicy(Qt.NoFocus)
    go.setAutoDefault(False)
    box.setDefaultButton(QMessageBox.Cancel)
    box.setEscapeButton(QMessageBox.Cancel)
    return box
