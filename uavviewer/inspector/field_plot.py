"""One field of one live message plotted as it arrives (the inspector's one-click plot), the last minute."""
from __future__ import annotations

import time
from collections import deque

import pyqtgraph as pg
from PyQt5.QtWidgets import QLabel, QVBoxLayout, QWidget

__all__ = ["FieldPlot"]

SPAN_S = 60.0


class FieldPlot(QWidget):
    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.title = QLabel("Double-click a numeric field to plot it")
        self.plot = pg.PlotWidget()
        self.plot.showGrid(x=True, y=True, alpha=0.2)
        self.plot.setLabel("bottom", "time", units="s")
        self.curve = self.plot.plot(pen=pg.mkPen("#4fc3f7", width=1.5))
        self.key: tuple | None = None                # (system, component, message, field)
        self.points: deque[tuple[float, float]] = deque()
        self._start = time.monotonic()
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.title)
        layout.addWidget(self.plot)

    def follow(self, key: tuple) -> None:
        self.key = key
        self.points.clear()
        self._start = time.monotonic()
        self.title.setText(f"{key[2]}.{key[3]} from {key[0]}/{key[1]}")
        self.curve.setData([], [])

    def add(self, value: float) -> None:
        now = time.monotonic() - self._start
        self.points.append((now, float(value)))
        while self.points and now - self.points[0][0] > SPAN_S:
            self.points.popleft()
        self.curve.setData([p[0] for p in self.points], [p[1] for p in self.points])
