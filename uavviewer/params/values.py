"""What a value means for one parameter: whether it parses, fits its type (driver.params.values) and the bounds.

No Qt here: the page, the review and the compare dialogs all judge a value the same way. ``meta`` is the
driver's ParamMeta (driver.params.metadata) or None.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from driver.params.model import Parameter
from driver.params.metadata import bounds_problem
from driver.params.values import type_problem

__all__ = ["Check", "check", "group_of", "meta_attr", "parse_value", "range_text"]


def meta_attr(meta, name: str, default=None):
    """An attribute of the metadata, or ``default`` (no metadata, or an attribute it lacks)."""
    value = getattr(meta, name, default) if meta is not None else default
    return default if value is None else value


def group_of(name: str) -> str:
    """The group a parameter is listed under: its prefix up to the first underscore (QGroundControl's way)."""
    return name.split("_", 1)[0]


def parse_value(text: str) -> float | None:
    """A number typed by the pilot (None if it is not one, or not finite)."""
    try:
        value = float(text.strip().replace(",", "."))
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def range_text(meta, with_units: bool = True) -> str:
    """"0 … 100 cm/s", "" without bounds; ``with_units`` False where the units have their own column."""
    lo, hi = meta_attr(meta, "min"), meta_attr(meta, "max")
    if lo is None and hi is None:
        return ""
    units = meta_attr(meta, "units", "")
    lo_text = "" if lo is None else f"{lo:g}"
    hi_text = "" if hi is None else f"{hi:g}"
    return f"{lo_text} … {hi_text}" + (f" {units}" if units and with_units else "")


@dataclass(frozen=True)
class Check:
    """A value judged for one parameter: ``error`` forbids it; ``warning`` needs the pilot's confirmation."""
    value: float | None
    error: str = ""
    warning: str = ""

    @property
    def ok(self) -> bool:
        return self.value is not None and not self.error


def check(param: Parameter, value: float | None, meta) -> Check:
    """Judge ``value`` for ``param``: a type it cannot hold, or a read-only parameter, is refused; outside the
    metadata's bounds (driver.params.metadata) it needs confirming, since the vehicle itself checks nothing."""
    if value is None:
        return Check(None, "not a number")
    problem = type_problem(param.type, value)
    if problem:
        return Check(value, f"{param.name} is an {param.type.name.lower()}: {problem}" if param.type.is_integer
                     else problem)
    if meta_attr(meta, "read_only", False):
        return Check(value, f"{param.name} is read-only")
    problem = bounds_problem(meta, value)
    return Check(value, warning=f"{problem}: the vehicle stores it without checking" if problem else "")
