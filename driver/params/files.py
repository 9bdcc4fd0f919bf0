""".param files, as MAVProxy and Mission Planner write them, and how one compares with the vehicle.

* MAVProxy (``param save``): ``NAME VALUE``, the name padded to 16 columns, sorted by name;
* Mission Planner (Full Parameter List, Save): ``NAME,VALUE``, sorted by name.

Both read either: ``#`` starts a comment, a comma or spaces separate name and value, a value may be hex (``0x10``).
On load the parameters MAVProxy never loads from a file (FORMAT_VERSION, SYS_NUM_RESETS, ... :
pymavlink's ``MAVParmDict.exclude_load``) are left out, as MAVProxy does. Values are written as the shortest
text that reads back as the very value the vehicle holds (integers bare, REAL32 to float32 precision).
"""
from __future__ import annotations

import enum
import fnmatch
import math
import os
import struct
from dataclasses import dataclass, field

from pymavlink.mavparm import MAVParmDict

from .model import ParameterTable, ParamType
from .values import same_value

__all__ = ["ParamFormat", "ParamFile", "Difference", "read_param_file", "write_param_file", "param_file_text",
           "compare", "EXCLUDED_ON_LOAD"]

EXCLUDED_ON_LOAD = frozenset(MAVParmDict().exclude_load)


class ParamFormat(enum.Enum):
    MAVPROXY = "mavproxy"
    MISSION_PLANNER = "missionplanner"


@dataclass
class ParamFile:
    """What a .param file says: values by name (in file order), and the lines that could not be read."""
    path: str
    values: dict[str, float] = field(default_factory=dict)
    problems: list[str] = field(default_factory=list)       # "line 12: ..."
    excluded: list[str] = field(default_factory=list)       # names MAVProxy never loads from a file


@dataclass(frozen=True)
class Difference:
    """One parameter where a file and the vehicle disagree; None for the side that lacks it."""
    name: str
    file_value: float | None
    vehicle_value: float | None
    type: ParamType | None = None

    @property
    def kind(self) -> str:
        if self.vehicle_value is None:
            return "not on the vehicle"
        if self.file_value is None:
            return "not in the file"
        return "changed"


def read_param_file(path: str) -> ParamFile:
    """Read a MAVProxy or Mission Planner .param file (OSError when it cannot be opened)."""
    result = ParamFile(path)
    with open(path, encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            text = line.split("#", 1)[0].replace(",", " ").strip()
            if not text:
                continue
            parts = text.split()
            if len(parts) != 2:
                result.problems.append(f"line {number}: expected NAME VALUE, got {line.strip()!r}")
                continue
            name, raw = parts[0].upper(), parts[1]
            try:
                value = float(int(raw, 16)) if raw.lower().startswith("0x") else float(raw)
            except ValueError:
                result.problems.append(f"line {number}: {raw!r} is not a number")
                continue
            if not math.isfinite(value) or len(name) > 16:
                result.problems.append(f"line {number}: {name} {raw} is not a parameter value")
                continue
            if name in EXCLUDED_ON_LOAD:
                result.excluded.append(name)
                continue
            result.values[name] = value
    return result


def _text(ptype: ParamType | None, value: float) -> str:
    """The shortest text that reads back as ``value`` in ``ptype``: "750", "0.1", "1e-07"."""
    if ptype is not None and ptype.is_integer:
        return str(int(round(value)))
    target = struct.unpack("<f", struct.pack("<f", value))[0]
    for digits in range(1, 10):
        short = float(f"{value:.{digits}g}")
        if struct.unpack("<f", struct.pack("<f", short))[0] == target:
            text = repr(short)
            return text[:-2] if text.endswith(".0") else text
    return repr(value)


def param_file_text(table: ParameterTable, fmt: ParamFormat = ParamFormat.MAVPROXY, pattern: str = "*") -> str:
    """The table's parameters matching ``pattern`` (fnmatch, any case), sorted by name, in ``fmt``."""
    lines = []
    for name in sorted(table.values):
        if not fnmatch.fnmatchcase(name, pattern.upper()):
            continue
        p = table.values[name]
        value = _text(p.type, p.value)
        lines.append(f"{name},{value}" if fmt is ParamFormat.MISSION_PLANNER else f"{name:<16} {value}")
    return "".join(line + "\n" for line in lines)


def write_param_file(path: str, table: ParameterTable, fmt: ParamFormat = ParamFormat.MAVPROXY,
                     pattern: str = "*") -> int:
    """Save; returns how many parameters were written. Written whole or not at all (a new file, then renamed)."""
    text = param_file_text(table, fmt, pattern)
    tmp = f"{path}.{os.getpid()}.tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, path)
    return text.count("\n")


def compare(values: dict[str, float], table: ParameterTable, pattern: str = "*",
            include_vehicle_only: bool = False) -> list[Difference]:
    """Where ``values`` (a file's) and the vehicle's table differ, at each parameter's own precision; by name.
    Parameters only the vehicle has are listed only with ``include_vehicle_only`` (a file often holds a few)."""
    out = []
    pattern = pattern.upper()
    for name in sorted(set(values) | (set(table.values) if include_vehicle_only else set())):
        if not fnmatch.fnmatchcase(name, pattern):
            continue
        mine, theirs = values.get(name), table.values.get(name)
        if theirs is None:
            out.append(Difference(name, mine, None))
        elif mine is None:
            if name not in EXCLUDED_ON_LOAD:
                out.append(Difference(name, None, theirs.value, theirs.type))
        elif not same_value(theirs.type, mine, theirs.value):
            out.append(Difference(name, mine, theirs.value, theirs.type))
    return out
