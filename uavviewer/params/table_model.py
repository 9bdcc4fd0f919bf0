"""The vehicle's parameters as a Qt table: one row per parameter, the values from the newest ParameterTable.

Rows are kept sorted by name and only ever inserted while the vehicle stays the same, so a download that grows
the table inserts rows (the view keeps its selection and scroll position) instead of resetting 1,392 of them, and
the filter above never has to sort. A new value repaints its rows only.
"""
from __future__ import annotations

import enum
from typing import Mapping

from PyQt5.QtCore import QAbstractTableModel, QModelIndex, Qt, pyqtSignal
from PyQt5.QtGui import QBrush, QColor, QFont

from driver.params.model import Parameter, ParameterTable
from driver.params.values import format_value, same_value

from .values import group_of, meta_attr, range_text

__all__ = ["Column", "ParameterModel", "WriteState", "GROUP_ROLE", "MODIFIED_ROLE", "NAME_ROLE", "SEARCH_ROLE"]

NAME_ROLE = Qt.UserRole + 1          # the parameter's name
GROUP_ROLE = Qt.UserRole + 2         # its prefix
MODIFIED_ROLE = Qt.UserRole + 3      # pending, changed here, or off its default
SEARCH_ROLE = Qt.UserRole + 4        # name, display name and description, upper-case, for the search box

PENDING = QColor("#ffd27a")
CHANGED = QColor("#8fd0ff")
CONFIRMED = QColor("#56d364")
FAILED = QColor("#ff6b5b")
DIM = QColor("#8b97a3")


class Column(enum.IntEnum):
    NAME = 0
    VALUE = 1
    UNITS = 2
    RANGE = 3
    STATUS = 4
    DESCRIPTION = 5


_HEADERS = {Column.NAME: "Name", Column.VALUE: "Value", Column.UNITS: "Units", Column.RANGE: "Range",
            Column.STATUS: "Status", Column.DESCRIPTION: "Description"}


_COLUMNS = len(Column)
_COLUMN = list(Column)


class WriteState(enum.Enum):
    WRITING = "writing…"
    CONFIRMED = "confirmed by the vehicle"
    FAILED = "not confirmed"


