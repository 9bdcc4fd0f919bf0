"""What a reviewer asks of a flight log, the same for a .BIN and a .tlog: the tree of types and fields, one field
over time, the flight modes, the events, the path, the parameters as they were, a CSV of chosen fields.

:func:`open_log` raises :class:`LogError` with words a pilot can read for an empty, truncated or foreign file.
"""
from __future__ import annotations

import csv
import logging
import os
from dataclasses import dataclass

import numpy as np
from pymavlink import mavutil

from .dataflash import DataFlashError, DataFlashLog
from .tlog import TlogColumns, TlogError

log = logging.getLogger(__name__)

MODE_NAMES = dict(mavutil.mode_mapping_acm)
#: EV ids: AP_Logger.h's LogEvent (ArduPilot 4.6.3), in words
EVENT_NAMES = {
    10: "armed", 11: "disarmed", 15: "auto armed", 17: "land complete maybe", 18: "land complete", 19: "lost GPS",
    21: "flip start", 22: "flip end", 25: "set home", 26: "simple mode on", 27: "simple mode off", 28: "not landed",
    29: "super simple mode on", 30: "autotune initialised", 31: "autotune off", 32: "autotune restart",
    33: "autotune success", 34: "autotune failed", 35: "autotune reached limit", 36: "autotune pilot testing",
    37: "autotune saved gains", 38: "save trim", 39: "save waypoint added", 41: "fence enabled",
    42: "fence disabled", 43: "acro trainer off", 44: "acro trainer leveling", 45: "acro trainer limited",
    46: "gripper grab", 47: "gripper release", 49: "parachute disabled", 50: "parachute enabled",
    51: "parachute released", 52: "landing gear deployed", 53: "landing gear retracted",
    54: "motors emergency stopped", 55: "motors emergency stop cleared", 56: "motor interlock disabled",
    57: "motor interlock enabled", 58: "rotor run-up complete", 59: "rotor speed below critical",
    60: "EKF altitude reset", 61: "land cancelled by pilot", 62: "EKF yaw reset", 63: "ADS-B avoidance enabled",
    64: "ADS-B avoidance disabled", 65: "proximity avoidance enabled", 66: "proximity avoidance disabled",
    67: "GPS primary changed", 71: "ZigZag point A stored", 72: "ZigZag point B stored",
    73: "land repositioning active", 74: "standby enabled", 75: "standby disabled",
    76: "fence max altitude enabled", 77: "fence max altitude disabled", 78: "fence circle enabled",
    79: "fence circle disabled", 80: "fence min altitude enabled", 81: "fence min altitude disabled",
    82: "fence polygon enabled", 83: "fence polygon disabled", 85: "EKF sources set to primary",
    86: "EKF sources set to secondary", 87: "EKF sources set to tertiary", 90: "airspeed primary changed",
    163: "surfaced", 164: "not surfaced", 165: "bottomed", 166: "not bottomed"}
#: the EV ids that are arming, shown as such where the log has no ARM records (4.6 writes both)
ARMING_EVENTS = {10: "armed", 11: "disarmed"}
#: ERR subsystems: AP_Logger.h's LogErrorSubsystem (4.6.3)
ERROR_SUBSYSTEMS = {
    1: "main loop", 2: "radio", 3: "compass", 4: "optical flow", 5: "radio failsafe", 6: "battery failsafe",
    7: "GPS failsafe", 8: "GCS failsafe", 9: "fence failsafe", 10: "flight mode", 11: "GPS", 12: "crash check",
    13: "flip", 14: "autotune", 15: "parachute", 16: "EKF check", 17: "EKF failsafe", 18: "barometer",
    19: "CPU failsafe", 20: "ADS-B failsafe", 21: "terrain", 22: "navigation", 23: "terrain failsafe",
    24: "EKF primary", 25: "thrust loss check", 26: "sensors failsafe", 27: "leak failsafe", 28: "pilot input",
    29: "vibration failsafe", 30: "internal error", 31: "dead reckoning failsafe"}
