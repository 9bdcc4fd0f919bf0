"""Is a downloaded .BIN whole? pymavlink's DFReader must read it to its end, and it must be as long as the vehicle
said.

A download that lost bytes, a file cut short or overwritten with garbage fails here with a sentence that says
where, instead of opening as a log with silently missing minutes.

What a real log may legitimately end with, after its last whole message (told, never removed: the file stays
byte-identical to the vehicle's):

* **an unfinished record**: ``0xA3 0x95 <type>`` and fewer bytes than that type's length. AP_Logger writes its
  buffer as a byte stream (the file backend in chunks, AP_Logger_Block a page at a time, records running across
  pages), so a power loss or a log read while it is written stops inside a record; pymavlink's own test log
  (tests/data/logs/pymavlink-test.BIN) ends with 24 bytes of one.
* **padding**: AP_Logger_Block lists a log as whole pages (get_log_info: pages × (page size − page header) − file
  header) and fills the last page's rest with zeros (write_log_page); erased flash reads 0xFF. DFReader skips such a
  tail itself ("block based logs ... can have up to 249 bytes of trailing space"). A page is at most a few kB, an
  SD card's cluster that a power loss left unwritten at most 64 kB: a longer run is not taken for padding.

Anything else after the last whole message, bytes DFReader skips between two messages, or a file shorter than the
size the vehicle announced, is an error.
"""
from __future__ import annotations

import contextlib
import io
import os
from dataclasses import dataclass

__all__ = ["LogFileError", "LogCheck", "check_dataflash"]

HEAD = b"\xa3\x95"
MAX_PADDING = 64 * 1024         # bytes: the largest SD cluster; flash pages are far smaller


class LogFileError(ValueError):
    pass


@dataclass(frozen=True)
class LogCheck:
    messages: int               # whole messages DFReader read
    tail: int = 0               # bytes after the last whole message: an unfinished record or padding
    ending: str = ""            # what those bytes are, in words ("" when the log ends on a whole message)


def check_dataflash(path: str, announced: int | None = None) -> LogCheck:
    """Read ``path`` as DFReader does; LogFileError when it is not a whole log (``announced``: the size the vehicle
    gave for it, which the file must reach)."""
    try:
        size = os.path.getsize(path)
    except OSError as exc:
        raise LogFileError(f"{path}: {exc.strerror or exc}") from None
    if size == 0:
        raise LogFileError(f"{path}: the log is empty (0 bytes)")
    if announced is not None and size < announced:
        raise LogFileError(f"{path}: {size} bytes, shorter than the {announced} bytes the vehicle announced "
                           "(truncated)")
    with open(path, "rb") as f:
        head = f.read(3)
    if head[:2] != HEAD or head[2:3] != b"\x80":
        raise LogFileError(f"{path}: not a DataFlash log (it does not begin with an FMT message)")
    count, end, formats = _read_whole_messages(path)
    if end == size:
        return LogCheck(count)
    with open(path, "rb") as f:
        f.seek(end)
        tail = f.read()
    ending = _legitimate_ending(tail, formats)
    if ending is None:
        raise LogFileError(f"{path}: the last whole message ends at offset {end} of {size} bytes and the "
                           f"{size - end} bytes after it are neither a record's start nor padding (truncated or "
                           "corrupt)")
    return LogCheck(count, len(tail), f"{len(tail)} bytes of {ending}")


def _read_whole_messages(path: str) -> tuple[int, int, dict]:
    """(messages, the offset where the last one ends, DFReader's formats); LogFileError where it skips bytes."""
    from pymavlink.DFReader import DFReader_binary
    noise = io.StringIO()
    with contextlib.redirect_stdout(noise), contextlib.redirect_stderr(noise):
        try:
            reader = DFReader_binary(path)
            count, end = 0, 0
            while True:
                msg = reader.recv_msg()
                if msg is None:
                    break
                length = reader.formats[reader.prev_type].len
                if reader.offset - length != end and count:
                    raise LogFileError(f"{path}: unreadable bytes at offset {end} (corrupt: "
                                       f"{reader.offset - length - end} bytes skipped)")
                end = reader.offset
                count += 1
        except LogFileError:
            raise
        except Exception as exc:              # DFReader's own failures on garbage
            raise LogFileError(f"{path}: DFReader could not read it: {exc}") from None
    return count, end, reader.formats


def _legitimate_ending(tail: bytes, formats: dict) -> str | None:
    """What the bytes after the last whole message are, if a real log may end with them; None otherwise."""
    if HEAD.startswith(tail[:2]) and len(tail) < 3:
        return "an unfinished record"         # its header itself cut
    if tail[:2] == HEAD:
        fmt = formats.get(tail[2])
        if fmt is not None and len(tail) < fmt.len:
            return f"an unfinished {fmt.name} record"
        return None
    if len(tail) <= MAX_PADDING and not tail.strip(b"\x00\xff"):
        kinds = [name for byte, name in ((0x00, "0x00"), (0xFF, "0xFF")) if byte in tail]
        return f"padding ({' and '.join(kinds)})"
    return None
