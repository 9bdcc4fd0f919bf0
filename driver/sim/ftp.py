"""The simulated ArduCopter's MAVLink FTP, for the one file a ground station reads fast: ``@PARAM/param.pck``.

ArduPilot (4.1+, GCS_FTP.cpp and AP_Filesystem_Param.cpp) serves every parameter as one packed file, which
MAVProxy and QGroundControl read instead of the PARAM_VALUE stream where the vehicle advertises
MAV_PROTOCOL_CAPABILITY_FTP. The file (:func:`pack`): a header (magic 0x671b, or 0x671c with defaults, count,
total count), then per parameter in index order one byte type (1 int8, 2 int16, 3 int32, 4 float; bit 4: a default
follows the value), one byte (name length - 1) << 4 | the length of the prefix shared with the previous name, the
rest of the name, the value little-endian. Zero pad bytes keep every value inside one read packet, so the file
depends on the packet size, which the first read of an open fixes. pymavlink's ``MAVFTP.ftp_param_decode`` reads it.

Answered as ArduCopter 4.6.3 does in tests/data/recordings/arducopter-4.6-sitl-ftp-params.* (one file open at a
time, one worker answering the requests in order from a queue of :data:`REQUEST_QUEUE`, one packet every
:data:`PACKET_INTERVAL` of sim time, as the recording's TCP link shows; on a radio a burst takes a third of its
bandwidth, as GCS_FTP's burst delay makes it):

* OpenFileRO: ACK size 4 with the file's size as ArduPilot *estimates* it, 12 bytes a parameter (the real file is
  smaller), then the version banner; another path: NAK 10 (FileNotFound); while a file is open: NAK 1 (Fail) to the
  same session, NAK 4 (InvalidSession) to another (unless the open one has been idle for 3 s);
* BurstReadFile: at most :data:`BURST_PACKETS` ACKs at offset + i * size, seq counting up from the request's + 1,
  burst_complete only on the 500th; at the end of the file a short last packet (burst_complete 0) and then NAK 6
  (EOF) whose offset is the end after a short packet, the last full packet's offset when the file is a multiple of
  the packet size (0 when the burst starts at the end);
* ReadFile: one ACK of the packet size; at or past the end NAK 6 with offset 0; another packet size than the
  open's first read: NAK 2 (FailErrno) errno 22; no file open: NAK 10;
* TerminateSession, ResetSessions: ACK (size 0); a request repeating the last one's seq gets the last reply again;
  anything else: NAK 1.

The log folder too, as the logs recording shows (arducopter-4.6-sitl-logs.*): ListDirectory of ``logs`` and ``/``
(``/APM/LOGS``: NAK 10, an empty path: NAK 3), OpenFileRO of ``logs/0000000N.BIN`` (its true size, no banner), read
by the same worker. The Solo profile (3.3) has no MAVLink FTP: its requests go unanswered.
"""
from __future__ import annotations

import os
import struct
from collections import deque

from pymavlink.dialects.v20 import ardupilotmega as mavlink

__all__ = ["FtpServer", "pack", "sim_entries", "PARAM_FILE", "CHUNK", "BURST_PACKETS", "PACKET_INTERVAL",
           "SIZE_ESTIMATE"]

PARAM_FILE = "@PARAM/param.pck"
CHUNK = 239                       # data bytes in one FILE_TRANSFER_PROTOCOL payload (251 - 12 header)
HEADER = struct.Struct("<HBBBBBBI")
OP_TERMINATE, OP_RESET, OP_LIST, OP_OPEN_RO, OP_READ, OP_BURST = 1, 2, 3, 4, 5, 15
OP_ACK, OP_NAK = 128, 129
ERR_FAIL, ERR_ERRNO, ERR_SIZE, ERR_INVALID_SESSION, ERR_EOF, ERR_NOT_FOUND = 1, 2, 3, 4, 6, 10
EINVAL = 22
BURST_PACKETS = 500               # ACKs one BurstReadFile gets at most (GCS_FTP.cpp's transfer_size in 4.6)
PACKET_INTERVAL = 0.0055          # s of sim time between FTP packets (the recording: 5.4-5.7 ms over TCP)
REQUEST_QUEUE = 5                 # requests waiting for the worker; one more is dropped (ArduPilot's ObjectBuffer)
SESSION_TIMEOUT = 3.0             # s idle before another session may take the open file over
SIZE_ESTIMATE = 12                # bytes a parameter: the size OpenFileRO reports (AP_Filesystem_Param::stat)
FRAME_OVERHEAD = 12 + 3 + 12      # a FILE_TRANSFER_PROTOCOL frame's bytes besides the data (MAVLink 2, FTP header)
BURST_SHARE = 3                   # a burst on a radio leaves the link 2/3 free (burst_delay_ms)
MAGIC, MAGIC_DEFAULTS = 0x671B, 0x671C
_PCK_TYPES = {mavlink.MAV_PARAM_TYPE_INT8: 1, mavlink.MAV_PARAM_TYPE_INT16: 2,
              mavlink.MAV_PARAM_TYPE_INT32: 3, mavlink.MAV_PARAM_TYPE_REAL32: 4}
