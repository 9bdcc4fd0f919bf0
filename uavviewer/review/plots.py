"""The review's plots: fields of a log on one time axis, a left and a right y-axis, zoom and pan (pyqtgraph), the
log's events as marks on the time axis, and a cursor the pilot drags (its time goes to the map's marker)."""
from __future__ import annotations

import pyqtgraph as pg
from PyQt5.QtCore import pyqtSignal
from PyQt5.QtWidgets import QWidget, QVBoxLayout

__all__ = ["ReviewPlots"]

COLOURS = ["#4fc3f7", "#ffb74d", "#81c784", "#e57373", "#ba68c8", "#fff176", "#4db6ac", "#f06292"]
EVENT_COLOURS = {"mode": "#81c784", "arming": "#ffb74d", "failsafe": "#e57373", "error": "#e57373",
                 "event": "#90a4ae", "message": "#607d8b"}


class ReviewPlots(QWidget):
    cursorMoved = pyqtSignal(float)          # seconds from the log's start

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.widget = pg.PlotWidget()
        self.item = self.widget.getPlotItem()
        self.item.showGrid(x=True, y=True, alpha=0.2)
        self.item.setLabel("bottom", "time", units="s")
        self.legend = self.item.addLegend(offset=(10, 10))
        self.right = pg.ViewBox()
        self.item.showAxis("right")
        self.item.scene().addItem(self.right)
        self.item.getAxis("right").linkToView(self.right)
        self.right.setXLink(self.item)
        self.item.vb.sigResized.connect(self._fit_right)
        self.cursor = pg.InfiniteLine(0.0, movable=True, pen=pg.mkPen("#ffffff", width=1))
        self.item.addItem(self.cursor, ignoreBounds=True)
        self.cursor.sigPositionChanged.connect(lambda line: self.cursorMoved.emit(float(line.value())))
        self.curves: dict[tuple[str, str], tuple[pg.PlotDataItem, int]] = {}
        self.event_marks: list[pg.InfiniteLine] = []
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.widget)

    def _fit_right(self) -> None:
        self.right.setGeometry(self.item.vb.sceneBoundingRect())
        self.right.linkedViewChanged(self.item.vb, self.right.XAxis)

    def add(self, key: tuple[str, str], t, values, axis: int = 0) -> None:
        """One field; ``axis`` 0 the left y-axis, 1 the right (drawn dashed)."""
        if key in self.curves:
            return
        colour = COLOURS[len(self.curves) % len(COLOURS)]
        pen = pg.mkPen(colour, width=1.5, style=pg.QtCore.Qt.DashLine if axis else pg.QtCore.Qt.SolidLine)
        curve = pg.PlotDataItem(t, values, pen=pen, name=f"{key[0]}.{key[1]}" + (" (right)" if axis else ""))
        if axis:
            self.right.addItem(curve)
            self.legend.addItem(curve, curve.name())
            self.right.enableAutoRange()
        else:
            self.item.addItem(curve)
        curve.setDownsampling(auto=True, method="peak")     # a 100 MB log's field: drawn at the pixels' rate
        curve.setClipToView(True)
        self.curves[key] = (curve, axis)

    def clear_fields(self) -> None:
        for curve, axis in self.curves.values():
            (self.right if axis else self.item).removeItem(curve)
            self.legend.removeItem(curve)
        self.curves.clear()

    def show_events(self, events) -> None:
        for mark in self.event_marks:
            self.item.removeItem(mark)
        self.event_marks = []
        for e in events:
            if e.kind == "message":
                pen = pg.mkPen(EVENT_COLOURS[e.kind], width=1, style=pg.QtCore.Qt.DotLine)
            else:
                pen = pg.mkPen(EVENT_COLOURS.get(e.kind, "#90a4ae"), width=1)
            mark = pg.InfiniteLine(e.t, pen=pen, label=e.text if e.kind != "message" else None,
                                   labelOpts={"position": 0.08, "color": EVENT_COLOURS.get(e.kind), "rotateAxis": (1, 0)})
            mark.setToolTip(f"{e.t:.1f} s  {e.kind}: {e.text}")
            self.item.addItem(mark, ignoreBounds=True)
            self.event_marks.append(mark)

    def set_cursor(self, t: float) -> None:
        self.cursor.setValue(t)