#: the subsystems whose code is 1 (or a fence's breaches) when the failsafe triggers, 0 when it clears
FAILSAFE_SUBSYSTEMS = {5, 6, 7, 8, 9, 17, 19, 20, 23, 26, 27, 29, 31}
#: ERR codes: LogErrorCode (4.6.3), by (subsystem, code); the general ones by (None, code)
ERROR_CODES = {
    (None, 0): "resolved", (None, 1): "failed to initialise", (None, 4): "unhealthy",
    (1, 1): "INS delay", (2, 2): "late frame", (11, 2): "glitch", (11, 0): "glitch cleared", (12, 1): "crash",
    (12, 2): "loss of control", (13, 2): "abandoned", (15, 2): "not released: too low",
    (15, 3): "not released: landed", (16, 2): "bad variance", (16, 0): "variance cleared", (18, 2): "glitch",
    (21, 2): "missing terrain data", (22, 2): "failed to set destination",
    (22, 3): "restarted RTL", (22, 4): "failed to start circle", (22, 5): "destination outside the fence",
    (22, 6): "RTL without a rangefinder", (25, 1): "thrust lost", (30, 1): "internal errors detected"}


def error_event(subsystem: int, code: int) -> tuple[str, str]:
    """(kind, words) of one ERR record, as AP_Logger's enums mean it: a failsafe triggers or clears; a flight mode
    error's code is the mode refused, an EKF primary's the core now primary."""
    name = ERROR_SUBSYSTEMS.get(subsystem, f"subsystem {subsystem}")
    if subsystem in FAILSAFE_SUBSYSTEMS:
        return "failsafe", f"{name} {'cleared' if code == 0 else 'triggered'}"
    if subsystem == 10:
        return "error", f"flight mode {MODE_NAMES.get(code, f'mode {code}')} refused"
    if subsystem == 24:
        return "event", f"EKF primary changed to core {code}"
    what = ERROR_CODES.get((subsystem, code), ERROR_CODES.get((None, code), f"code {code}"))
    return "error", f"{name}: {what}"


class LogError(ValueError):
    """The log cannot be read; str() says why, for the pilot."""


@dataclass(frozen=True)
class Event:
    t: float          # seconds from the log's start
    kind: str         # "mode", "arming", "error", "failsafe", "event", "message"
    text: str


@dataclass(frozen=True)
class FlightPath:
    t: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    alt: np.ndarray
    mode: list[str]    # the mode flown at each point


PRESETS: dict[str, list[tuple[str, str, int]]] = {
    # name -> (type, field, axis 0 left / 1 right)
    "Attitude": [("ATT", "DesRoll", 0), ("ATT", "Roll", 0), ("ATT", "DesPitch", 0), ("ATT", "Pitch", 0),
                 ("ATTITUDE", "roll", 0), ("ATTITUDE", "pitch", 0)],
    "Altitude": [("CTUN", "DAlt", 0), ("CTUN", "Alt", 0), ("CTUN", "BAlt", 0), ("GPS", "Alt", 1),
                 ("GLOBAL_POSITION_INT", "relative_alt", 0), ("VFR_HUD", "alt", 1)],
    "Battery": [("BAT", "Volt", 0), ("BAT", "Curr", 1), ("SYS_STATUS", "voltage_battery", 0),
                ("SYS_STATUS", "current_battery", 1)],
    "Vibration": [("VIBE", "VibeX", 0), ("VIBE", "VibeY", 0), ("VIBE", "VibeZ", 0), ("VIBE", "Clip0", 1),
                  ("VIBRATION", "vibration_x", 0), ("VIBRATION", "vibration_y", 0), ("VIBRATION", "vibration_z", 0)],
    "GPS": [("GPS", "NSats", 0), ("GPS", "HDop", 1), ("GPS_RAW_INT", "satellites_visible", 0),
            ("GPS_RAW_INT", "eph", 1)],
}


