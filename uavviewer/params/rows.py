"""The rows the review and compare dialogs list, built from the table, the metadata and the pending values.

No Qt here. ``meta_of(name)`` gives a parameter's ParamMeta (driver.params.metadata) or None.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from driver.params.files import ParamFile, compare
from driver.params.model import ParameterTable
from driver.params.values import format_value

from .values import check, meta_attr, range_text

__all__ = ["FileRow", "ReviewRow", "compare_rows", "review_rows"]


@dataclass(frozen=True)
class ReviewRow:
    """One pending change as the review shows it."""
    name: str
    vehicle: str
    new: str
    notes: str = ""
    warn: bool = False           # outside the bounds (confirmed when staged)


@dataclass(frozen=True)
class FileRow:
    """One difference between a file and the vehicle, as the compare dialog shows it."""
    name: str
    vehicle: str                 # "" when the vehicle has no such parameter
    file: str
    value: float                 # the file's value
    notes: str = ""
    warn: bool = False           # outside the bounds: staging it asks first
    applicable: bool = True      # False: the vehicle has no such parameter, or the value cannot be held


def _with_units(text: str, meta) -> str:
    units = meta_attr(meta, "units", "")
    return f"{text} {units}" if units else text


def review_rows(pending: dict[str, float], param_of: Callable, meta_of: Callable) -> list[ReviewRow]:
    """``param_of(name)``: the Parameter as shown (during a Refresh, possibly the value read before it)."""
    rows = []
    for name, value in pending.items():
        param, meta = param_of(name), meta_of(name)
        if param is None:
            continue
        verdict = check(param, value, meta)
        notes = []
        if verdict.warning:
            notes.append(verdict.warning + " (confirmed)")
        if meta is None:
            notes.append("no metadata: bounds unknown")
        elif range_text(meta):
            notes.append(f"range {range_text(meta)}")
        if meta_attr(meta, "reboot_required", False):
            notes.append("needs a reboot to take effect")
        rows.append(ReviewRow(name, _with_units(format_value(param.type, param.value), meta),
                              _with_units(format_value(param.type, value), meta), "; ".join(notes),
                              bool(verdict.warning)))
    return rows


def compare_rows(file: ParamFile, table: ParameterTable, meta_of: Callable) -> tuple[list[FileRow], int, int]:
    """The file's differences with the vehicle (driver.params.files.compare), how many values are the same, and
    how many parameters only the vehicle has."""
    rows = []
    for d in compare(file.values, table):
        param, meta = table.get(d.name), meta_of(d.name)
        if param is None:
            rows.append(FileRow(d.name, "", format_value(None, d.file_value), d.file_value,
                                d.kind + ("" if table.complete else " (yet)"), applicable=False))
            continue
        verdict = check(param, d.file_value, meta)
        notes = verdict.error or verdict.warning or (f"range {range_text(meta)}" if range_text(meta) else "")
        rows.append(FileRow(d.name, _with_units(format_value(param.type, param.value), meta),
                            _with_units(format_value(param.type, d.file_value), meta), d.file_value, notes,
                            bool(verdict.warning), verdict.ok))
    differing = {r.name for r in rows}
    same = sum(1 for name in file.values if name in table.values and name not in differing)
    vehicle_only = sum(1 for name in table.values if name not in file.values and name not in file.excluded)
    return rows, same, vehicle_only
