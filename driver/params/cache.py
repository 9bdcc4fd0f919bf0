"""The parameters of every vehicle seen, kept per user: the table is there at once when it connects again.

Keyed by system id and firmware version (``vehicle-1-4.6.3.json`` in ``$XDG_CACHE_HOME/uavviewer/params``): a
new firmware brings new parameters, and another vehicle on the same id with the same firmware is told apart
by its values once they are checked. On a reconnect the cached table is shown while the vehicle's list is read
again (ArduPilot has no checksum of its parameters on the PARAM protocol: every value is read to be sure);
what changed since is then named, and only that (``ParameterManager``: "3 parameters changed since ...").
"""
from __future__ import annotations

import json
import logging
import os
import re

from ..core.files import private_dir, write_private
from .model import Parameter, ParameterTable, ParameterValues, ParamType
from .values import same_value

log = logging.getLogger(__name__)

__all__ = ["ParameterCache", "changed_names"]


def _default_folder() -> str:
    cache = os.environ.get("XDG_CACHE_HOME", "")
    if not os.path.isabs(cache):
        cache = os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(cache, "uavviewer", "params")


class ParameterCache:
    """Tables saved per (system id, firmware); ``folder`` defaults to the per-user cache."""

    def __init__(self, folder: str | None = None) -> None:
        self.folder = folder or _default_folder()

    def path(self, system_id: int, firmware: str) -> str:
        safe = re.sub(r"[^0-9A-Za-z.+-]", "_", firmware or "unknown")
        return os.path.join(self.folder, f"vehicle-{int(system_id)}-{safe}.json")

    def load(self, system_id: int | None, firmware: str | None) -> ParameterTable | None:
        """The table last saved for this vehicle, or None (none saved, unreadable, or no key yet)."""
        if not system_id or not firmware:
            return None
        path = self.path(system_id, firmware)
        try:
            with open(path, encoding="utf-8") as f:
                data = json.load(f)
            values = {name: Parameter(name, float(value), ParamType(ptype), int(index))
                      for name, ptype, value, index in data["params"]}
            return ParameterTable(ParameterValues(values), int(data["expected"]), False, "")
        except FileNotFoundError:
            return None
        except (OSError, ValueError, KeyError, TypeError) as e:
            log.warning("parameter cache %s unreadable: %s", path, e)
            return None

    def save(self, system_id: int | None, firmware: str | None, table: ParameterTable) -> str | None:
        """Keep a complete table; returns the file written (None when there is no key or it failed)."""
        if not system_id or not firmware or not table.complete:
            return None
        path = self.path(system_id, firmware)
        data = {"system_id": system_id, "firmware": firmware, "expected": table.expected,
                "params": [[p.name, int(p.type), p.value, p.index] for p in table.values.values()]}
        try:
            private_dir(self.folder)
            write_private(path, json.dumps(data, separators=(",", ":")).encode())
        except OSError as e:
            log.warning("parameter cache %s not written: %s", path, e)
            return None
        return path


def changed_names(old: ParameterTable, new: ParameterTable) -> list[str]:
    """Parameters whose value differs between two tables, or that only one has; sorted."""
    out = []
    for name in sorted(set(old.values) | set(new.values)):
        a, b = old.values.get(name), new.values.get(name)
        if a is None or b is None or not same_value(b.type, a.value, b.value):
            out.append(name)
    return out