class FlightLog:
    """A log opened for review; ``kind`` is "bin" or "tlog". Fields load when asked (:meth:`series`)."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.kind = "tlog" if path.lower().endswith(".tlog") else "bin"
        self._bin: DataFlashLog | None = None
        self._tlog: TlogColumns | None = None
        try:
            if self.kind == "bin":
                self._bin = DataFlashLog(path)
            else:
                self._tlog = TlogColumns(path)
        except (DataFlashError, TlogError) as e:
            raise LogError(f"{os.path.basename(path)}: {e}") from e
        except (OSError, ValueError, IndexError, MemoryError) as e:
            raise LogError(f"{os.path.basename(path)}: cannot be read ({e})") from e

    def close(self) -> None:
        if self._bin is not None:
            self._bin.close()

    @property
    def start_unix(self) -> float | None:
        """Unix time of a .tlog's first message (the ground station's clock); None for a .BIN (its clock is the
        autopilot's boot time: UTC comes from its GPS records)."""
        return self._tlog.t0 if self._tlog is not None else None

    @property
    def skipped_bytes(self) -> int:
        return self._bin.skipped if self._bin is not None else 0

    # -- the tree and fields -----------------------------------------------------------------------------------
    def tree(self) -> dict[str, list[str]]:
        """Message type -> its numeric fields (TimeUS left out: it is the axis). A type several sensors log (two
        GPS, three IMUs) is one entry per instance, ``GPS[0]``, ``GPS[1]``: mixed, their records interleave."""
        if self._bin is not None:
            b = self._bin
            return {n: [f.name for f in b.formats[n].fields if f.numeric and f.name != "TimeUS"]
                    for base in b.names() if base != "FMT" for n in b.instances.get(base, [base])}
        return {n: sorted(cols) for n, cols in sorted(self._tlog.columns.items())}

    def first_instance(self, mtype: str) -> str:
        """``GPS[0]`` where the log has several GPS (the first sensor: the one presets and the path follow), else
        ``mtype`` itself."""
        if self._bin is not None and mtype in self._bin.instances:
            return self._bin.instances[mtype][0]
        return mtype

    def count(self, mtype: str) -> int:
        if self._bin is not None:
            return self._bin.count(mtype)
        return len(self._tlog.times.get(mtype, ()))

    def has(self, mtype: str, field: str) -> bool:
        return field in self.tree().get(mtype, []) if self._bin is None else (
            mtype in self._bin.formats and any(f.name == field and f.numeric for f in self._bin.formats[mtype].fields))

    def series(self, mtype: str, field: str) -> tuple[np.ndarray, np.ndarray]:
        """(seconds, values) of one field, read now from the index."""
        if self._bin is not None:
            return self._bin.times(mtype), self._bin.column(mtype, field)
        return self._tlog.series(mtype, field)

    def duration(self) -> float:
        ends = [self.series(t, f)[0][-1] for t, f in (("ATT", "Roll"), ("GPS", "Lat"), ("ATTITUDE", "roll"),
                                                     ("HEARTBEAT", "custom_mode")) if self.has(t, f)]
        return float(max(ends)) if ends else 0.0

    def preset(self, name: str) -> list[tuple[str, str, int]]:
        """The fields of preset ``name`` this log has, (type, field, axis); a type several sensors log gives its
        first instance's (VIBE[0], not every IMU's records in one sawtooth)."""
        chosen = [(self.first_instance(t), f, axis) for t, f, axis in PRESETS.get(name, [])]
        return [(t, f, axis) for t, f, axis in chosen if self.has(t, f)]

    # -- modes, events, path, parameters ------------------------------------------------------------------------
    def modes(self) -> list[tuple[float, str]]:
        """(time, mode name) at each change of flight mode."""
        out: list[tuple[float, str]] = []
        if self._bin is not None:
            if "MODE" in self._bin.formats:
                field = "ModeNum" if self.has("MODE", "ModeNum") else "Mode"
                t, nums = self.series("MODE", field)
                out = [(float(a), MODE_NAMES.get(int(n), f"mode {int(n)}")) for a, n in zip(t, nums)]
        else:
            for t, custom, _armed in self._tlog.heartbeats:
                name = MODE_NAMES.get(custom, f"mode {custom}")
                if not out or out[-1][1] != name:
                    out.append((t, name))
        return out

    def events(self) -> list[Event]:
        out = [Event(t, "mode", name) for t, name in self.modes()]
        if self._bin is not None:
            b = self._bin
            logs_arming = "ARM" in b.formats and self.has("ARM", "ArmState")
            if "EV" in b.formats:
                for t, i in zip(*self.series("EV", "Id")):
                    i = int(i)
                    if i in ARMING_EVENTS:
                        if not logs_arming:
                            out.append(Event(float(t), "arming", ARMING_EVENTS[i]))
                        continue
                    out.append(Event(float(t), "event", EVENT_NAMES.get(i, f"event {i}")))
            if logs_arming:
                for t, s in zip(*self.series("ARM", "ArmState")):
                    out.append(Event(float(t), "arming", "armed" if s else "disarmed"))
            if "ERR" in b.formats:
                t, sub = self.series("ERR", "Subsys")
                _t, code = self.series("ERR", "ECode")
                for a, s, c in zip(t, sub, code):
                    out.append(Event(float(a), *error_event(int(s), int(c))))
            if "MSG" in b.formats:
                for t, text in zip(b.times("MSG"), b.strings("MSG", "Message")):
                    out.append(Event(float(t), "message", text))
        else:
            armed = None
            for t, _custom, arm in self._tlog.heartbeats:
                if arm != armed and armed is not None:
                    out.append(Event(t, "arming", "armed" if arm else "disarmed"))
                armed = arm
            for t, sev, text in self._tlog.texts:
                out.append(Event(t, "failsafe" if "failsafe" in text.lower() else
                                 ("error" if sev <= 3 else "message"), text))
        return sorted(out, key=lambda e: e.t)

    def flight_path(self) -> FlightPath | None:
        gps = self.first_instance("GPS")           # one receiver: two interleaved zig-zag between their fixes
        if self._bin is not None and self.has(gps, "Lat"):
            t, lat = self.series(gps, "Lat")
            lon, alt = self.series(gps, "Lng")[1], self.series(gps, "Alt")[1]
        elif self._tlog is not None and "GLOBAL_POSITION_INT" in self._tlog.columns:
            cols = self._tlog.columns["GLOBAL_POSITION_INT"]
            t, lat, lon, alt = (self._tlog.times["GLOBAL_POSITION_INT"], cols["lat"] / 1e7, cols["lon"] / 1e7,
                                cols["relative_alt"] / 1000.0)
        else:
            return None
        fix = (np.abs(lat) > 1e-6) | (np.abs(lon) > 1e-6)
        t, lat, lon, alt = t[fix], lat[fix], lon[fix], alt[fix]
        if len(t) == 0:
            return None
        changes = self.modes()
        starts = np.array([c[0] for c in changes]) if changes else np.zeros(0)
        idx = np.searchsorted(starts, t, side="right") - 1
        mode = [changes[i][1] if i >= 0 else "" for i in idx.tolist()]
        return FlightPath(t, lat, lon, alt, mode)

    def params(self) -> dict[str, float]:
        """The parameters as they were in that flight (the last value logged of each)."""
        if self._bin is None:
            return dict(self._tlog.params)
        if "PARM" not in self._bin.formats:
            return {}
        names = self._bin.strings("PARM", "Name")
        values = self._bin.column("PARM", "Value")
        return {n: float(v) for n, v in zip(names, values)}

    def export_csv(self, path: str, fields: list[tuple[str, str]]) -> int:
        """Write time and the chosen fields, one row per time any of them was logged; each column holds its last
        logged value (empty before its first). Returns the rows written."""
        series = [self.series(t, f) for t, f in fields]
        times = np.unique(np.concatenate([s[0] for s in series])) if series else np.zeros(0)
        columns = []
        for t, v in series:
            i = np.searchsorted(t, times, side="right") - 1
            columns.append([("" if k < 0 else repr(float(v[k]))) for k in i.tolist()])
        with open(path, "w", newline="", encoding="utf-8") as f:
            w = csv.writer(f)
            w.writerow(["time_s"] + [f"{t}.{n}" for t, n in fields])
            for r, t in enumerate(times.tolist()):
                w.writerow([f"{t:.6f}"] + [c[r] for c in columns])
        return len(times)


def param_diff(flight: dict[str, float], current: dict[str, float]) -> list[tuple[str, float | None, float | None]]:
    """(name, in the flight, now) for each parameter that differs or exists on one side only."""
    out = []
    for name in sorted(set(flight) | set(current)):
        a, b = flight.get(name), current.get(name)
        if a is None or b is None or not np.isclose(a, b, rtol=1e-6, atol=1e-7):
            out.append((name, a, b))
    return out


def open_log(path: str) -> FlightLog:
    return FlightLog(path)
