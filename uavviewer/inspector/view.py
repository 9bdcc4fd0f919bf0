"""Tools › MAVLink inspector: every message type from every system and component with its rate and
count, the selected message's fields updating in place, and a double-click to plot a field."""
from __future__ import annotations

import math

from PyQt5.QtCore import Qt, QTimer
from PyQt5.QtWidgets import (QLabel, QSplitter, QTableWidget, QTableWidgetItem, QTreeWidget, QTreeWidgetItem,
                             QVBoxLayout, QWidget)

from driver.vehicle.inspector import Inspection

from ..widgets.dialog_fit import close_buttons, closes_with_esc
from .field_plot import FieldPlot

__all__ = ["InspectorWindow", "REFRESH_MS"]

REFRESH_MS = 200


def _text(v) -> str:
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_text(x) for x in v) + "]"
    return str(v)


class InspectorWindow(QWidget):
    """``inspect``: a callable giving an :class:`Inspection` (the adapter's), read every REFRESH_MS while shown."""

    def __init__(self, inspect, parent: QWidget | None = None) -> None:
        super().__init__(parent, Qt.Window)
        self.setWindowTitle("MAVLink inspector")
        self.setObjectName("inspectorWindow")
        self.setAttribute(Qt.WA_QuitOnClose, False)
        self._inspect = inspect
        self.note = QLabel()
        self.note.setWordWrap(True)
        self.tree = QTreeWidget()
        self.tree.setHeaderLabels(["Component / message", "Hz", "count"])
        self.tree.setSortingEnabled(False)
        self.fields = QTableWidget(0, 2)
        self.fields.setHorizontalHeaderLabels(["Field", "Value"])
        self.fields.horizontalHeader().setStretchLastSection(True)
        self.fields.setEditTriggers(QTableWidget.NoEditTriggers)
        self.field_plot = FieldPlot()
        right = QSplitter(Qt.Vertical)
        right.addWidget(self.fields)
        right.addWidget(self.field_plot)
        split = QSplitter(Qt.Horizontal)
        split.addWidget(self.tree)
        split.addWidget(right)
        split.setSizes([380, 520])
        layout = QVBoxLayout(self)
        layout.addWidget(self.note)
        layout.addWidget(split, 1)
        layout.addWidget(close_buttons(self))         # and Esc: a window of its own closes as a dialog does
        closes_with_esc(self)
        self._components: dict[tuple[int, int], QTreeWidgetItem] = {}
        self._messages: dict[tuple[int, int, str], QTreeWidgetItem] = {}
        self.selected: tuple[int, int, str] | None = None
        self.inspection: Inspection | None = None
        self._plotted_count = -1
        self.tree.currentItemChanged.connect(self._pick)
        self.fields.cellDoubleClicked.connect(self._plot_field)
        self.timer = QTimer(self)
        self.timer.setInterval(REFRESH_MS)
        self.timer.timeout.connect(self.refresh)
        self.resize(900, 600)

    def showEvent(self, event) -> None:  # noqa: N802
        self.refresh()
        self.timer.start()
        super().showEvent(event)

    def hideEvent(self, event) -> None:  # noqa: N802
        self.timer.stop()
        super().hideEvent(event)

    # -- the tree, updated in place -----------------------------------------------------------------------------
    def refresh(self) -> None:
        seen = self._inspect()
        self.inspection = seen
        if not seen.available:
            self.note.setText(f"No inspector for this connection: {seen.why}.")
            return
        self.note.setText(f"{len(seen.messages)} message types from {len({(m.system, m.component) for m in seen.messages})}"
                          " components. Pick a message to see its fields; double-click a field to plot it.")
        for m in seen.messages:
            comp = self._components.get((m.system, m.component))
            if comp is None:
                comp = QTreeWidgetItem([f"system {m.system}, component {m.component}", "", ""])
                self._components[(m.system, m.component)] = comp
                self.tree.addTopLevelItem(comp)
                comp.setExpanded(True)
            key = (m.system, m.component, m.name)
            item = self._messages.get(key)
            if item is None:
                item = QTreeWidgetItem([m.name, "", ""])
                item.setData(0, Qt.UserRole, key)
                self._messages[key] = item
                comp.addChild(item)
                comp.sortChildren(0, Qt.AscendingOrder)
            item.setText(1, f"{m.rate_hz:.1f}")
            item.setText(2, str(m.count))
            if key == self.selected:
                self._show_fields(m)
            self._feed_plot(m)
        self.tree.resizeColumnToContents(0)

    def _pick(self, item, _previous=None) -> None:
        self.selected = item.data(0, Qt.UserRole) if item is not None else None
        self.fields.setRowCount(0)
        if self.selected and self.inspection is not None:
            for m in self.inspection.messages:
                if (m.system, m.component, m.name) == self.selected:
                    self._show_fields(m)

    def select(self, system: int, component: int, name: str) -> bool:
        item = self._messages.get((system, component, name))
        if item is not None:
            self.tree.setCurrentItem(item)
        return item is not None

    def _show_fields(self, m) -> None:
        if self.fields.rowCount() != len(m.fields):
            self.fields.setRowCount(len(m.fields))
            for row, (name, _v) in enumerate(m.fields):
                self.fields.setItem(row, 0, QTableWidgetItem(name))
                self.fields.setItem(row, 1, QTableWidgetItem(""))
        for row, (_name, value) in enumerate(m.fields):
            cell = self.fields.item(row, 1)
            text = _text(value)
            if cell.text() != text:
                cell.setText(text)

    def _feed_plot(self, m) -> None:
        """The plotted field's newest value, whichever message is selected now (the plot follows its own key)."""
        plot = self.field_plot.key
        if plot is not None and plot[:3] == (m.system, m.component, m.name) and m.count != self._plotted_count:
            self._plotted_count = m.count
            value = dict(m.fields).get(plot[3])
            if isinstance(value, (int, float)) and math.isfinite(value):
                self.field_plot.add(value)

    def _plot_field(self, row: int, _column: int = 0) -> None:
        if self.selected is None:
            return
        self.field_plot.follow((*self.selected, self.fields.item(row, 0).text()))
        self._plotted_count = -1
