"""The simulated ArduCopter's DataFlash logs: real ``.BIN`` files, as AP_Logger's file backend writes them.

A log is a stream of messages, each ``0xA3 0x95 <type>`` then its fields packed little-endian by the format
letters of its FMT message (FMT itself is type 128 and comes first, then one FMT per type before it is used).
pymavlink's ``DFReader_binary`` reads what is written here, so a test can compare a download with the sim's own
file byte for byte and parse it. Files are ``0000000N.BIN`` with ``LASTLOG.TXT`` holding the newest number, as
ArduPilot names them; a log is begun at arming and closed at disarming (the sim does not log while disarmed).
"""
from __future__ import annotations

import logging
import os
import struct
import tempfile
import time

from ..review.dataflash import FMT_ID, HEAD
from ..review.writer import record_struct, text_size

__all__ = ["DataFlashWriter", "LogFolder", "FORMATS", "log_file_name", "write_flight_log"]

log = logging.getLogger(__name__)

FMT_TYPE = FMT_ID
#: name → (type, format letters, columns): the subset of ArduCopter's messages the sim logs.
FORMATS = {
    "FMT": (FMT_TYPE, "BBnNZ", "Type,Length,Name,Format,Columns"),
    "PARM": (64, "QNf", "TimeUS,Name,Value"),
    "MODE": (65, "QMBB", "TimeUS,Mode,ModeNum,Rsn"),
    "MSG": (66, "QZ", "TimeUS,Message"),
    "ATT": (67, "Qffffff", "TimeUS,DesRoll,Roll,DesPitch,Pitch,DesYaw,Yaw"),
    "GPS": (68, "QBIHBLLeff", "TimeUS,Status,GMS,GWk,NSats,Lat,Lng,Alt,Spd,GCrs"),
    "BAT": (69, "QBfff", "TimeUS,Inst,Volt,Curr,CurrTot"),
    "CTUN": (70, "Qffffff", "TimeUS,ThI,ThO,DAlt,Alt,BAlt,CRt"),
    # AP_Camera_Logging.h (4.6): instance, image, the GPS's time, position, altitudes (AMSL, above home, GPS's)
    "CAM": (71, "QBHIHLLeeeccC", "TimeUS,I,Img,GPSTime,GPSWeek,Lat,Lng,Alt,RelAlt,GPSAlt,R,P,Y"),
}


def log_file_name(number: int) -> str:
    return f"{number:08d}.BIN"


class DataFlashWriter:
    """Packs messages; each type's FMT goes out just before its first message (as AP_Logger does)."""

    def __init__(self) -> None:
        self._structs = {name: record_struct(letters) for name, (_t, letters, _c) in FORMATS.items()}
        self._announced: set[str] = set()

    def _fmt(self, name: str) -> bytes:
        kind, letters, columns = FORMATS[name]
        length = 3 + self._structs[name].size
        return self._pack("FMT", kind, length, name.encode(), letters.encode(), columns.encode())

    def _pack(self, name: str, *values) -> bytes:
        return HEAD + bytes([FORMATS[name][0]]) + self._structs[name].pack(*values)

    def message(self, name: str, *values) -> bytes:
        out = b""
        if "FMT" not in self._announced:
            self._announced.add("FMT")
            out += self._fmt("FMT")
        if name not in self._announced:
            self._announced.add(name)
            out += self._fmt(name)
        values = tuple(v.encode()[:self._text_size(name, i)] if isinstance(v, str) else v
                       for i, v in enumerate(values))
        return out + self._pack(name, *values)

    @staticmethod
    def _text_size(name: str, index: int) -> int:
        return text_size(FORMATS[name][1][index])


