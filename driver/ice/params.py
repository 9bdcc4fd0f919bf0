"""The vehicle's parameters over Ice (mavlinkserver.ice's getParameters, fetchParameters, setParameter): the
conversions both sides share, and the server's revision numbering of its immutable tables."""
from __future__ import annotations

import fnmatch
import threading

from ..params.model import Parameter, ParameterTable, ParameterValues, ParamType

__all__ = ["Revisions", "table_to_ice", "table_from_ice"]


class Revisions:
    """A number that changes whenever the driver publishes another table (tables are replaced, never changed)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._table: ParameterTable | None = None
        self._revision = 0

    def of(self, table: ParameterTable) -> int:
        with self._lock:
            if table is not self._table:
                self._table = table
                self._revision += 1
            return self._revision


def table_to_ice(module, table: ParameterTable, revision: int, pattern: str, known_revision: int):
    params = []
    if known_revision != revision:
        pattern = (pattern or "*").upper()
        params = [module.Parameter(p.name, float(p.value), int(p.type), int(p.index))
                  for name, p in sorted(table.values.items()) if fnmatch.fnmatchcase(name, pattern)]
    return module.ParameterTable(revision, -1 if table.expected is None else table.expected, table.downloading,
                                 table.detail, params)


def table_from_ice(answer) -> ParameterTable:
    values = {}
    for p in answer.params:
        try:
            values[p.name] = Parameter(p.name, p.value, ParamType(p.type), p.index)
        except ValueError:                   # a type this side does not know: left out rather than guessed
            continue
    return ParameterTable(ParameterValues(values), None if answer.expected < 0 else answer.expected,
                          answer.downloading, answer.detail)
