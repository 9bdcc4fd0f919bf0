"""Reading every parameter as one file over MAVLink FTP: ``@PARAM/param.pck``, as MAVProxy and QGroundControl do.

Where the vehicle advertises MAV_PROTOCOL_CAPABILITY_FTP (ArduPilot 4.1+), the packed file is about a third of
the PARAM_VALUE stream's bytes (names share prefixes, values take 1 to 4 bytes): 15,311 bytes for ArduCopter
4.6.3's 1,397 parameters in 239-byte packets. pymavlink's ``MAVFTP.ftp_param_decode`` unpacks it; the file lists
the parameters in the vehicle's index order.

The reading itself is the shared FTP engine's (driver.ftp.reader); what ArduCopter 4.6.3 does (tests/data/recordings/README.md, "MAVFTP parameter download"), and so how this reads:

* the size in the OpenFileRO ACK is only an estimate (12 bytes a parameter: 16,764 for a 15,311-byte file), so it
  is never used to end or check the read: the end of the file is learnt from a short packet, or from a NAK EOF
  (mapped to its request by seq: a reply's seq is the request's + 1, counting up within a burst). A burst's NAK
  offset is the end after a short packet, the last full packet's offset when the file is a multiple of the
  packet size; a ReadFile at or past the end gets NAK EOF with offset 0, so its own offset bounds the file;
* a BurstReadFile gets at most 500 packets, burst_complete only on the 500th: the next burst starts after it;
* the first read fixes the packet size (pad bytes keep every value inside one packet): every read here asks for
  :data:`CHUNK` bytes, and a ReadFile fills each gap the radio left;
* a second OpenFileRO while the file is open is refused (NAK 1): after a lost ACK the file is open, so reading
  goes on; to the first open it means a file left open before (a fetch given up), so ResetSessions closes it and
  the open is sent again; TerminateSession ends every read, given up or not.

Any trouble (no progress for :data:`STALL_SECONDS`, a NAK other than EOF, a chunk asked :data:`READ_TRIES` times,
a file that does not decode or whose count is not its header's) ends it with a reason: the caller then reads the
list the classic way and tells the pilot why. All methods run with the driver's state lock held and return what
to send.
"""
from __future__ import annotations

import struct

from pymavlink.mavftp import MAVFTP

from ..ftp.reader import STALL_SECONDS, FtpRead
from .model import Parameter, ParamType

__all__ = ["FtpDownload", "PARAM_FILE", "STALL_SECONDS"]

PARAM_FILE = b"@PARAM/param.pck"
_TYPES = {1: ParamType.INT8, 2: ParamType.INT16, 3: ParamType.INT32, 4: ParamType.REAL32}


class FtpDownload(FtpRead):
    """param.pck read by the shared engine, then decoded."""

    def __init__(self, started: float, roundtrip=None) -> None:
        super().__init__(started, PARAM_FILE, roundtrip=roundtrip)

    def parameters(self) -> tuple[dict[str, Parameter], int] | str:
        """The decoded table (name -> Parameter, index = order in the file) and its count, or why not."""
        data = b"".join(self.chunks[o] for o in sorted(self.chunks) if o < (self.end or 0))
        if len(data) != self.end:
            return f"read {len(data):,} bytes, not the file's {self.end:,}"
        if len(data) < 6:
            return "read an empty param.pck"
        _, count, total = struct.unpack("<HHH", data[:6])
        if count != total:
            return f"read a param.pck holding only {count} of the {total} parameters"
        decoded = MAVFTP.ftp_param_decode(data)
        if decoded is None:
            return "read a param.pck that did not decode"
        values = {}
        for index, (raw, value, ptype) in enumerate(decoded.params):
            name = raw.decode()
            values[name] = Parameter(name, float(value), _TYPES[ptype], index)
        return values, len(decoded.params)
