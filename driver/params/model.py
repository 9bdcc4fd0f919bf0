"""The parameter model every layer shares.

A :class:`ParameterTable` is immutable and is replaced as a whole when a value arrives; the snapshot
(:class:`~driver.vehicle.state.VehicleState`) holds a reference to it, so a state change that is not about
parameters copies nothing.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass, field
from typing import Iterator, Mapping

from pymavlink.dialects.v20 import ardupilotmega as mavlink

__all__ = ["ParamType", "Parameter", "ParameterValues", "ParameterTable"]


class ParamType(enum.IntEnum):
    """MAV_PARAM_TYPE as ArduPilot uses it."""
    UINT8 = mavlink.MAV_PARAM_TYPE_UINT8
    INT8 = mavlink.MAV_PARAM_TYPE_INT8
    UINT16 = mavlink.MAV_PARAM_TYPE_UINT16
    INT16 = mavlink.MAV_PARAM_TYPE_INT16
    UINT32 = mavlink.MAV_PARAM_TYPE_UINT32
    INT32 = mavlink.MAV_PARAM_TYPE_INT32
    REAL32 = mavlink.MAV_PARAM_TYPE_REAL32

    @property
    def is_integer(self) -> bool:
        return self is not ParamType.REAL32


@dataclass(frozen=True)
class Parameter:
    name: str
    value: float
    type: ParamType = ParamType.REAL32
    index: int = -1                              # the vehicle's param_index, -1 when not known


class ParameterValues(Mapping[str, Parameter]):
    """A read-only name → :class:`Parameter` mapping: shared, never copied (a deep copy is itself)."""
    __slots__ = ("_values",)

    def __init__(self, values: Mapping[str, Parameter] | None = None):
        self._values = dict(values or {})

    def __getitem__(self, name: str) -> Parameter:
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __deepcopy__(self, memo) -> "ParameterValues":
        return self

    def __repr__(self) -> str:
        return f"ParameterValues({len(self._values)} parameters)"


@dataclass(frozen=True)
class ParameterTable:
    """Every parameter the vehicle has reported, by name, and how complete the set is."""
    values: Mapping[str, Parameter] = field(default_factory=ParameterValues)
    expected: int | None = None                  # PARAM_VALUE.param_count; None until the first one
    downloading: bool = False
    detail: str = ""                             # "re-asking 12 missing", "link lost: 1380 of 1392", ...

    @property
    def received(self) -> int:
        return len(self.values)

    @property
    def complete(self) -> bool:
        return self.expected is not None and self.received >= self.expected

    def get(self, name: str) -> Parameter | None:
        return self.values.get(name)
