"""A .tlog read into columns: one pass with pymavlink, each message type's numeric fields kept as numpy arrays.

A .tlog is the ground station's own record (tens of messages a second), small beside a DataFlash log, so one
pass is fine; what the vehicle said is kept, what the ground station sent (system 255) is not.
"""
from __future__ import annotations

import logging
import os
from collections import defaultdict

import numpy as np

log = logging.getLogger(__name__)

GCS_SYSTEM = 255


class TlogError(ValueError):
    pass


class TlogColumns:
    """``columns[type][field]`` numpy arrays, ``times[type]`` seconds from the first message, ``texts`` (t, severity,
    text), ``params`` name -> value, ``heartbeats`` (t, custom_mode, armed), ``t0`` the first message's time (Unix
    seconds, the ground station's clock)."""

    def __init__(self, path: str) -> None:
        from pymavlink import mavutil
        if os.path.getsize(path) == 0:
            raise TlogError("the file is empty")
        conn = mavutil.mavlink_connection(path, dialect="ardupilotmega", robust_parsing=True)
        rows: dict[str, list] = defaultdict(list)
        names: dict[str, list[str]] = {}
        stamps: dict[str, list[float]] = defaultdict(list)
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
                if mtype == "BAD_DATA" or m.get_srcSystem() == GCS_SYSTEM:
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
                if mtype not in names:
                    names[mtype] = [f for f in m.get_fieldnames()
                                    if isinstance(getattr(m, f), (int, float)) and not isinstance(getattr(m, f), bool)]
                values = []
                for f in names[mtype]:
                    v = getattr(m, f, float("nan"))
                    values.append(v if isinstance(v, (int, float)) else float("nan"))
                rows[mtype].append(values)
                stamps[mtype].append(t)
        finally:
            conn.close()
        self.t0 = t0 or 0.0
        if not rows:
            raise TlogError("no MAVLink messages from a vehicle in the file")
        self.columns: dict[str, dict[str, np.ndarray]] = {}
        self.times: dict[str, np.ndarray] = {}
        for mtype, table in rows.items():
            array = np.asarray(table, dtype=np.float64).reshape(len(table), len(names[mtype]))
            self.columns[mtype] = {f: array[:, i] for i, f in enumerate(names[mtype])}
            self.times[mtype] = np.asarray(stamps[mtype])
