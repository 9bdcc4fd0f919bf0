"""The simulated ArduCopter's MAVLink FTP, for the one file a ground station reads fast: ``@PARAM/param.pck``.

ArduPilot (4.1+, GCS_FTP.cpp and AP_Filesystem_Param.cpp) serves every parameter as one packed file, which
MAVProxy and QGroundControl read instead of the PARAM_VALUE stream where the vehicle advertises
MAV_PROTOCOL_CAPABILITY_FTP. The file (``pack_params``): a header (magic 0x671b, count, total count), then per
parameter in index order one byte type (1 int8, 2 int16, 3 int32, 4 float), one byte (name length - 1) << 4 | the
length of the prefix shared with the previous name, the rest of the name, the value little-endian. pymavlink's
``MAVFTP.ftp_param_decode`` reads it.

Served here: OpenFileRO (one session; another path: NAK FileNotFound), ReadFile, BurstReadFile (chunks of
239 bytes from the offset to the end, the last one marked burst_complete, sent within the link's budget as the
parameter replies are: ``ParamProtocol``), TerminateSession, ResetSessions; anything else: NAK UnknownCommand.
"""
from __future__ import annotations

import struct

from pymavlink.dialects.v20 import ardupilotmega as mavlink

__all__ = ["FtpServer", "pack_params", "PARAM_FILE", "CHUNK"]

PARAM_FILE = "@PARAM/param.pck"
CHUNK = 239                       # data bytes in one FILE_TRANSFER_PROTOCOL payload (251 - 12 header)
HEADER = struct.Struct("<HBBBBBBI")
OP_TERMINATE, OP_RESET, OP_OPEN_RO, OP_READ, OP_BURST = 1, 2, 4, 5, 15
OP_ACK, OP_NAK = 128, 129
ERR_FAIL, ERR_INVALID_SESSION, ERR_EOF, ERR_UNKNOWN, ERR_NOT_FOUND = 1, 4, 6, 7, 10
_PCK_TYPES = {mavlink.MAV_PARAM_TYPE_INT8: (1, "<b"), mavlink.MAV_PARAM_TYPE_INT16: (2, "<h"),
              mavlink.MAV_PARAM_TYPE_INT32: (3, "<i"), mavlink.MAV_PARAM_TYPE_REAL32: (4, "<f")}


def pack_params(params) -> bytes:
    """``SimParams`` as ArduPilot's param.pck (no defaults, no padding: the decoder needs neither)."""
    out = [struct.pack("<HHH", 0x671B, len(params), len(params))]
    last = b""
    for name, value in params.items():
        code, fmt = _PCK_TYPES[params.type_of(name)]
        raw = name.encode()
        common = 0
        while common < min(len(raw) - 1, len(last), 15) and raw[common] == last[common]:
            common += 1
        rest = raw[common:]
        out.append(bytes([code, (len(rest) - 1) << 4 | common]) + rest + struct.pack(fmt, value))
        last = raw
    return b"".join(out)


class _Session:
    def __init__(self, data: bytes, peer) -> None:
        self.data = data
        self.peer = peer
        self.burst: tuple[int, int] | None = None     # (next offset, the request's seq) while a burst runs
        self.reads: list[tuple[int, int]] = []        # ReadFile requests (offset, seq), answered first

    @property
    def sending(self) -> bool:
        return self.burst is not None or bool(self.reads)


class FtpServer:
    """Mixed into the Autopilot; the burst is sent from ``ParamProtocol.params_step`` within the link's budget."""

    ftp_session: _Session | None = None
    ftp_gcs: tuple[int, int] = (255, 190)          # who asked last (the reply's target)

    def _ftp_reply(self, request: tuple, opcode: int, data: bytes = b"", offset: int | None = None,
                   burst_complete: int = 0, peer=None):
        seq, session, req_opcode, req_offset = request
        payload = HEADER.pack((seq + 1) & 0xFFFF, session, opcode, len(data), req_opcode, burst_complete, 0,
                              req_offset if offset is None else offset) + data
        msg = self.factory.file_transfer_protocol_encode(0, self.ftp_gcs[0], self.ftp_gcs[1],
                                                         list(payload.ljust(251, b"\0")))
        self.emit_to(msg, peer if peer is not None else self.sender)

    def _ftp_nak(self, request: tuple, error: int) -> None:
        self._ftp_reply(request, OP_NAK, bytes([error]))

    def _on_file_transfer_protocol(self, msg) -> None:
        if msg.target_system not in (0, self.config.system_id):
            return
        payload = bytes(msg.payload)
        seq, session, opcode, size, _, _, _, offset = HEADER.unpack(payload[:12])
        data = payload[12:12 + size]
        self.ftp_gcs = (msg.get_srcSystem(), msg.get_srcComponent())
        request = (seq, session, opcode, offset)
        if opcode == OP_OPEN_RO:
            path = data.split(b"\0", 1)[0].decode(errors="replace")
            if path != PARAM_FILE and not path.startswith(PARAM_FILE + "?"):
                self._ftp_nak(request, ERR_NOT_FOUND)
                return
            self.ftp_session = _Session(pack_params(self.params), self.sender)
            self._ftp_reply(request, OP_ACK, struct.pack("<I", len(self.ftp_session.data)))
        elif opcode in (OP_TERMINATE, OP_RESET):
            self.ftp_session = None
            self._ftp_reply(request, OP_ACK)
        elif opcode in (OP_READ, OP_BURST):
            s = self.ftp_session
            if s is None or session != 0:
                self._ftp_nak(request, ERR_INVALID_SESSION)
            elif offset >= len(s.data):
                self._ftp_nak(request, ERR_EOF)
            elif opcode == OP_READ:
                if len(s.reads) < 20:                      # answered within the link's budget (params_step)
                    s.reads.append((offset, seq))
            else:
                s.burst, s.peer = (offset, seq), self.sender
        else:
            self._ftp_nak(request, ERR_UNKNOWN)

    def ftp_burst_chunk(self) -> int:
        """Send the next read's answer, else the burst's next chunk; returns its frame's bytes (0: none)."""
        s = self.ftp_session
        if s is None or not s.sending:
            return 0
        if s.reads:
            offset, seq = s.reads.pop(0)
            chunk = s.data[offset:offset + CHUNK]
            self._ftp_reply((seq, 0, OP_READ, offset), OP_ACK, chunk, offset, 0, s.peer)
            return 12 + 3 + 12 + len(chunk)
        offset, seq = s.burst
        chunk = s.data[offset:offset + CHUNK]
        last = offset + len(chunk) >= len(s.data)
        self._ftp_reply((seq, 0, OP_BURST, offset), OP_ACK, chunk, offset, 1 if last else 0, s.peer)
        s.burst = None if last else (offset + len(chunk), seq)
        return 12 + 3 + 12 + len(chunk)
