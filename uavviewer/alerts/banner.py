"""A thin strip above the instruments with the latest critical alert, until the pilot dismisses it."""
from __future__ import annotations

import time

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import QHBoxLayout, QLabel, QSizePolicy, QToolButton, QWidget

from driver.vehicle.state import Severity

__all__ = ["AlertBanner"]

_STYLE = """
QWidget#alertBanner[level="critical"] { background: #b3261e; border-radius: 4px; }
QWidget#alertBanner[level="warning"] { background: #8a5a00; border-radius: 4px; }
QWidget#alertBanner QLabel { color: #ffffff; font-weight: bold; }
QWidget#alertBanner QToolButton { color: #ffffff; border: none; font-weight: bold; padding: 0 6px; }
"""


class AlertBanner(QWidget):
    """Hidden until a critical alert; one line (the newest, with how many more came), a ✕ to dismiss. It never
    takes the keyboard focus, so keys keep flying."""

    dismissed = pyqtSignal()

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("alertBanner")
        self.setAttribute(Qt.WA_StyledBackground, True)
        self.setStyleSheet(_STYLE)
        self.label = QLabel()
        self.label.setObjectName("alertText")
        self.label.setTextInteractionFlags(Qt.NoTextInteraction)
        self.label.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Preferred)   # cut, never widens the window
        self.close_button = QToolButton()
        self.close_button.setObjectName("alertDismiss")
        self.close_button.setText("✕")
        self.close_button.setToolTip("Dismiss (the alert stays in Messages)")
        self.close_button.setFocusPolicy(Qt.NoFocus)
        row = QHBoxLayout(self)
        row.setContentsMargins(8, 2, 2, 2)
        row.addWidget(self.label, 1)
        row.addWidget(self.close_button)
        self.setFixedHeight(26)
        self._count = 0
        self.close_button.clicked.connect(self.dismiss)
        self.setVisible(False)

    @property
    def text(self) -> str:
        return self.label.text()

    def show_alert(self, text: str, severity: Severity, when: float = 0.0) -> None:
        """``when``: the event's wall clock (a replay's is the recording's); now when 0."""
        self._count = self._count + 1 if self.isVisible() else 1
        more = f"  (+{self._count - 1} more in Messages)" if self._count > 1 else ""   # before the text: a long
        self.label.setText(f"{time.strftime('%H:%M:%S', time.localtime(when or None))}{more}  {text}")   # one is cut
        self.label.setToolTip(text)
        level = "critical" if severity <= Severity.CRITICAL else "warning"
        if self.property("level") != level:
            self.setProperty("level", level)
            self.style().unpolish(self)
            self.style().polish(self)
        self.setVisible(True)

    def clear_if(self, words: str) -> None:
        """Hide the banner when what it shows is over (``words`` in its text: "Link lost" once recovered)."""
        if self.isVisible() and words in self.label.text() and self._count == 1:
            self.dismiss()

    def dismiss(self) -> None:
        self._count = 0
        self.setVisible(False)
        self.dismissed.emit()
