"""What each parameter means: ArduPilot's own metadata (apm.pdef.xml), because the vehicle checks nothing.

ArduPilot publishes an ``apm.pdef.xml`` per vehicle and version, generated from the sources' @Param comments:
display name, description, units, range, increment, named values, bitmask bits, whether a reboot is needed.
The vehicle itself stores anything (the recording: RTL_ALT = 1e9), so the bounds are the ground station's job.

Where it comes from (:func:`load_metadata`), first found wins:

1. a file the user points to (``--param-metadata``, or ``load_metadata(path)``): an apm.pdef.xml, gzipped or not;
2. the per-user cache, ``$XDG_CACHE_HOME/uavviewer/params/apm.pdef.xml``, which :func:`fetch_metadata`
   fills once from ArduPilot's site when the machine is online (as MAVProxy's ``param help`` does);
3. the copy shipped with the driver (``data/apm.pdef.xml.gz``: ArduCopter, from Copter-4.5.3, GPL-3.0-or-later;
   scripts/params-metadata says where it comes from).

Without any (a stripped install), :func:`load_metadata` returns None: editing still works, with a warning.
"""
from __future__ import annotations

import gzip
import logging
import math
import os
import threading
import types
import urllib.request
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from typing import Mapping

from ..core.files import private_dir, write_private

log = logging.getLogger(__name__)

__all__ = ["ParamMeta", "ParamMetadata", "load_metadata", "metadata_for", "fetch_metadata", "cache_path", "SHIPPED", "METADATA_URL",
           "bounds_problem", "set_problem"]

SHIPPED = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "apm.pdef.xml.gz")
METADATA_URL = "https://autotest.ardupilot.org/Parameters/ArduCopter/apm.pdef.xml"   # MAVProxy's source
FETCH_TIMEOUT = 10.0


def _frozen(mapping=None) -> Mapping:
    return types.MappingProxyType(dict(mapping or {}))


@dataclass(frozen=True)
class ParamMeta:
    """One parameter as ArduPilot documents it; None (or empty) for what the documentation does not say."""
    name: str
    display_name: str = ""
    description: str = ""
    units: str = ""                          # "cm", "m/s", "deg" ...
    unit_text: str = ""                      # "centimeters"
    min: float | None = None
    max: float | None = None
    increment: float | None = None
    values: Mapping[float, str] = field(default_factory=_frozen)      # value -> its meaning ("1": "RTL")
    bitmask: Mapping[int, str] = field(default_factory=_frozen)       # bit number -> its meaning
    reboot_required: bool = False
    read_only: bool = False
    user: str = ""                           # "Standard" or "Advanced"

    def value_text(self, value: float) -> str:
        """What ``value`` means: its named value, or the bits it sets; "" when nothing is documented."""
        if value in self.values:
            return self.values[value]
        if self.bitmask and value == int(value) and value >= 0:
            bits = [self.bitmask.get(b, f"bit {b}") for b in range(32) if int(value) >> b & 1]
            return ", ".join(bits)
        return ""


def bounds_problem(meta: ParamMeta | None, value: float) -> str:
    """Why ``value`` is outside what the metadata allows ("" when it is within, or nothing is known)."""
    if meta is None:
        return ""
    if meta.read_only:
        return f"{meta.name} is read-only"
    unit = f" {meta.units}" if meta.units else ""
    if meta.min is not None and meta.max is not None and not meta.min <= value <= meta.max:
        return f"{meta.name} = {value:g} is outside {meta.min:g} to {meta.max:g}{unit}"
    if meta.min is None and meta.values and value not in meta.values and not meta.bitmask:
        return f"{meta.name} = {value:g} is none of its values ({', '.join(f'{k:g}' for k in meta.values)})"
    if meta.bitmask and (value != int(value) or value < 0 or any(
            int(value) >> b & 1 and b not in meta.bitmask for b in range(32))):
        return f"{meta.name} = {value:g} sets bits that mean nothing"
    return ""


def set_problem(metadata: "ParamMetadata | None", name: str, value: float, allow_out_of_bounds: bool) -> str:
    """Why a set of ``name`` to ``value`` must not go out without the pilot's explicit confirmation ("" when
    it may go)."""
    if allow_out_of_bounds or metadata is None:
        return ""
    problem = bounds_problem(metadata.get(name), value)
    return f"{problem} (ArduPilot's metadata): confirm to set it anyway" if problem else ""


