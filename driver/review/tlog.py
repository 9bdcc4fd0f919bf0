"""A .tlog read into columns: one pass with pymavlink, each message type's numeric fields kept in compact arrays of
their MAVLink type (a uint8 field takes a byte a message, not a Python number), read as float64 when asked.

A .tlog is the ground station's own record (tens of messages a second), small beside a DataFlash log, so one
pass is fine; what the vehicle said is kept, what the ground station sent (system 255) is not. Messages the
dialect does not know (UNKNOWN_n: all that random bytes ever parse into, dated some 300,000 years ahead) are
not kept: a file with nothing else is not a telemetry log.
"""
from __future__ import annotations

import logging
import os
from array import array
from operator import attrgetter

import numpy as np

log = logging.getLogger(__name__)

GCS_SYSTEM = 255
#: MAVLink field type -> array typecode (8, 16, 32, 64 bits on every platform we run on)
_TYPECODES = {"float": "f", "double": "d", "int8_t": "b", "uint8_t": "B", "int16_t": "h", "uint16_t": "H",
              "int32_t": "i", "uint32_t": "I", "int64_t": "q", "uint64_t": "Q"}


class TlogError(ValueError):
    pass


class _Columns:
    """One message type's numeric fields, an array each, appended message by message; a field that is an array of
    numbers (ESC_TELEMETRY_1_TO_4's rpm, ...) gives one column per element: rpm[0], rpm[1], ..."""

    def __init__(self, m) -> None:
        types = dict(zip(m.get_fieldnames(), getattr(m, "fieldtypes", ())))
        scalars = [f for f in m.get_fieldnames()
                   if isinstance(getattr(m, f), (int, float)) and not isinstance(getattr(m, f), bool)]
        self.lists = [(f, len(getattr(m, f))) for f in m.get_fieldnames()
                      if isinstance(getattr(m, f), (list, tuple)) and getattr(m, f)
                      and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in getattr(m, f))]
        self.scalars = len(scalars)
        self.names = scalars + [f"{f}[{i}]" for f, n in self.lists for i in range(n)]
        self.arrays = [array(_TYPECODES.get(types.get(f), "d")) for f in scalars] + \
            [array(_TYPECODES.get(types.get(f), "d")) for f, n in self.lists for _ in range(n)]
        self.read = attrgetter(*scalars) if scalars else (lambda _m: ())
        self.times = array("d")

    def add(self, t: float, m) -> None:
        self.times.append(t)
        values = self.read(m)
        if self.scalars == 1:
            values = (values,)
        if self.lists:
            values = tuple(values)
            for f, n in self.lists:
                v = getattr(m, f, ())
                values += tuple(v[:n]) + (float("nan"),) * (n - len(v[:n]))
        for a, v in zip(self.arrays, values):
            try:
                a.append(v)
            except (TypeError, OverflowError):          # not a number after all: NaN where it can be, else 0
                a.append(float("nan") if a.typecode in "fd" else 0)

    def numpy(self) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        return (np.frombuffer(self.times, np.float64),
                {f: np.frombuffer(a, np.dtype(a.typecode)) for f, a in zip(self.names, self.arrays)})


class TlogColumns:
    """``columns[type][field]`` numpy arrays (the field's own type: :meth:`series` gives float64), ``times[type]``
    seconds from the first message, ``texts`` (t, severity, text), ``params`` name -> value, ``heartbeats`` (t,
    custom_mode, armed), ``t0`` the first message's time (Unix seconds, the ground station's clock)."""

    def __init__(self, path: str) -> None:
        from pymavlink import mavutil
        if os.path.getsize(path) == 0:
            raise TlogError("the file is empty")
        from pymavlink.dialects.v20 import ardupilotmega as mavlink2
        conn = mavutil.mavlink_connection(path, dialect="ardupilotmega", robust_parsing=True)
        # MAVLink 2's codec whatever mavutil chose for the process (its MAVLINK20 switch): with the 1.0 one the
        # messages above id 255 (ESC_TELEMETRY_1_TO_4 in the 4.7 recording, ...) parse to UNKNOWN_n and were dropped
        conn.mav = mavlink2.MAVLink(conn)
        conn.mav.robust_parsing = True
        by_type: dict[str, _Columns] = {}
        self.texts: list[tuple[float, int, str]] = []
        self.params: dict[str, float] = {}
        self.heartbeats: list[tuple[float, int, bool]] = []
        t0 = None
        try:
            while True:
                m = conn.recv_msg()
                if m is None:
                    break
                mtype = m.get_type()
                if mtype == "BAD_DATA" or mtype.startswith("UNKNOWN_") or m.get_srcSystem() == GCS_SYSTEM:
                    continue
                t = float(getattr(m, "_timestamp", 0.0))
                t0 = t if t0 is None else t0
                t -= t0
                if mtype == "STATUSTEXT":
                    self.texts.append((t, m.severity, m.text))
                elif mtype == "PARAM_VALUE":
                    self.params[m.param_id] = float(m.param_value)
                elif mtype == "HEARTBEAT" and m.get_srcComponent() == 1:
                    self.heartbeats.append((t, m.custom_mode, bool(m.base_mode & 128)))
                columns = by_type.get(mtype)
                if columns is None:
                    columns = by_type[mtype] = _Columns(m)
                columns.add(t, m)
        finally:
            conn.close()
        self.t0 = t0 or 0.0
        if not by_type:
            raise TlogError("no MAVLink messages from a vehicle in the file: not a telemetry log")
        self.columns: dict[str, dict[str, np.ndarray]] = {}
        self.times: dict[str, np.ndarray] = {}
        for mtype, columns in by_type.items():
            self.times[mtype], self.columns[mtype] = columns.numpy()

    def series(self, mtype: str, field: str) -> tuple[np.ndarray, np.ndarray]:
        """(seconds, values as float64) of one field."""
        return self.times[mtype], self.columns[mtype][field].astype(np.float64)
