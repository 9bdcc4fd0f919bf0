"""Shows the flight mode and lets the pilot pick another."""
from __future__ import annotations

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import QComboBox, QWidget

__all__ = ["ModeSelector", "COPTER_MODES"]

COPTER_MODES = ("STABILIZE", "ALT_HOLD", "LOITER", "GUIDED", "POSHOLD", "BRAKE", "AUTO", "RTL",
                "SMART_RTL", "LAND", "CIRCLE", "DRIFT", "SPORT", "ACRO")


class ModeSelector(QComboBox):
    """The current mode is the selection; choosing another emits ``modeRequested``.

    The selection snaps back to the vehicle's real mode on the next snapshot, so
    it never shows a mode the vehicle refused.
    """

    modeRequested = pyqtSignal(str)

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("modeSelector")
        self.setFocusPolicy(Qt.NoFocus)     # arrow keys fly; they must not change the mode
        self.setMinimumWidth(130)
        self.setPlaceholderText("Mode")
        self.setToolTip("Flight mode: the vehicle's own, as it reports it")
        self.addItems(COPTER_MODES)
        self._mode = ""
        self.setCurrentIndex(-1)
        self.activated.connect(self._picked)

    @property
    def mode(self) -> str:
        return self._mode

    def modes(self) -> list[str]:
        return [self.itemText(i) for i in range(self.count())]

    def refuse(self, reasons: dict[str, str | None]) -> None:
        """Grey out the modes the driver will not command now, each with why in its tooltip (the vehicle's
        current mode stays shown)."""
        model = self.model()
        for i in range(self.count()):
            reason = reasons.get(self.itemText(i))
            item = model.item(i)
            enabled = reason is None or self.itemText(i) == self._mode
            if item.isEnabled() != enabled:
                item.setEnabled(enabled)
            self.setItemData(i, reason, Qt.ToolTipRole)

    def set_mode(self, name: str) -> None:
        if name == self._mode or self.view().isVisible():
            return
        self._mode = name
        if name and self.findText(name) < 0:
            self.addItem(name)
        self.blockSignals(True)
        self.setCurrentIndex(self.findText(name) if name else -1)
        self.blockSignals(False)

    def wheelEvent(self, event) -> None:  # noqa: N802 (Qt name)
        """A stray scroll over the selector must never change the flight mode; only a pick from the list."""
        event.ignore()

    def _picked(self, index: int) -> None:
        name = self.itemText(index)
        if name and name != self._mode:
            self.modeRequested.emit(name)
        # Show the real mode until the vehicle confirms the change.
        self.blockSignals(True)
        self.setCurrentIndex(self.findText(self._mode) if self._mode else -1)
        self.blockSignals(False)
