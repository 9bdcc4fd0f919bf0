"""A DataFlash .BIN log indexed once with numpy, its fields read on demand.

Why not pymavlink's DFReader: it builds Python objects for the records it walks, and its index pass alone takes
many seconds on a 100 MB log. Here the file is memory-mapped, the record heads (0xA3 0x95) are found with numpy,
the chain of records is followed once from the FMT-defined lengths, and each message type keeps only an array
of record offsets. A field is then one gather over those offsets, typed by the FMT, scaled as ArduPilot scales it
(c/C/e/E by 0.01, L by 1e-7). Bytes that break the chain (a truncated tail, corruption) are skipped and counted.
"""
from __future__ import annotations

import logging
import mmap
import os
import struct
from dataclasses import dataclass

import numpy as np

log = logging.getLogger(__name__)

HEAD = b"\xa3\x95"
FMT_ID = 128
FMT_LENGTH = 89
CHUNK = 1 << 24          # bytes scanned at a time for record heads

#: format char -> (numpy dtype, scale); strings are bytes of the given size
_NUMERIC = {
    "b": ("<i1", None), "B": ("<u1", None), "h": ("<i2", None), "H": ("<u2", None),
    "i": ("<i4", None), "I": ("<u4", None), "f": ("<f4", None), "d": ("<f8", None),
    "g": ("<f2", None), "q": ("<i8", None), "Q": ("<u8", None), "M": ("<u1", None),
    "c": ("<i2", 0.01), "C": ("<u2", 0.01), "e": ("<i4", 0.01), "E": ("<u4", 0.01), "L": ("<i4", 1e-7),
}
_STRINGS = {"n": 4, "N": 16, "Z": 64, "a": 64}

#: type -> its instance column, from ArduPilot 4.6's LogStructure (the field whose unit is '#'), for a log that has
#: no FMTU (one written before 3.6, or by the simulator); a log's own FMTU wins
INSTANCE_COLUMNS = {
    "GPS": "I", "GPA": "I", "IMU": "I", "ACC": "I", "GYR": "I", "VIBE": "IMU", "MAG": "I", "BARO": "I",
    "BARD": "I", "ARSP": "I", "BAT": "Inst", "BCL": "Instance", "RFND": "Instance", "ESC": "Instance",
    "RPM": "I", "CAM": "I", "TRIG": "I", "MNT": "I",
    **{name: "C" for name in ("XKF0", "XKF1", "XKF2", "XKF3", "XKF4", "XKF5", "XKFD", "XKFM", "XKFS", "XKQ", "XKT",
                              "XKTV", "XKV1", "XKV2", "NKF0", "NKF1", "NKF2", "NKF3", "NKF4", "NKF5", "NKQ", "NKT")},
}


class DataFlashError(ValueError):
    """The file is not a DataFlash log we can read; the message says why in words for the pilot."""


@dataclass(frozen=True)
class Field:
    name: str
    kind: str          # the FMT format char
    offset: int        # from the start of the record (after the 3-byte head)
    size: int

    @property
    def numeric(self) -> bool:
        return self.kind in _NUMERIC


@dataclass(frozen=True)
class MessageFormat:
    type: int
    name: str
    length: int
    fields: tuple[Field, ...]

    def field(self, name: str) -> Field:
        for f in self.fields:
            if f.name == name:
                return f
        raise KeyError(f"{self.name} has no field {name}")


def _parse_fmt(record: bytes) -> MessageFormat | None:
    mtype, length = record[3], record[4]
    name = record[5:9].rstrip(b"\0").decode("ascii", "replace")
    fmt = record[9:25].rstrip(b"\0").decode("ascii", "replace")
    columns = record[25:89].rstrip(b"\0").decode("ascii", "replace").split(",")
    if len(columns) > len(fmt) or not name:
        return None
    columns += [f"_{i}" for i in range(len(columns), len(fmt))]   # fewer names than formats: DFReader reads it too
    fields, offset = [], 3
    for col, kind in zip(columns, fmt):
        if kind in _NUMERIC:
            size = np.dtype(_NUMERIC[kind][0]).itemsize
        elif kind in _STRINGS:
            size = _STRINGS[kind]
        else:
            return None
        fields.append(Field(col, kind, offset, size))
        offset += size
    if offset != length:
        return None
    return MessageFormat(mtype, name, length, tuple(fields))


