"""Reading every parameter as one file over MAVLink FTP: ``@PARAM/param.pck``, as MAVProxy and QGroundControl do.

Where the vehicle advertises MAV_PROTOCOL_CAPABILITY_FTP (ArduPilot 4.1+), the packed file is about a third of
the PARAM_VALUE stream's bytes (names share prefixes, values take 1 to 4 bytes): 15 kB for ArduCopter 4.6.3's
1,392 parameters against 51 kB. The steps: OpenFileRO, one BurstReadFile from 0 (the vehicle sends the file to
its end in 239-byte chunks), then ReadFile for every chunk the radio lost, a few at a time, TerminateSession.
pymavlink's ``MAVFTP.ftp_param_decode`` unpacks it; the file lists the parameters in the vehicle's index order.

Any trouble (no answer to the open, a NAK, a file that does not decode) ends it with a reason: the caller then
reads the list the classic way. All methods run with the driver's state lock held and return what to send.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mavlink
from pymavlink.mavftp import MAVFTP

from .model import Parameter, ParamType

__all__ = ["FtpDownload", "PARAM_FILE"]

PARAM_FILE = b"@PARAM/param.pck"
CHUNK = 239
HEADER = struct.Struct("<HBBBBBBI")
OP_TERMINATE, OP_OPEN_RO, OP_READ, OP_BURST, OP_ACK, OP_NAK = 1, 4, 5, 15, 128, 129
NAK_TEXT = {1: "failed", 2: "failed (errno)", 3: "invalid size", 4: "invalid session", 5: "no session available",
            6: "end of file", 7: "unknown command", 10: "file not found"}
OPEN_RETRY = 0.5           # s between OpenFileRO tries
OPEN_TRIES = 6
BURST_QUIET = 0.5          # s without a chunk before the burst counts as over (lost chunks are then read)
READ_WINDOW = 8
READ_TIMEOUT_MIN = 0.2
_TYPES = {1: ParamType.INT8, 2: ParamType.INT16, 3: ParamType.INT32, 4: ParamType.REAL32}


@dataclass
class FtpDownload:
    started: float
    size: int | None = None              # the file's bytes, from the open's ACK
    chunks: dict[int, bytes] = field(default_factory=dict)    # offset -> data
    phase: str = "open"                  # open, burst, gaps, done
    seq: int = 0
    tries: int = 0
    sent_at: float = -1.0
    last_chunk: float = 0.0
    asked: dict[int, float] = field(default_factory=dict)     # gap offset -> when asked
    rtt: float = 0.1
    frames: int = 0                      # FTP frames received (the cost on the radio)

    @property
    def received(self) -> int:
        return sum(len(c) for c in self.chunks.values())

    def _request(self, target: tuple[int, int], opcode: int, offset: int = 0, data: bytes = b"", size=None):
        self.seq = (self.seq + 1) & 0xFFFF
        payload = HEADER.pack(self.seq, 0, opcode, len(data) if size is None else size, 0, 0, 0, offset) + data
        return mavlink.MAVLink_file_transfer_protocol_message(0, target[0], target[1], list(payload.ljust(251, b"\0")))

    def missing(self) -> list[int]:
        """Offsets of the chunks not received."""
        return [o for o in range(0, self.size or 0, CHUNK) if o not in self.chunks]

    # -- the vehicle's answers ----------------------------------------------------------------------
    def on_message(self, m, now: float) -> str | None:
        """A FILE_TRANSFER_PROTOCOL reply; returns why the transfer failed, else None."""
        payload = bytes(m.payload)
        seq, session, opcode, size, req_opcode, burst_complete, _, offset = HEADER.unpack(payload[:12])
        data = payload[12:12 + size]
        self.frames += 1
        if opcode == OP_NAK:
            error = data[0] if data else 0
            if req_opcode in (OP_READ, OP_BURST) and error == 6:       # end of file: a burst past the end
                return None
            return f"the vehicle's FTP said {NAK_TEXT.get(error, error)} to {'open' if req_opcode == OP_OPEN_RO else 'a read'}"
        if opcode != OP_ACK:
            return None
        if req_opcode == OP_OPEN_RO and self.phase == "open" and size >= 4:
            self.size = struct.unpack("<I", data[:4])[0]
            self.phase = "burst"
            self.sent_at = -1.0
        elif req_opcode in (OP_READ, OP_BURST) and self.size is not None and offset % CHUNK == 0:
            if offset not in self.chunks and data:
                self.chunks[offset] = data
            sent = self.asked.pop(offset, None)
            if sent is not None:
                self.rtt = 0.8 * self.rtt + 0.2 * max(0.0, now - sent)
            self.last_chunk = now
            if burst_complete and self.phase == "burst":
                self.phase = "gaps"
        return None

    # -- the ticker ----------------------------------------------------------------------------------
    def service(self, now: float, target: tuple[int, int]) -> tuple[list, str | None]:
        """Messages to send, and why it failed (None while it goes on)."""
        if self.phase == "open":
            if self.sent_at < 0 or now - self.sent_at >= OPEN_RETRY:
                if self.tries >= OPEN_TRIES:
                    return [], f"no answer to the FTP open of {PARAM_FILE.decode()} ({self.tries} tries)"
                self.tries += 1
                self.sent_at = now
                return [self._request(target, OP_OPEN_RO, 0, PARAM_FILE)], None
            return [], None
        if self.phase == "burst":
            if self.sent_at < 0:
                self.sent_at = self.last_chunk = now
                return [self._request(target, OP_BURST, 0, size=CHUNK)], None
            if now - self.last_chunk >= max(BURST_QUIET, 4 * self.rtt):
                self.phase = "gaps"                     # the end of the burst was lost, or the burst stalled
            else:
                return [], None
        if self.phase == "gaps":
            missing = self.missing()
            if not missing:
                self.phase = "done"
                return [self._request(target, OP_TERMINATE)], None
            timeout = max(READ_TIMEOUT_MIN, 3 * self.rtt)
            for offset, sent in list(self.asked.items()):
                if now - sent >= timeout:
                    del self.asked[offset]
            out = []
            for offset in missing:
                if len(self.asked) >= READ_WINDOW:
                    break
                if offset not in self.asked:
                    self.asked[offset] = now
                    out.append(self._request(target, OP_READ, offset, size=CHUNK))
            return out, None
        return [], None

    @property
    def done(self) -> bool:
        return self.phase == "done"

    def parameters(self) -> tuple[dict[str, Parameter], int] | str:
        """The decoded table (name -> Parameter, index = order in the file) and its count, or why not."""
        data = b"".join(self.chunks[o] for o in sorted(self.chunks))[:self.size]
        decoded = MAVFTP.ftp_param_decode(data)
        if decoded is None:
            return "the vehicle's param.pck did not decode"
        values = {}
        for index, (raw, value, ptype) in enumerate(decoded.params):
            name = raw.decode()
            values[name] = Parameter(name, float(value), _TYPES[ptype], index)
        return values, len(decoded.params)
