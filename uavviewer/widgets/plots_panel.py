"""Altitude, velocities and attitude over the last minute (pyqtgraph).

Samples go into fixed numpy ring buffers as they arrive; curves are redrawn by
a slower timer so plotting never competes with the 30 Hz instruments.
"""
from __future__ import annotations

import numpy as np
import pyqtgraph as pg
from PyQt5.QtGui import QFont
from PyQt5.QtWidgets import QVBoxLayout, QWidget

__all__ = ["PlotsPanel", "SERIES"]

# series name -> (plot row, colour, legend)
SERIES = {
    "altitude": (0, "#5fd068", "altitude m"),
    "forward": (1, "#4ea3ff", "forward m/s"),
    "right": (1, "#ffb020", "right m/s"),
    "climb": (1, "#5fd068", "climb m/s"),
    "roll": (2, "#ff6b5b", "roll °"),
    "pitch": (2, "#4ea3ff", "pitch °"),
    "heading": (3, "#d8dee6", "heading °"),
}
_TITLES = ("Alt m", "Vel m/s", "Att °", "Hdg °")
# plot row -> the smallest y span shown, so a vehicle sitting still does not magnify its noise
MIN_SPAN = (4.0, 2.0, 10.0)
AXIS_WIDTH = 62        # px for the left axis of every plot (title + "-0.5"), so their time axes line up
TICK_FONT_PX = 11
# series that wrap (degrees): no line is drawn across the wrap, which would look like a turn through south
WRAPS = {"heading": 360.0}


def _tick_font() -> QFont:
    font = QFont()
    font.setPixelSize(TICK_FONT_PX)
    return font


def _connections(y: np.ndarray, wrap: float | None) -> np.ndarray | str:
    """Which points join the next: finite neighbours, and for a wrapping series not across the wrap."""
    if wrap is None:
        return "finite"
    joined = np.zeros(y.size, dtype=bool)
    with np.errstate(invalid="ignore"):
        joined[:-1] = np.abs(np.diff(y)) < wrap / 2           # NaN compares False: gaps stay open too
    return joined


class PlotsPanel(QWidget):
    WINDOW_S = 60.0

    def __init__(self, parent: QWidget | None = None, capacity: int = 60 * 30 + 64) -> None:
        """Samples go in with :meth:`append`; the owner calls :meth:`redraw` at the rate the eye needs (the
        window's refresh channel), so nothing is drawn while nobody sees it."""
        super().__init__(parent)
        self.setObjectName("plotsPanel")
        pg.setConfigOptions(antialias=False, background="#12161c", foreground="#aab4be")
        self._cap = capacity
        self._t = np.zeros(capacity)
        self._data = {name: np.zeros(capacity) for name in SERIES}
        self._n = 0            # samples written in total
        self._dirty = False
        self.graphics = pg.GraphicsLayoutWidget()
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.graphics)
        self.plots = []
        for row, title in enumerate(_TITLES):
            plot = self.graphics.addPlot(row=row, col=0)
            plot.setLabel("left", title)
            plot.getAxis("left").enableAutoSIPrefix(False)     # never "(x0.001)"
            plot.getAxis("left").setWidth(AXIS_WIDTH)            # the four time axes line up
            for side in ("left", "bottom"):
                plot.getAxis(side).setStyle(tickFont=_tick_font())
            plot.showGrid(x=True, y=True, alpha=0.2)
            plot.setXRange(-self.WINDOW_S, 0, padding=0)
            plot.setMouseEnabled(x=False, y=False)
            plot.hideButtons()
            plot.setMenuEnabled(False)
            legend = plot.addLegend(offset=(5, 2), labelTextSize="8pt", verSpacing=-6)
            legend.setColumnCount(3)            # one line across the top: a narrow dock's short plots stay readable
            plot.getAxis("bottom").setTickSpacing(20, 10)    # -60 -40 -20 0: no labels run into each other
            if row:
                plot.setXLink(self.plots[0])
            if row < len(_TITLES) - 1:
                plot.getAxis("bottom").setStyle(showValues=False)
            self.plots.append(plot)
        self.plots[-1].setYRange(0, 360)
        self.plots[-1].setLabel("bottom", "time before now", units="s", **{"font-size": "9pt"})   # with its unit
        self.plots[-1].getAxis("bottom").enableAutoSIPrefix(False)
        self.curves = {name: self.plots[row].plot(pen=pg.mkPen(color, width=1.5), name=legend)
                       for name, (row, color, legend) in SERIES.items()}

    @property
    def sample_count(self) -> int:
        return min(self._n, self._cap)

    def append(self, t: float, **values: float) -> None:
        """One sample at time ``t`` (seconds, any monotonic origin); unknown names are ignored."""
        i = self._n % self._cap
        self._t[i] = t
        for name, arr in self._data.items():
            v = values.get(name, np.nan)
            arr[i] = v if v is not None else np.nan
        self._n += 1
        self._dirty = True

    def gap(self, t: float) -> None:
        """Break every line at ``t`` (link lost, replay paused): no line is drawn across missing data."""
        self.append(t)

    def clear(self) -> None:
        self._n = 0
        self._dirty = True

    def _ordered(self, arr: np.ndarray) -> np.ndarray:
        if self._n <= self._cap:
            return arr[: self._n]
        i = self._n % self._cap
        return np.concatenate((arr[i:], arr[:i]))

    def redraw(self) -> None:
        if not self._dirty or not self.isVisible():
            return
        self._dirty = False
        t = self._ordered(self._t)
        if t.size == 0:
            for curve in self.curves.values():
                curve.setData([], [])
            return
        x = t - t[-1]
        keep = x >= -self.WINDOW_S
        x = x[keep]
        shown = {name: self._ordered(self._data[name])[keep] for name in self.curves}
        for name, curve in self.curves.items():
            curve.setData(x, shown[name], connect=_connections(shown[name], WRAPS.get(name)))
        for row, span in enumerate(MIN_SPAN):
            values = np.concatenate([shown[name] for name, (r, _, _) in SERIES.items() if r == row])
            values = values[np.isfinite(values)]
            lo, hi = (float(values.min()), float(values.max())) if values.size else (0.0, 0.0)
            if hi - lo < span:
                mid = (lo + hi) / 2.0
                lo, hi = mid - span / 2.0, mid + span / 2.0
            self.plots[row].setYRange(lo, hi, padding=0.05)

    def y_range(self, row: int) -> tuple[float, float]:
        """The y range a plot shows (for tests)."""
        lo, hi = self.plots[row].viewRange()[1]
        return float(lo), float(hi)

    def curve_points(self, name: str) -> int:
        """How many points a curve shows (for tests)."""
        xs, _ = self.curves[name].getData()
        return 0 if xs is None else len(xs)