_FORMATS = {1: "<b", 2: "<h", 3: "<i", 4: "<f"}


def pack(entries, read_size: int, with_defaults: bool = False) -> bytes:
    """``entries`` (name, file type 1-4, value, default) as ArduPilot's param.pck read in ``read_size`` packets:
    AP_Filesystem_Param::pack_param, pad bytes included. ``default`` is None unless the parameter's default differs
    from its value (ArduPilot sends a default only then, and only ``with_defaults``)."""
    entries = list(entries)
    out = bytearray(struct.pack("<HHH", MAGIC_DEFAULTS if with_defaults else MAGIC, len(entries), len(entries)))
    last = b""
    for name, code, value, default in entries:
        raw = name.encode()
        common = 0
        while common < min(len(raw), len(last)) and raw[common] == last[common]:
            common += 1
        if common == len(raw):                       # the name is a prefix of the last one: send one byte of it
            common -= 1
        rest = raw[common:]
        fmt = _FORMATS[code]
        add_default = with_defaults and default is not None
        value_bytes = struct.pack(fmt, value) + (struct.pack(fmt, default) if add_default else b"")
        type_len = struct.calcsize(fmt)
        record = bytes([code | (0x10 if add_default else 0), (len(rest) - 1) << 4 | common]) + rest + value_bytes
        if type_len > 1:                             # a value never crosses a packet boundary
            end_mod = (len(out) + len(record)) % read_size
            if 0 < end_mod < type_len:
                out += bytes(type_len - end_mod)
        out += record
        last = raw
    return bytes(out)


def sim_entries(params) -> list[tuple[str, int, float, None]]:
    """``SimParams`` as :func:`pack` takes them (the sim knows no defaults: none differs from its value)."""
    return [(name, _PCK_TYPES[params.type_of(name)], value, None) for name, value in params.items()]


class _OpenFile:
    """The open param.pck: packed when the first read fixes the packet size (AP_Filesystem_Param::read)."""

    def __init__(self, entries, with_defaults: bool) -> None:
        self.entries = entries
        self.with_defaults = with_defaults
        self.read_size = 0
        self.data = b""

    def read(self, offset: int, count: int) -> bytes | None:
        """The bytes at ``offset`` (b"" at the end), None for another packet size than the first read's."""
        if self.read_size == 0 and count > 0:
            self.read_size = count
            self.data = pack(self.entries, count, self.with_defaults)
        if self.read_size != count:
            return None
        return self.data[offset:offset + count]


class _BytesFile:
    """A log (``logs/0000000N.BIN``) as it was when opened: any packet size reads it."""

    def __init__(self, data: bytes) -> None:
        self.data = data

    def read(self, offset: int, count: int) -> bytes:
        return self.data[offset:offset + count]


ROOT_ENTRIES = ("D.", "Dlogs", "D..", "Dterrain", "D@ROMFS", "D@SYS")      # "/" on the 4.6.3 SITL


class _Reply:
    """One reply as GCS_FTP builds it: kept whole, since a burst reuses it packet after packet."""

    def __init__(self, request: tuple, target: tuple[int, int], peer) -> None:
        seq, session, opcode, _, _, _ = request
        self.seq, self.session, self.req_opcode = (seq + 1) & 0xFFFF, session, opcode
        self.opcode, self.data, self.offset, self.burst_complete = OP_ACK, b"", 0, 0
        self.target, self.peer = target, peer

    def nak(self, error: int, errno: int | None = None) -> None:
        self.opcode, self.data = OP_NAK, bytes([error] if errno is None else [error, errno])

    def payload(self) -> bytes:
        return HEADER.pack(self.seq, self.session, self.opcode, len(self.data), self.req_opcode, self.burst_complete,
                           0, self.offset) + self.data


