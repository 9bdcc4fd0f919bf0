"""Live bars for RC channels or servo outputs, in microseconds as the vehicle reported them."""
from __future__ import annotations

from PyQt5.QtWidgets import QGridLayout, QLabel, QProgressBar, QWidget

__all__ = ["ChannelBars"]

LOW, HIGH = 800, 2200


class ChannelBars(QWidget):
    """One labelled bar per channel; a channel the vehicle did not send reads "—" (never a guess)."""

    def __init__(self, prefix: str, count: int, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._prefix = prefix
        self._grid = QGridLayout(self)
        self._grid.setContentsMargins(0, 0, 0, 0)
        self._grid.setVerticalSpacing(2)
        self.bars: list[QProgressBar] = []
        self._ensure(count)

    def _ensure(self, count: int) -> None:
        while len(self.bars) < count:
            n = len(self.bars) + 1
            bar = QProgressBar(self)
            bar.setRange(LOW, HIGH)
            bar.setFormat("—")
            bar.setValue(LOW)
            bar.setMaximumHeight(16)
            self._grid.addWidget(QLabel(f"{self._prefix} {n}"), n - 1, 0)
            self._grid.addWidget(bar, n - 1, 1)
            self.bars.append(bar)

    def show_values(self, values: tuple[int, ...]) -> None:
        self._ensure(len(values))
        for i, bar in enumerate(self.bars):
            us = values[i] if i < len(values) else 0
            if us:
                bar.setValue(min(max(us, LOW), HIGH))
                bar.setFormat(f"{us} µs")
            else:
                bar.setValue(LOW)
                bar.setFormat("—")

    def value(self, number: int) -> int | None:
        """What bar ``number`` (1-based) shows, None for "—"."""
        bar = self.bars[number - 1]
        return None if bar.format() == "—" else bar.value()
