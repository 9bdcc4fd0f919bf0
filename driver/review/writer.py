"""A small DataFlash writer: FMT then records, as ArduPilot lays them out. Tests and the bench make .BIN files with
it; the simulator writes its logs with the same record layout (driver.sim.dataflash)."""
from __future__ import annotations

import struct

from .dataflash import _STRINGS, FMT_ID, FMT_LENGTH, HEAD, _fmt_record

_STRUCT = {
    "b": "b", "B": "B", "h": "h", "H": "H", "i": "i", "I": "I", "f": "f", "d": "d", "q": "q", "Q": "Q",
    "M": "B", "c": "h", "C": "H", "e": "i", "E": "I", "L": "i", "g": "e"}


def record_struct(fmt: str) -> struct.Struct:
    """The little-endian layout of a record with DataFlash format letters ``fmt`` (text fields fixed-size bytes)."""
    return struct.Struct("<" + "".join(f"{_STRINGS[c]}s" if c in _STRINGS else _STRUCT[c] for c in fmt))


def text_size(letter: str) -> int:
    """Bytes of a text field's format letter (n 4, N 16, Z 64)."""
    return _STRINGS[letter]


class DataFlashWriter:
    """``define(type, name, format, columns)`` writes the FMT; ``record(name, *values)`` a record, values raw (as
    stored: a 'c' field is centi-units, an 'L' 1e-7 degrees, text is str)."""

    def __init__(self) -> None:
        self._out = bytearray()
        self._defs: dict[str, tuple[int, struct.Struct]] = {}

    def define(self, mtype: int, name: str, fmt: str, columns: str) -> None:
        packer = record_struct(fmt)
        self._defs[name] = (mtype, packer)
        self._out += _fmt_record(mtype, 3 + packer.size, name, fmt, columns)

    def record(self, name: str, *values) -> None:
        mtype, packer = self._defs[name]
        vals = [v.encode() if isinstance(v, str) else v for v in values]
        self._out += HEAD + bytes([mtype]) + packer.pack(*vals)

    def bytes(self) -> bytes:
        return bytes(self._out)

    def save(self, path: str) -> None:
        with open(path, "wb") as f:
            f.write(self._out)


__all__ = ["DataFlashWriter", "FMT_ID", "FMT_LENGTH", "record_struct", "text_size"]


def sample_flight(seconds: float = 60.0, rate_hz: float = 25.0, params: dict[str, float] | None = None,
                  lat: float = -35.3632621, lon: float = 149.1652374, sensors: int = 1) -> DataFlashWriter:
    """A made-up flight in ArduCopter's record layouts: arm, take off in GUIDED, fly a circle in LOITER, RTL,
    land, disarm; ATT, CTUN, BAT, VIBE, GPS at ``rate_hz`` (GPS at a fifth of it), with MODE, EV, ERR, MSG and
    PARM. ``sensors``: how many GPS, IMUs and batteries log (instance k's GPS reads 0.0001 k degrees north of the
    first, its vibration 10 k m/s/s more, its battery 0.1 k V less), their records interleaved as ArduPilot
    writes them. The bench makes its 100 MB log with it."""
    import math
    w = DataFlashWriter()
    w.define(129, "PARM", "QNf", "TimeUS,Name,Value")
    w.define(130, "ATT", "QccccCCCC", "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw,ErrRP,ErrYaw")
    w.define(131, "CTUN", "Qfffffffccf", "TimeUS,ThI,ABst,ThO,ThH,DAlt,Alt,BAlt,DSAlt,SAlt,TAlt")
    w.define(132, "BAT", "QBfffffcf", "TimeUS,Inst,Volt,VoltR,Curr,CurrTot,EnrgTot,Temp,Res")
    w.define(133, "VIBE", "QBfffI", "TimeUS,IMU,VibeX,VibeY,VibeZ,Clip")
    w.define(134, "GPS", "QBBIHBcLLeffff", "TimeUS,I,Status,GMS,GWk,NSats,HDop,Lat,Lng,Alt,Spd,GCrs,VZ,Yaw")
    w.define(135, "MODE", "QMBB", "TimeUS,Mode,ModeNum,Rsn")
    w.define(136, "EV", "QB", "TimeUS,Id")
    w.define(137, "ERR", "QBB", "TimeUS,Subsys,ECode")
    w.define(138, "MSG", "QZ", "TimeUS,Message")
    for i, (name, value) in enumerate(sorted((params or {"RTL_ALT": 1500.0, "WPNAV_SPEED": 500.0,
                                                          "BATT_LOW_VOLT": 10.5}).items())):
        w.record("PARM", 1000 + i, name, value)
    w.record("MSG", 2000, "ArduCopter V4.6.3 (sample)")
    t0 = 10_000
    w.record("MODE", t0, 4, 4, 1)
    w.record("EV", t0 + 1000, 10)
    steps = int(seconds * rate_hz)
    mode = 4
    for k in range(steps):
        t = t0 + int(k * 1e6 / rate_hz)
        s = k / rate_hz
        phase = s / seconds
        if mode == 4 and phase > 0.2:
            mode = 5
            w.record("MODE", t, 5, 5, 1)
        elif mode == 5 and phase > 0.75:
            mode = 6
            w.record("MODE", t, 6, 6, 1)
            w.record("ERR", t, 6, 1)
            w.record("MSG", t, "Battery 1 is low 10.40V used 2200 mAh")
        alt = min(s, 10.0) if phase < 0.8 else max(0.0, 10.0 * (1 - (phase - 0.8) / 0.2))
        roll = 10 * math.sin(s)
        w.record("ATT", t, int(roll * 100), int((roll + 0.5 * math.sin(7 * s)) * 100), int(200 * math.cos(s)),
                 int(210 * math.cos(s)), 9000, 9000, 10, 20)
        w.record("CTUN", t, 0.5, 0.0, 0.5, 0.5, alt, alt + 0.1 * math.sin(3 * s), alt, 0, 0, 0)
        for i in range(sensors):
            w.record("BAT", t, i, 12.6 - 2.2 * phase - 0.1 * i, 12.6, 15.0 + math.sin(s), 2200 * phase, 0.0, 2500,
                     0.01)
        for i in range(sensors):
            w.record("VIBE", t, i, 5 + math.sin(s) + 10 * i, 6 + math.cos(s) + 10 * i, 12 + math.sin(2 * s) + 10 * i,
                     0)
        if k % 5 == 0:
            r = 0.0005 if mode == 5 else 0.0001 * phase
            for i in range(sensors):
                w.record("GPS", t, i, 3, 0, 0, 14, 70, int((lat + 0.0001 * i + r * math.sin(s / 4)) * 1e7),
                         int((lon + r * math.cos(s / 4)) * 1e7), int((584 + alt) * 100), 2.0, 0.0, 0.0, 0.0)
    end = t0 + int(steps * 1e6 / rate_hz)
    w.record("EV", end, 18)
    w.record("EV", end + 1000, 11)
    return w
