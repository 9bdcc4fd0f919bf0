"""The go / no-go panel: one verdict on top, one line per check with its reason."""
from __future__ import annotations

from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QFrame, QGridLayout, QLabel, QScrollArea, QVBoxLayout, QWidget

from .model import Check, Verdict

__all__ = ["PreflightPanel"]

COLOURS = {Verdict.GO: "#2e9d4f", Verdict.UNKNOWN: "#6b6f76", Verdict.CAUTION: "#c98a00", Verdict.NO_GO: "#c62828"}
HEADLINES = {Verdict.GO: "GO", Verdict.UNKNOWN: "NOT YET KNOWN", Verdict.CAUTION: "GO, WITH CAUTIONS",
             Verdict.NO_GO: "NO GO"}


class PreflightPanel(QWidget):
    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("preflightPanel")
        self.headline = QLabel()
        self.headline.setObjectName("preflightHeadline")
        self.headline.setAlignment(Qt.AlignCenter)
        self._grid = QGridLayout()
        self._grid.setColumnStretch(2, 1)
        self._grid.setHorizontalSpacing(8)
        self._rows: dict[str, tuple[QLabel, QLabel, QLabel]] = {}
        lines = QWidget()                            # scrolls in a short dock rather than clipping a reason
        inner = QVBoxLayout(lines)
        inner.setContentsMargins(0, 0, 0, 0)
        inner.addLayout(self._grid)
        inner.addStretch(1)
        scroll = QScrollArea()
        scroll.setWidgetResizable(True)
        scroll.setFrameShape(QFrame.NoFrame)
        scroll.setWidget(lines)
        box = QVBoxLayout(self)
        box.setContentsMargins(6, 6, 6, 6)
        box.addWidget(self.headline)
        box.addWidget(scroll, 1)
        self._shown: tuple = ()

    def set_checks(self, checks: list[Check], verdict: Verdict) -> None:
        key = (tuple(checks), verdict)
        if key == self._shown:
            return                                   # 10 Hz of the same verdicts: nothing to redraw
        self._shown = key
        self.headline.setText(HEADLINES[verdict])
        self.headline.setStyleSheet(f"background: {COLOURS[verdict]}; color: white; font-weight: bold; "
                                    "font-size: 15px; padding: 4px; border-radius: 4px;")
        for row, check in enumerate(checks):
            if check.name not in self._rows:
                labels = (QLabel(), QLabel(check.name), QLabel())
                labels[2].setWordWrap(True)
                for column, label in enumerate(labels):
                    self._grid.addWidget(label, row, column, Qt.AlignTop)
                self._rows[check.name] = labels
            badge, _, reason = self._rows[check.name]
            badge.setText(check.verdict.label)
            badge.setStyleSheet(f"color: {COLOURS[check.verdict]}; font-weight: bold;")
            reason.setText(check.reason)

    def verdict_of(self, name: str) -> str:
        """The badge shown for ``name`` ("GO", "NO GO", ...), for tests and the screenshot's reader."""
        return self._rows[name][0].text() if name in self._rows else ""

    def reason_of(self, name: str) -> str:
        return self._rows[name][2].text() if name in self._rows else ""