class DataFlashLog:
    """One .BIN, indexed: ``formats`` by name, ``offsets`` (numpy) by name, ``count(name)``, ``column(name, field)``,
    ``strings(name, field)``, ``times(name)`` in seconds from the log's first TimeUS. ``skipped``: bytes outside
    the chain of records (corruption, a truncated tail). ``instances``: a type logged by several sensors -> the
    names of each one's records, ``GPS[0]``, ``GPS[1]`` (each a name the methods take; ``GPS`` is all of them)."""

    def __init__(self, path: str) -> None:
        self.path = path
        size = os.path.getsize(path)
        if size == 0:
            raise DataFlashError("the file is empty")
        with open(path, "rb") as f:
            self._map = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
        self.data = np.frombuffer(self._map, dtype=np.uint8)
        self.formats: dict[str, MessageFormat] = {}
        self.offsets: dict[str, np.ndarray] = {}
        self.instances: dict[str, list[str]] = {}
        self.skipped = 0
        self._index()
        self.t0 = self._first_time()

    def close(self) -> None:
        self.data = np.zeros(0, np.uint8)
        try:
            self._map.close()
        except BufferError:           # an array still views it; the map goes with it
            pass

    # -- the index ------------------------------------------------------------------------------------------------
    def _index(self) -> None:
        data = self.data
        n = len(data)
        heads = _record_heads(data)
        if len(heads) == 0:
            raise DataFlashError("no DataFlash records: not a .BIN log")
        ids = data[heads + 2]
        lengths = np.zeros(256, np.int64)
        by_type: dict[int, MessageFormat] = {}
        buf = self._map
        for p in heads[(ids == FMT_ID) & (heads + FMT_LENGTH <= n)].tolist():
            fmt = _parse_fmt(buf[p:p + FMT_LENGTH])
            if fmt is None or fmt.type == FMT_ID and fmt.length != FMT_LENGTH:
                continue
            if fmt.type not in by_type:
                by_type[fmt.type] = fmt
                lengths[fmt.type] = fmt.length
        lengths[FMT_ID] = FMT_LENGTH
        if FMT_ID not in by_type:
            by_type[FMT_ID] = _parse_fmt(_fmt_record(FMT_ID, FMT_LENGTH, "FMT", "BBnNZ",
                                                      "Type,Length,Name,Format,Columns"))
        if len(by_type) <= 1:
            raise DataFlashError("no FMT records: not a DataFlash log, or its start is missing")
        chained, skipped = _follow_chain(heads, lengths[ids], n)
        self.skipped = int(skipped)
        good, good_ids = heads[chained], ids[chained]
        order = np.argsort(good_ids, kind="stable")
        sorted_ids = good_ids[order]
        bounds = np.searchsorted(sorted_ids, np.arange(257))
        for mtype, fmt in by_type.items():
            a, b = bounds[mtype], bounds[mtype + 1]
            if b > a and fmt.name not in self.formats:
                self.formats[fmt.name] = fmt
                self.offsets[fmt.name] = good[order[a:b]]
        if not self.formats or set(self.formats) == {"FMT"}:
            raise DataFlashError("no records after the formats: the log is empty or cut short")
        if self.skipped:
            log.info("%s: %d bytes outside the records skipped", self.path, self.skipped)
        self._split_instances({fmt.type: fmt.name for fmt in by_type.values()})

    def _split_instances(self, names_by_type: dict[int, str]) -> None:
        """A type logged by several sensors (two GPS, three IMUs, two batteries) interleaves them record by record;
        each instance becomes ``NAME[i]`` (as pymavlink names them) where the type's instance column holds more
        than one value. The column is the one FMTU marks '#' in its units, else ArduPilot's own (INSTANCE_COLUMNS)."""
        columns = {name: column for name, column in INSTANCE_COLUMNS.items()}
        if "FMTU" in self.formats and {"FmtType", "UnitIds"} <= {f.name for f in self.formats["FMTU"].fields}:
            for mtype, units in zip(self.column("FMTU", "FmtType").tolist(), self.strings("FMTU", "UnitIds")):
                fmt = self.formats.get(names_by_type.get(int(mtype), ""))
                if fmt is not None and "#" in units and units.index("#") < len(fmt.fields):
                    columns[fmt.name] = fmt.fields[units.index("#")].name
        for name, column in columns.items():
            fmt = self.formats.get(name)
            if fmt is None or not any(f.name == column and f.numeric for f in fmt.fields):
                continue
            which = self._raw(name, column)
            values = np.unique(which)
            if len(values) < 2:
                continue
            offsets = self.offsets[name]
            self.instances[name] = []
            for value in values.tolist():
                key = f"{name}[{int(value) if float(value).is_integer() else value}]"
                self.instances[name].append(key)
                self.formats[key] = fmt
                self.offsets[key] = offsets[which == value]

    def _first_time(self) -> float:
        """The earliest TimeUS among each type's first record (one record read per type, not its column)."""
        starts = [_gather(self.data, self.offsets[name][:1], fmt.field("TimeUS"))[0]
                  for name, fmt in self.formats.items() if any(f.name == "TimeUS" for f in fmt.fields)]
        return float(min(starts)) if starts else 0.0

    # -- reading ------------------------------------------------------------------------------------------------
    def names(self) -> list[str]:
        """The message types (an instance's ``NAME[i]`` is in ``instances[NAME]``)."""
        return sorted(name for name in self.formats if "[" not in name)

    def count(self, name: str) -> int:
        return len(self.offsets.get(name, ()))

    def _raw(self, name: str, field: str) -> np.ndarray:
        fmt = self.formats[name]
        f = fmt.field(field)
        offs = self.offsets[name]
        if f.kind in _STRINGS:
            raise TypeError(f"{name}.{field} is text")
        return _gather(self.data, offs, f)

    def column(self, name: str, field: str) -> np.ndarray:
        """One numeric field of every record of ``name``, as ArduPilot means it (scaled), in float64."""
        kind = self.formats[name].field(field).kind
        values = self._raw(name, field).astype(np.float64)
        scale = _NUMERIC[kind][1]
        return values * scale if scale else values

    def strings(self, name: str, field: str) -> list[str]:
        f = self.formats[name].field(field)
        out = []
        buf = self._map
        for p in self.offsets[name].tolist():
            out.append(buf[p + f.offset:p + f.offset + f.size].split(b"\0", 1)[0].decode("utf-8", "replace"))
        return out

    def times(self, name: str) -> np.ndarray:
        """Seconds from the log's first TimeUS; a type without TimeUS counts its records instead."""
        fmt = self.formats[name]
        if any(f.name == "TimeUS" for f in fmt.fields):
            return (self._raw(name, "TimeUS").astype(np.float64) - self.t0) / 1e6
        return np.arange(self.count(name), dtype=np.float64)


