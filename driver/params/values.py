"""What a parameter's type means for its values: which values it can hold, and when two are the same.

ArduPilot sends every parameter as a float on the wire (MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT: the value is cast,
not its bytes reinterpreted) and stores it in the parameter's own type (AP_Param::set_float rounds integers and
holds them in range). So a value is compared at its type's precision: integers as integers, REAL32 as the
32-bit float the vehicle holds.
"""
from __future__ import annotations

import math
import struct

from .model import ParamType

__all__ = ["RANGES", "as_stored", "same_value", "type_problem", "wire_problem", "format_value"]

RANGES = {
    ParamType.INT8: (-128, 127), ParamType.UINT8: (0, 255),
    ParamType.INT16: (-32768, 32767), ParamType.UINT16: (0, 65535),
    ParamType.INT32: (-2 ** 31, 2 ** 31 - 1), ParamType.UINT32: (0, 2 ** 32 - 1),
}


def _float32(value: float) -> float:
    try:
        return struct.unpack("<f", struct.pack("<f", value))[0]
    except OverflowError:                        # beyond float32: infinite, never equal to a stored value
        return math.copysign(math.inf, value)


def as_stored(ptype: ParamType, value: float) -> float:
    """``value`` as the vehicle holds it: an integer for integer types, a 32-bit float for REAL32."""
    if ptype.is_integer:
        return float(round(value))
    return _float32(value)


def same_value(ptype: ParamType, a: float, b: float) -> bool:
    """Equal at the precision of ``ptype``."""
    if not (math.isfinite(a) and math.isfinite(b)):
        return False
    if ptype.is_integer:
        return round(a) == round(b)
    return _float32(a) == _float32(b)


def type_problem(ptype: ParamType, value: float) -> str:
    """Why ``value`` cannot be held in ``ptype`` ("" when it can)."""
    if not math.isfinite(value):
        return "not a finite number"
    if ptype.is_integer:
        if value != round(value):
            return f"{ptype.name.lower()} holds whole numbers only"
        low, high = RANGES[ptype]
        if not low <= value <= high:
            return f"{ptype.name.lower()} holds {low} to {high}"
        return wire_problem(value)
    if math.isinf(_float32(value)):
        return "too large for a 32-bit float"
    return ""


def wire_problem(value: float) -> str:
    """Why a whole number cannot go out exactly in PARAM_SET, whose value is a 32-bit float ("" when it can):
    above 2^24 not every integer has a float32, and the vehicle would store the rounded one."""
    sent = _float32(value)
    if sent == value:
        return ""
    return (f"PARAM_SET carries a 32-bit float, which cannot hold {int(value)} exactly: the vehicle would store "
            f"{int(sent)} (whole numbers are exact only up to 16,777,216 and at some values above)")


def format_value(ptype: ParamType | None, value: float) -> str:
    """As MAVProxy and Mission Planner write it: integers bare, floats with up to 7 significant digits."""
    if ptype is not None and ptype.is_integer:
        return str(int(round(value)))
    text = f"{value:.7g}"
    if "e" in text:
        text = f"{value:.6f}".rstrip("0").rstrip(".")
    return text