class ParamMetadata:
    """Every parameter's :class:`ParamMeta`, from one apm.pdef.xml; ``source`` says which file."""

    def __init__(self, metas: dict[str, ParamMeta], source: str, generated: str = "") -> None:
        self._metas = metas
        self.source = source
        self.generated = generated           # "Copter-4.5.3 on 2024-05-30", from the file's header

    def get(self, name: str) -> ParamMeta | None:
        return self._metas.get(name)

    def __contains__(self, name: object) -> bool:
        return name in self._metas

    def __len__(self) -> int:
        return len(self._metas)

    def __repr__(self) -> str:
        return f"ParamMetadata({len(self)} parameters from {self.source})"

    @classmethod
    def parse(cls, data: bytes, source: str) -> "ParamMetadata":
        """An apm.pdef.xml's bytes (gzipped or not); ValueError when it is not one."""
        if data[:2] == b"\x1f\x8b":
            data = gzip.decompress(data)
        try:
            root = ET.fromstring(data)
        except ET.ParseError as e:
            raise ValueError(f"{source} is not an apm.pdef.xml: {e}") from None
        metas: dict[str, ParamMeta] = {}
        for element in root.iter("param"):
            meta = _meta(element)
            if meta is not None:
                metas.setdefault(meta.name, meta)
        if not metas:
            raise ValueError(f"{source} holds no parameter metadata")
        head = data[:400].decode("utf-8", "replace")
        generated = ""
        if "Generated from git tag " in head:
            generated = head.split("Generated from git tag ", 1)[1].split("-->", 1)[0].strip()
        return cls(metas, source, generated)

    @classmethod
    def from_file(cls, path: str) -> "ParamMetadata":
        with open(path, "rb") as f:
            return cls.parse(f.read(), path)


def _number(text: str | None) -> float | None:
    try:
        value = float(text)
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) else None


def _meta(element) -> ParamMeta | None:
    name = (element.get("name") or "").split(":")[-1]
    if not name:
        return None
    fields = {f.get("name"): (f.text or "").strip() for f in element.findall("field")}
    low = high = None
    if "Range" in fields:
        parts = fields["Range"].split()
        if len(parts) == 2:
            low, high = _number(parts[0]), _number(parts[1])
    values = {}
    for v in element.iter("value"):
        code = _number(v.get("code"))
        if code is not None:
            values[code] = (v.text or "").strip()
    bitmask = {}
    for part in fields.get("Bitmask", "").split(","):
        bit, _, meaning = part.partition(":")
        if bit.strip().isdigit():
            bitmask[int(bit)] = meaning.strip()
    return ParamMeta(name, element.get("humanName", ""), element.get("documentation", ""), fields.get("Units", ""),
                     fields.get("UnitText", ""), low, high, _number(fields.get("Increment")), _frozen(values),
                     _frozen(bitmask), fields.get("RebootRequired", "").lower() == "true",
                     fields.get("ReadOnly", "").lower() == "true", element.get("user", "").strip())


# -- where it comes from -------------------------------------------------------------------------------------
def cache_path() -> str:
    """The per-user cache's copy: $XDG_CACHE_HOME/uavviewer/params/apm.pdef.xml."""
    cache = os.environ.get("XDG_CACHE_HOME", "")
    if not os.path.isabs(cache):
        cache = os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(cache, "uavviewer", "params", "apm.pdef.xml")


_loaded: dict[str, ParamMetadata] = {}
_load_lock = threading.Lock()


def load_metadata(path: str | None = None) -> ParamMetadata | None:
    """The metadata from ``path`` (the user's file: an error if it cannot be read), else the cache's, else the
    shipped copy; None when there is none. Parsed once per file per process."""
    candidates = [path] if path else [cache_path(), SHIPPED]
    for candidate in candidates:
        if not path and not os.path.isfile(candidate):
            continue
        with _load_lock:
            key = os.path.abspath(candidate)
            if key not in _loaded:
                try:
                    _loaded[key] = ParamMetadata.from_file(candidate)
                except (OSError, ValueError) as e:
                    if path:
                        raise
                    log.warning("parameter metadata %s unusable: %s", candidate, e)
                    continue
            return _loaded[key]
    return None


_outcomes: dict[tuple[str, str], tuple[ParamMetadata | None, str]] = {}
_outcome_lock = threading.Lock()


def _outcome_key(path: str | None) -> tuple[str, str]:
    return ("file", os.path.abspath(path)) if path else ("default", cache_path())


def metadata_for(path: str | None = None, wait: bool = True) -> tuple[ParamMetadata | None, str] | None:
    """What :func:`load_metadata` gives for ``path``, as ``(metadata, error)``, read once per process and
    remembered, "none found" (None, "") and an unreadable file (None, why) included, so no caller reads it again.
    With ``wait`` False it never blocks: None while it has not been read yet."""
    key = _outcome_key(path)
    outcome = _outcomes.get(key)
    if outcome is not None or not wait:
        return outcome
    with _outcome_lock:
        outcome = _outcomes.get(key)
        if outcome is None:
            try:
                outcome = (load_metadata(path), "")
            except (OSError, ValueError) as e:
                outcome = (None, str(e))
            _outcomes[key] = outcome
        return outcome


def fetch_metadata(url: str = METADATA_URL, timeout: float = FETCH_TIMEOUT) -> ParamMetadata:
    """Download apm.pdef.xml once into the per-user cache (checked before it replaces anything); OSError or
    ValueError when offline or the answer is not metadata."""
    with urllib.request.urlopen(url, timeout=timeout) as response:   # noqa: S310 (an https URL we chose)
        data = response.read()
    metadata = ParamMetadata.parse(data, url)
    target = cache_path()
    private_dir(os.path.dirname(target))
    write_private(target, gzip.decompress(data) if data[:2] == b"\x1f\x8b" else data, 0o644)
    with _load_lock:
        _loaded.pop(os.path.abspath(target), None)
    with _outcome_lock:
        _outcomes.pop(_outcome_key(None), None)
    log.info("parameter metadata fetched from %s into %s (%d parameters)", url, target, len(metadata))
    return load_metadata() or metadata