def _record_heads(data: np.ndarray) -> np.ndarray:
    """Offsets of every 0xA3 0x95 pair: the 0xA3 bytes found a slice at a time (a temporary of CHUNK bytes, not
    of the file's size), kept where the next byte is 0x95."""
    n = len(data)
    if n <= 3:
        return np.zeros(0, np.int64)
    parts = []
    for start in range(0, n - 2, CHUNK):
        found = np.flatnonzero(data[start:min(start + CHUNK, n - 2)] == HEAD[0])   # a type byte follows
        found += start
        parts.append(found[data[found + 1] == HEAD[1]])
    return np.concatenate(parts).astype(np.int64, copy=False)


def _follow_chain(heads: np.ndarray, lengths: np.ndarray, n: int) -> tuple[np.ndarray, int]:
    """Which heads are records (a bool per head) and how many bytes lie outside them, following the chain: each
    record ends where the next must begin; where it does not (corruption, a 0xA3 0x95 inside a payload, an unknown
    type), the walk goes on from the next head at or after the end. A run of records each ending exactly on the
    next head is taken in one step, so Python walks only the places where the chain breaks."""
    count = len(heads)
    ends = heads + lengths
    fits = (lengths > 0) & (ends <= n)
    follows = np.empty(count, bool)                           # the next head is right at this record's end
    follows[:-1] = heads[1:] == ends[:-1]
    follows[-1] = ends[-1] == n
    broken = np.flatnonzero(~(fits & follows))
    del follows
    chained = np.zeros(count, bool)
    i, k, skipped = 0, 0, int(heads[0])
    while i < count:
        k = int(np.searchsorted(broken, i, side="left")) if k < len(broken) and broken[k] < i else k
        stop = int(broken[k]) if k < len(broken) else count
        if stop > i:                                          # a clean run: every record chained, nothing skipped
            chained[i:stop] = True
            i = stop
            continue
        if fits[i]:
            chained[i] = True
            j = int(np.searchsorted(heads, ends[i]))          # the first head at or after its end
            skipped += (int(heads[j]) if j < count else n) - int(ends[i])
            i = j
        else:
            skipped += (int(heads[i + 1]) if i + 1 < count else n) - int(heads[i])
            i += 1
    return chained, skipped


def _gather(data: np.ndarray, offsets: np.ndarray, f: Field) -> np.ndarray:
    """One numeric field at each record offset: rows of a sliding window over the file (a view, no copy) taken at
    the offsets, so the only temporary is the (records, size) result, not an index of records x size."""
    windows = np.lib.stride_tricks.sliding_window_view(data, f.size)
    out = np.ascontiguousarray(windows[offsets + f.offset])
    return out.view(np.dtype(_NUMERIC[f.kind][0])).reshape(-1)


def _fmt_record(mtype: int, length: int, name: str, fmt: str, columns: str) -> bytes:
    return HEAD + bytes([FMT_ID]) + struct.pack("<BB4s16s64s", mtype, length, name.encode(), fmt.encode(),
                                                columns.encode())