class ParameterModel(QAbstractTableModel):
    """Parameters, their metadata, the pilot's pending changes and how each write ended."""
    pendingChanged = pyqtSignal()            # a change was staged or dropped
    namesChanged = pyqtSignal()              # parameters were added (once per table), or the list started over
    metadataChanged = pyqtSignal()

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self._table = ParameterTable()
        self._values: dict[str, Parameter] = {}   # what is shown: the table's, and during a refresh the older ones
        self._names: list[str] = []
        self._row: dict[str, int] = {}
        self._first: dict[str, float] = {}   # each value as first seen: "changed here" is measured from it
        self._meta: Mapping[str, object] = {}
        self._pending: dict[str, float] = {}
        self._writes: dict[str, tuple[WriteState, str]] = {}
        self._bold = QFont()
        self._bold.setBold(True)

    # -- what is shown ---------------------------------------------------------------------------
    @property
    def table(self) -> ParameterTable:
        return self._table

    def set_table(self, table: ParameterTable) -> None:
        """The newest table: new names are inserted, new values repaint their rows. While a download runs (a
        Refresh starts from an empty list) the values not read again yet stay shown; a finished table that lost
        names starts over."""
        if table is self._table:
            return
        self._table = table
        values = table.values
        if not table.downloading and any(name not in values for name in self._names):
            self.beginResetModel()
            self._values = dict(values)
            self._names = sorted(values)
            self._row = {n: i for i, n in enumerate(self._names)}
            self._first = {n: p.value for n, p in values.items()}
            self._pending = {n: v for n, v in self._pending.items() if n in values}
            self._writes.clear()
            self.endResetModel()
            self.namesChanged.emit()
            self.pendingChanged.emit()
            return
        old_values = self._values
        self._values = {**old_values, **values}
        new = sorted(name for name in values if name not in self._row)
        if new:
            self._insert(new)
            self._row = {n: i for i, n in enumerate(self._names)}
            for name in new:
                self._first.setdefault(name, values[name].value)
            self.namesChanged.emit()
        changed = [self._row[n] for n, p in values.items() if n in old_values and p is not old_values[n]]
        if changed:
            self.dataChanged.emit(self.index(min(changed), 0), self.index(max(changed), _COLUMNS - 1))

    def _insert(self, new: list[str]) -> None:
        """Insert the sorted ``new`` names where they belong, a run of neighbours at a time (a download brings
        a group's parameters together)."""
        merged = sorted(self._names + new)
        fresh = set(new)
        i = 0
        while i < len(merged):
            if merged[i] not in fresh:
                i += 1
                continue
            end = i
            while end < len(merged) and merged[end] in fresh:
                end += 1
            self.beginInsertRows(QModelIndex(), i, end - 1)
            self._names[i:i] = merged[i:end]
            self.endInsertRows()
            i = end

    def forget(self) -> None:
        """Another vehicle: nothing shown, staged or written so far applies to it."""
        self.beginResetModel()
        self._table = ParameterTable()
        self._values, self._names, self._row, self._first = {}, [], {}, {}
        self._pending.clear()
        self._writes.clear()
        self.endResetModel()
        self.namesChanged.emit()
        self.pendingChanged.emit()

    def set_metadata(self, meta: Mapping[str, object]) -> None:
        """Describe the parameters with ``meta``: every row repaints, the selection and scroll stay."""
        self._meta = meta or {}
        if self._names:
            self.dataChanged.emit(self.index(0, 0), self.index(len(self._names) - 1, _COLUMNS - 1))
        self.metadataChanged.emit()

    def meta(self, name: str):
        return self._meta.get(name)

    @property
    def metadata(self) -> Mapping[str, object]:
        """ParamMetadata (or {} without any)."""
        return self._meta

    @property
    def has_metadata(self) -> bool:
        return bool(self._meta)

    def parameter(self, name: str) -> Parameter | None:
        return self._values.get(name)

    def name_at(self, row: int) -> str:
        return self._names[row]

    def row_of(self, name: str) -> int:
        return self._row.get(name, -1)

    # -- pending changes and writes ------------------------------------------------------------
    @property
    def pending(self) -> dict[str, float]:
        """Staged changes, name → new value, in the order they were made."""
        return dict(self._pending)

    def stage(self, name: str, value: float) -> None:
        """Stage ``value`` for ``name``; staging the vehicle's own value drops the change."""
        param = self._values.get(name)
        if param is None:
            return
        if same_value(param.type, param.value, value):
            self._pending.pop(name, None)
        else:
            self._pending[name] = value
        self._writes.pop(name, None)
        self._repaint(name)
        self.pendingChanged.emit()

    def unstage(self, names) -> None:
        for name in list(names):
            if self._pending.pop(name, None) is not None:
                self._repaint(name)
        self.pendingChanged.emit()

    def set_write_state(self, name: str, state: WriteState, reason: str = "", written: float | None = None) -> None:
        """How the write of ``name`` stands; once confirmed, the change is no longer pending, unless the pilot
        has staged another value meanwhile (``written``: the value that was confirmed)."""
        self._writes[name] = (state, reason)
        if state is WriteState.CONFIRMED and (written is None or self._pending.get(name) == written):
            self._pending.pop(name, None)
            self.pendingChanged.emit()
        self._repaint(name)

    def modified(self, name: str) -> bool:
        """Pending, changed since this page first saw it, or off the metadata's default where it gives one."""
        param = self._values.get(name)
        if param is None:
            return False
        if name in self._pending:
            return True
        if not same_value(param.type, self._first.get(name, param.value), param.value):
            return True
        default = meta_attr(self._meta.get(name), "default")
        return default is not None and not same_value(param.type, float(default), param.value)

    def _repaint(self, name: str) -> None:
        row = self._row.get(name)
        if row is not None:
            self.dataChanged.emit(self.index(row, 0), self.index(row, len(Column) - 1))

    # -- QAbstractTableModel ------------------------------------------------------------------------
    def rowCount(self, parent: QModelIndex = QModelIndex()) -> int:  # noqa: N802
        return 0 if parent.isValid() else len(self._names)

    def columnCount(self, parent: QModelIndex = QModelIndex()) -> int:  # noqa: N802
        return 0 if parent.isValid() else _COLUMNS

    def headerData(self, section: int, orientation, role: int = Qt.DisplayRole):  # noqa: N802
        if orientation == Qt.Horizontal and role == Qt.DisplayRole:
            return _HEADERS[Column(section)]
        return None

    def data(self, index: QModelIndex, role: int = Qt.DisplayRole):
        # The proxy asks for names and groups thousands of times while it sorts and filters: answered first.
        name = self._names[index.row()]
        if role == NAME_ROLE:
            return name
        if role == GROUP_ROLE:
            return group_of(name)
        column = _COLUMN[index.column()]
        if role == Qt.DisplayRole:
            return self._text(name, column)
        if role == MODIFIED_ROLE:
            return self.modified(name)
        if role == SEARCH_ROLE:
            meta = self._meta.get(name)
            return " ".join((name, meta_attr(meta, "display_name", ""), meta_attr(meta, "description", ""))).upper()
        if role == Qt.ForegroundRole:
            return self._colour(name, column)
        if role == Qt.FontRole and column in (Column.NAME, Column.VALUE) and self.modified(name):
            return self._bold
        if role == Qt.ToolTipRole:
            return self._tooltip(name, column)
        if role == Qt.TextAlignmentRole and column is Column.VALUE:
            return int(Qt.AlignRight | Qt.AlignVCenter)
        return None

    def _text(self, name: str, column: Column) -> str:
        param = self._values[name]
        meta = self._meta.get(name)
        if column is Column.NAME:
            return name
        if column is Column.VALUE:
            text = format_value(param.type, param.value)
            label = _label(meta, param.value)
            if label and label != text:
                text = f"{text} ({label})"
            if name in self._pending:
                text += f" → {format_value(param.type, self._pending[name])}"
            return text
        if column is Column.UNITS:
            return meta_attr(meta, "units", "")
        if column is Column.RANGE:
            return range_text(meta, with_units=False)
        if column is Column.STATUS:
            write = self._writes.get(name)
            if write is not None:
                state, reason = write
                return state.value + (f": {reason}" if reason and state is WriteState.FAILED else "")
            if name in self._pending:
                return "pending"
            return "needs reboot" if meta_attr(meta, "reboot_required", False) and self.modified(name) else ""
        return meta_attr(meta, "display_name", "") or meta_attr(meta, "description", "")

    def _colour(self, name: str, column: Column):
        if column is Column.STATUS:
            write = self._writes.get(name)
            if write is not None:
                return QBrush({WriteState.WRITING: PENDING, WriteState.CONFIRMED: CONFIRMED,
                               WriteState.FAILED: FAILED}[write[0]])
        if column in (Column.NAME, Column.VALUE, Column.STATUS):
            if name in self._pending:
                return QBrush(PENDING)
            if self.modified(name):
                return QBrush(CHANGED)
            return None
        return QBrush(DIM) if column is not Column.DESCRIPTION else None

    def _tooltip(self, name: str, column: Column) -> str:
        if column is Column.VALUE:                   # the whole text, which the column may cut short
            return self._text(name, column)
        meta = self._meta.get(name)
        if meta is None:
            return f"{name}: no metadata (no bounds, units or description known)"
        parts = [f"<b>{name}</b> — {meta_attr(meta, 'display_name', '')}", meta_attr(meta, "description", "")]
        if range_text(meta):
            parts.append(f"Range: {range_text(meta)}")
        if meta_attr(meta, "reboot_required", False):
            parts.append("Takes effect after a reboot")
        return "<br>".join(p for p in parts if p)


def _label(meta, value: float) -> str:
    """What ``value`` means for an enumerated or bitmask parameter (ParamMeta.value_text), or ""."""
    return meta.value_text(value) if meta is not None else ""