class LogFolder:
    """The vehicle's log folder: ``0000000N.BIN`` files, the newest one open while armed.

    ``entries()`` is what LOG_ENTRY says: (id, size, time_utc) for ids 1..last, in order; ids are numbered
    from 1 after an erase, as ArduPilot does. An id is a place in the list, not a file's number: id N is the file
    oldest + N - 1, and there are as many ids as the newest file's number (AP_Logger_File::get_num_logs,
    AP_Logger_Backend::log_num_from_list_entry): once old logs are deleted to free space, ids past the newest
    log come with size 0.
    """

    def __init__(self, folder: str | None = None) -> None:
        self.folder = folder or tempfile.mkdtemp(prefix="uav-sim-logs-")
        os.makedirs(self.folder, exist_ok=True)
        self.current: int | None = None          # the log being written (armed)
        self._writer: DataFlashWriter | None = None
        self._file = None
        self._times: dict[int, int] = {}
        self._reader = None                      # (number, file) kept open while a log is read packet by packet

    def path(self, number: int) -> str:
        return os.path.join(self.folder, log_file_name(number))

    def written(self) -> int:
        """Bytes of the log being written (0 when none is)."""
        return self._file.tell() if self._file is not None else 0

    def numbers(self) -> list[int]:
        out = []
        for name in os.listdir(self.folder):
            stem, dot, ext = name.partition(".")
            if ext.upper() == "BIN" and stem.isdigit():
                out.append(int(stem))
        return sorted(out)

    def file_number(self, list_id: int, numbers: list[int] | None = None) -> int:
        """The file of LOG_ENTRY id ``list_id`` (0: no logs); ``numbers``: the folder's, if listed already."""
        numbers = self.numbers() if numbers is None else numbers
        return numbers[0] + list_id - 1 if numbers else 0

    def entries(self) -> list[tuple[int, int, int]]:
        if self._file is not None:
            self._file.flush()
        numbers = self.numbers()
        out = []
        for list_id in range(1, numbers[-1] + 1 if numbers else 1):
            number = numbers[0] + list_id - 1
            path = self.path(number)
            try:
                size = os.path.getsize(path)
                stamp = self._times.get(number) or int(os.path.getmtime(path))
            except OSError:
                size = stamp = 0                 # get_log_info of a file that is not there
            out.append((list_id, size, stamp))
        return out

    def read(self, number: int, offset: int, count: int) -> bytes | None:
        """``count`` bytes at ``offset`` of log ``number`` (fewer at the end), None if there is no such log."""
        if self._file is not None and number == self.current:
            self._file.flush()
        reader = self._reader
        try:
            if reader is None or reader[0] != number:
                if reader is not None:
                    reader[1].close()
                reader = self._reader = (number, open(self.path(number), "rb"))
            reader[1].seek(offset)
            return reader[1].read(count)
        except (OSError, ValueError):
            self._reader = None
            return None

    def begin(self, params, stamp: float | None = None) -> int:
        """A new log (at arming): FMT, every parameter as PARM."""
        self.end()
        numbers = self.numbers()
        number = (numbers[-1] + 1) if numbers else 1
        self.current = number
        self._times[number] = int(stamp if stamp is not None else time.time())
        self._writer = DataFlashWriter()
        self._file = open(self.path(number), "wb")
        with open(os.path.join(self.folder, "LASTLOG.TXT"), "w") as f:
            f.write(f"{number}\r\n")
        for name, value in params:
            self.write("PARM", 0, name, float(value))
        log.info("logging to %s", self.path(number))
        return number

    def write(self, name: str, *values) -> None:
        if self._file is None:
            return
        try:
            self._file.write(self._writer.message(name, *values))
        except (struct.error, OSError) as exc:      # a bad value is logged, never fatal to the vehicle
            log.warning("log %s: %s", name, exc)

    def end(self) -> None:
        if self._file is not None:
            self._file.close()
        self._file = self._writer = None
        self.current = None

    def erase(self) -> None:
        self.end()
        if self._reader is not None:
            self._reader[1].close()
            self._reader = None
        for number in self.numbers():
            try:
                os.remove(self.path(number))
            except OSError:
                pass
        self._times.clear()


def write_flight_log(folder: LogFolder, size: int, params=(("SYSID_THISMAV", 1.0),), seed: int = 0) -> int:
    """A log of about ``size`` bytes as if flown (for tests and benches that need a large log fast): the
    parameters, a mode, then ATT, CTUN, BAT at 10 Hz, GPS at 5 Hz, a photo now and then. Returns its number."""
    import math as _m
    number = folder.begin(params)
    folder.write("MODE", 0, 4, 4, 1)
    folder.write("MSG", 0, "ArduCopter V4.6.3 (simulated)")
    i = 0
    while folder.written() < size:
        us = 1_000_000 + i * 100_000
        phase = (i + seed) * 0.05
        folder.write("ATT", us, 5 * _m.sin(phase), 5 * _m.sin(phase) + 0.1, 3 * _m.cos(phase), 3 * _m.cos(phase),
                     (i * 0.5) % 360, (i * 0.5) % 360)
        folder.write("CTUN", us, 0.5, 0.45, 10.0, 10.0 + 0.1 * _m.sin(phase), 10.0, 0.0)
        folder.write("BAT", us, 0, 16.0 - i * 1e-5, 12.0, i * 0.33)
        if i % 2 == 0:
            folder.write("GPS", us, 3, us // 1000, 2300, 14, 402839000 + i, -37940000 - i, 67400, 2.0, 90.0)
        if i % 100 == 50:
            folder.write("CAM", us, 0, i // 100, us // 1000, 2300, 402839000 + i, -37940000 - i, 67400, 1000, 67400,
                         0, 0, 9000)
        i += 1
    folder.end()
    return number
