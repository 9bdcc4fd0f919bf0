"""Is a downloaded .BIN whole? pymavlink's DFReader must read it to its last byte.

A download that lost bytes, a file cut short or overwritten with garbage fails here with a sentence that says
where, instead of opening as a log with silently missing minutes.
"""
from __future__ import annotations

import contextlib
import io
import os

__all__ = ["LogFileError", "check_dataflash"]


class LogFileError(ValueError):
    pass


def check_dataflash(path: str) -> int:
    """The number of messages in ``path``; LogFileError when DFReader cannot read it to the end."""
    from pymavlink.DFReader import DFReader_binary
    try:
        size = os.path.getsize(path)
    except OSError as exc:
        raise LogFileError(f"{path}: {exc.strerror or exc}") from None
    if size == 0:
        raise LogFileError(f"{path}: the log is empty (0 bytes)")
    with open(path, "rb") as f:
        head = f.read(3)
    if head[:2] != b"\xa3\x95" or head[2:3] != b"\x80":
        raise LogFileError(f"{path}: not a DataFlash log (it does not begin with an FMT message)")
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
    if end != size:
        raise LogFileError(f"{path}: the last message is cut at offset {end} of {size} bytes (truncated)")
    return count
