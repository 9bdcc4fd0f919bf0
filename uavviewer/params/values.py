"""What a value means for one parameter: its text, whether it parses, whether it fits the type and the bounds.

No Qt here: the page, the review and the compare dialogs all judge a value the same way. ``meta`` is the
driver's ParamMeta (driver.params metadata) or None; only its attributes are read.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from driver.params.model import Parameter, ParamType

__all__ = ["TYPE_RANGES", "Check", "check", "format_value", "group_of", "meta_attr", "parse_value", "range_text",
           "same_value"]

#: What each MAV_PARAM_TYPE can hold: a value outside is never sent (it would wrap on the vehicle).
TYPE_RANGES = {
    ParamType.UINT8: (0, 255), ParamType.INT8: (-128, 127), ParamType.UINT16: (0, 65535),
    ParamType.INT16: (-32768, 32767), ParamType.UINT32: (0, 4294967295), ParamType.INT32: (-2147483648, 2147483647),
    ParamType.REAL32: (-3.4028234e38, 3.4028234e38),
}


def meta_attr(meta, name: str, default=None):
    """An attribute of the metadata, or ``default`` (no metadata, or an attribute it lacks)."""
    value = getattr(meta, name, default) if meta is not None else default
    return default if value is None else value


def group_of(name: str) -> str:
    """The group a parameter is listed under: its prefix up to the first underscore (QGroundControl's way)."""
    return name.split("_", 1)[0]


def format_value(value: float, kind: ParamType) -> str:
    """The value as the pilot reads it: integers whole, REAL32 with the 7 significant digits a float32 holds."""
    if not math.isfinite(value):
        return str(value)
    if kind.is_integer:
        return str(int(round(value)))
    return f"{value:.7g}"


def same_value(a: float, b: float, kind: ParamType) -> bool:
    """Equal at the parameter's own precision (integers exactly, float32 to its 7 digits)."""
    if kind.is_integer:
        return round(a) == round(b)
    return math.isclose(a, b, rel_tol=1e-6, abs_tol=1e-7)


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
    """Judge ``value`` for ``param``: a type it cannot hold is refused; outside the metadata's bounds, or an
    integer parameter given a fraction, it needs confirming (the vehicle itself checks nothing)."""
    if value is None:
        return Check(None, "not a number")
    lo_type, hi_type = TYPE_RANGES[param.type]
    if not lo_type <= value <= hi_type:
        return Check(value, f"{param.type.name.lower()} holds {lo_type:g} … {hi_type:g} only")
    if param.type.is_integer and value != int(value):
        return Check(value, f"{param.name} is an integer ({param.type.name.lower()})")
    lo, hi = meta_attr(meta, "min"), meta_attr(meta, "max")
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        return Check(value, warning=f"{format_value(value, param.type)} is outside {param.name}'s range "
                                    f"{range_text(meta)}: the vehicle stores it without checking")
    values = meta_attr(meta, "values", {})
    if values and lo is None and hi is None and not _among(value, values):
        return Check(value, warning=f"{format_value(value, param.type)} is none of {param.name}'s listed values")
    return Check(value)


def _among(value: float, values) -> bool:
    return any(math.isclose(float(k), value, abs_tol=1e-6) for k in values)