class FtpServer:
    """Mixed into the Autopilot; its packets go out from ``ParamProtocol.params_step`` (:meth:`ftp_packet`)."""

    ftp_file: _OpenFile | None = None
    ftp_session: int = -1              # the open file's session (-1: none)
    ftp_last_send: float = 0.0
    ftp_queue: deque | None = None     # (request, data, target, peer) waiting for the worker
    ftp_burst: tuple | None = None     # (request, reply, packet size, packets sent) while a burst runs
    ftp_last: _Reply | None = None
    ftp_credit: float = 0.0            # packets the pacing allows now

    def ftp_entries(self):
        return sim_entries(self.params)

    def _on_file_transfer_protocol(self, msg) -> None:
        profile = getattr(self, "profile", None)         # the Autopilot's firmware profile (absent in a bare worker)
        if msg.target_system not in (0, self.config.system_id) or (profile is not None and profile.version[0] < 4):
            return                                       # the Solo's 3.3 has no MAVLink FTP
        payload = bytes(msg.payload)
        seq, session, opcode, size, _, _, _, offset = HEADER.unpack(payload[:12])
        if self.ftp_queue is None:
            self.ftp_queue = deque()
        if len(self.ftp_queue) < REQUEST_QUEUE:          # a full queue drops it (treated as lost on the radio)
            self.ftp_queue.append(((seq, session, opcode, size, offset, payload[12:]),
                                   (msg.get_srcSystem(), msg.get_srcComponent()), self.sender))

    @property
    def ftp_busy(self) -> bool:
        return self.ftp_burst is not None or bool(self.ftp_queue)

    def ftp_peer(self):
        """The link the worker's next packet goes to (while :attr:`ftp_busy`)."""
        if self.ftp_burst is not None:
            return self.ftp_burst[1].peer
        return self.ftp_queue[0][2] if self.ftp_queue else None

    def ftp_tick(self, dt: float) -> None:
        """Sim time passes: the worker may send one packet every :data:`PACKET_INTERVAL`; on a radio (no flow
        control) ArduPilot also waits between a burst's packets so that FTP takes at most a third of the link
        (GCS_FTP's burst_delay_ms = 3000 * packet bytes / link bytes a second)."""
        interval = PACKET_INTERVAL
        baud = getattr(self.config, "radio_baud", None)
        burst = self.ftp_burst[0] if self.ftp_burst is not None else \
            self.ftp_queue[0][0] if self.ftp_queue and self.ftp_queue[0][0][2] == OP_BURST else None
        if baud and burst is not None:
            interval = max(interval, BURST_SHARE * (FRAME_OVERHEAD + (burst[3] or CHUNK)) / (baud / 10.0))
        self.ftp_credit = min(self.ftp_credit + dt / interval, 1.0 + dt / interval) if self.ftp_busy else 0.0

    def ftp_packet(self, paced: bool = True) -> int:
        """Send the worker's next packet; returns its frame's bytes (0: none due)."""
        if paced and self.ftp_credit < 1.0:
            return 0
        while self.ftp_burst is None and self.ftp_queue:
            request, target, peer = self.ftp_queue.popleft()
            reply = self._ftp_handle(request, target, peer)
            if reply is not None:
                break
        else:
            reply = self._ftp_burst_packet() if self.ftp_burst is not None else None
        if reply is None:
            return 0
        self.ftp_credit -= 1.0
        self._ftp_send(reply)
        if reply.req_opcode == OP_OPEN_RO and reply.opcode == OP_ACK and isinstance(self.ftp_file, _OpenFile):
            self._banner()                          # send_banner() after the open of param.pck, as 4.6.3 does
        return FRAME_OVERHEAD + len(reply.data)

    # -- the worker ---------------------------------------------------------------------------------------
    def _ftp_send(self, reply: _Reply) -> None:
        self.ftp_last, self.ftp_last_send = reply, self.t
        msg = self.factory.file_transfer_protocol_encode(0, reply.target[0], reply.target[1],
                                                         list(reply.payload().ljust(251, b"\0")))
        self.emit_to(msg, reply.peer)

    def _ftp_handle(self, request: tuple, target, peer) -> _Reply | None:
        """One request as GCS_MAVLINK::ftp_worker answers it; None while a burst has only just begun."""
        seq, session, opcode, size, offset, data = request
        last = self.ftp_last
        if last is not None and last.session == session and (seq + 1) & 0xFFFF == last.seq and last.target == target:
            return last                              # a re-request: the last reply again
        reply = _Reply(request, target, peer)
        idle = self.t - self.ftp_last_send >= SESSION_TIMEOUT
        if size > CHUNK:
            reply.nak(ERR_SIZE)
        elif session != self.ftp_session and opcode in (OP_TERMINATE, OP_RESET):
            pass                                     # another session's end: just ACK
        elif self.ftp_file is not None and session != self.ftp_session and not idle:
            reply.nak(ERR_INVALID_SESSION)
        else:
            if self.ftp_file is not None and session != self.ftp_session:
                self.ftp_file, self.ftp_session = None, -1    # the old session idled out: closed
            if opcode in (OP_TERMINATE, OP_RESET):
                self.ftp_file, self.ftp_session = None, -1
            elif opcode == OP_LIST:
                self._ftp_list(reply, data[:size].split(b"\0", 1)[0].decode(errors="replace"), offset)
            elif opcode == OP_OPEN_RO:
                self._ftp_open(reply, data[:size].split(b"\0", 1)[0].decode(errors="replace"), idle)
            elif opcode in (OP_READ, OP_BURST) and self.ftp_file is None:
                reply.nak(ERR_NOT_FOUND)
            elif opcode == OP_READ:
                got = self.ftp_file.read(offset, min(CHUNK, size))
                if got is None:
                    reply.nak(ERR_ERRNO, EINVAL)
                elif not got:
                    reply.nak(ERR_EOF)
                else:
                    reply.data, reply.offset = got, offset
            elif opcode == OP_BURST:
                self.ftp_burst = (request, reply, size or CHUNK, 0)
                return self._ftp_burst_packet()
            else:
                reply.nak(ERR_FAIL)
        return reply

    def _ftp_list(self, reply: _Reply, path: str, offset: int) -> None:
        """ListDirectory as the 4.6.3 SITL answers it: ``logs`` (relative) and ``/``; entries ``F<name>\\t<size>``
        or ``D<name>``, each followed by two NULs, from entry ``offset`` on; past the last: NAK EOF."""
        folder = path.strip("/")
        if not path:
            reply.nak(ERR_SIZE)
            return
        if path == "/":
            entries = list(ROOT_ENTRIES)
        elif folder == "logs":
            logs = self.log_folder
            entries = ["D.", "D.."] + [f"F{name}\t{os.path.getsize(os.path.join(logs.folder, name))}"
                                       for name in sorted(os.listdir(logs.folder), reverse=True)
                                       if os.path.isfile(os.path.join(logs.folder, name))]
        else:
            reply.nak(ERR_NOT_FOUND)
            return
        out = b""
        for entry in entries[offset:]:
            raw = entry.encode() + b"\0\0"
            if len(out) + len(raw) > CHUNK:
                break
            out += raw
        if not out:
            reply.nak(ERR_EOF)
        else:
            reply.data = out

    def _ftp_open(self, reply: _Reply, path: str, idle: bool) -> None:
        if self.ftp_file is not None and idle:
            self.ftp_file, self.ftp_session = None, -1
        if self.ftp_file is not None:
            reply.nak(ERR_FAIL)
        elif path.startswith("logs/") and "/" not in path[5:] and path[5:] in os.listdir(self.log_folder.folder):
            with open(os.path.join(self.log_folder.folder, path[5:]), "rb") as f:
                self.ftp_file = _BytesFile(f.read())
            self.ftp_session = reply.session
            reply.data = struct.pack("<I", len(self.ftp_file.data))
        elif path != PARAM_FILE and not path.startswith(PARAM_FILE + "?"):
            reply.nak(ERR_NOT_FOUND)
        else:
            entries = self.ftp_entries()
            self.ftp_file = _OpenFile(entries, "withdefaults=1" in path)
            self.ftp_session = reply.session
            reply.data = struct.pack("<I", SIZE_ESTIMATE * len(entries))

    def _ftp_burst_packet(self) -> _Reply | None:
        """The burst's next ACK, or the NAK that ends it (GCS_MAVLINK::ftp_worker's BurstReadFile loop)."""
        request, reply, max_read, i = self.ftp_burst
        if i >= BURST_PACKETS:
            self.ftp_burst = None
            return None
        offset = request[4]
        got = self.ftp_file.read(offset + i * max_read, min(CHUNK, max_read)) if self.ftp_file is not None else None
        if got is None:
            reply.nak(ERR_ERRNO, EINVAL)
        elif not got:
            reply.nak(ERR_EOF)                       # offset: as the last packet left it (0 at the first)
        else:
            reply.opcode, reply.data = OP_ACK, got
            reply.offset = offset + i * max_read
            reply.burst_complete = 1 if i == BURST_PACKETS - 1 else 0
            sent = _Reply.__new__(_Reply)
            sent.__dict__.update(reply.__dict__)
            if len(got) < max_read:
                reply.offset += len(got)             # the NAK that follows says where the file ended
            reply.seq = (reply.seq + 1) & 0xFFFF
            self.ftp_burst = (request, reply, max_read, i + 1) if i + 1 < BURST_PACKETS else None
            return sent
        self.ftp_burst = None
        return reply
