"""One MAVLink FTP engine: read a file from the vehicle by BurstReadFile, fill the gaps with ReadFile, learn the
file's end from the vehicle, as ArduPilot (GCS_FTP.cpp) answers. It serves the parameters (``@PARAM/param.pck``,
driver.params.ftp) and the DataFlash logs (``/APM/LOGS/0000000N.BIN`` or SITL's ``logs/…``, driver.logs), whose folder
:class:`FtpList` lists.

What ArduCopter 4.6.3 does (tests/data/recordings/README.md, "MAVFTP parameter download" and "Log download"):

* the size in the OpenFileRO ACK may be an estimate (param.pck: 12 bytes a parameter), so it is never used to end
  or check the read: the end of the file is learnt from a short packet, or from a NAK EOF (mapped to its request
  by seq: a reply's seq is the request's + 1, counting up within a burst). A burst's NAK offset is the end after a
  short packet, the last full packet's offset when the file is a multiple of the packet size; a ReadFile at or
  past the end gets NAK EOF with offset 0, so its own offset bounds the file;
* a BurstReadFile gets at most 500 packets, burst_complete only on the 500th: the next burst starts after it;
* the first read fixes the packet size: every read here asks for :data:`CHUNK` bytes, and a ReadFile fills each
  gap the link left;
* a second OpenFileRO while the file is open is refused (NAK 1): after a lost ACK the file is open, so reading
  goes on; to the first open it means a file left open before (a read given up), so ResetSessions closes it and
  the open is sent again; TerminateSession ends every read, given up or not.

How long a request may stay unanswered is the link's, not the reader's: the vehicle's one round-trip estimate
(:class:`driver.core.roundtrip.RoundTrip`), which the open's ACK, each burst's first packet and every ReadFile
answered once feed.

Any trouble (no progress for ``stall`` seconds, a NAK other than EOF, a chunk asked :data:`READ_TRIES` times) ends
it with a reason. All methods run with the driver's state lock held and return what to send.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core.roundtrip import RoundTrip

__all__ = ["FtpRead", "FtpSpanRead", "FtpList", "CHUNK", "HEADER", "STALL_SECONDS", "NAK_TEXT"]

CHUNK = 239                # bytes a packet: the most one FILE_TRANSFER_PROTOCOL carries
HEADER = struct.Struct("<HBBBBBBI")
OP_TERMINATE, OP_RESET, OP_LIST, OP_OPEN_RO, OP_READ, OP_BURST, OP_ACK, OP_NAK = 1, 2, 3, 4, 5, 15, 128, 129
ERR_FAIL, ERR_INVALID_SESSION, ERR_EOF = 1, 4, 6
NAK_TEXT = {1: "failed", 2: "failed (errno)", 3: "invalid size", 4: "invalid session", 5: "no session available",
            6: "end of file", 7: "unknown command", 10: "file not found"}
STALL_SECONDS = 3.0        # no FTP progress (an answer to the open, a new byte of the file) this long: the list instead
OPEN_RETRY = 0.25          # s between OpenFileRO tries (a retry after a lost ACK is refused: the file is open)
BURST_QUIET = 0.3          # s without a packet before a burst counts as over (its end lost): gaps are then read,
                           # or the link's timeout, whichever is longer
BURST_GAPS = 8             # ... or this many of its packet intervals (a radio's burst sends one every 140 ms)
READ_WINDOW = 4            # ReadFiles out at once (ArduPilot queues 5 FTP requests and drops one more) ...
READ_WINDOW_MAX = 6        # ... up to this many when the link loses requests: of 6 sent through 30 % loss about 4
                           # arrive, and a worker left with an empty queue waits a round trip for the next one
READ_TIMEOUT_MIN = 0.05    # s before a ReadFile is asked again, or the link's timeout, whichever is longer (0.2 s
                           # made each lost read of 4 in flight cost 0.2 s: 2 MB at 30 % loss 46 s, 19 s on the sim)
FIRST_GUESS = 0.1          # s: the round trip guessed by a reader not handed the vehicle's (a read outside a vehicle)
READ_TRIES = 20            # ReadFiles for one chunk before FTP is given up
LIST_RETRY = 0.5           # s before a ListDirectory without its answer is asked again
BURSTS = 20                # BurstReadFiles at most by default (a 16-byte-packet file of 15 kB needs 2; param.pck: 1)


def _frame(target: tuple[int, int], seq: int, session: int, opcode: int, size: int, offset: int, data: bytes = b""):
    payload = HEADER.pack(seq, session, opcode, size, 0, 0, 0, offset) + data
    return mavlink.MAVLink_file_transfer_protocol_message(0, target[0], target[1], list(payload.ljust(251, b"\0")))


@dataclass
class FtpRead:
    """One file read: ``path`` as the vehicle names it; ``bursts``: BurstReadFiles at most (a big file needs one
    per 500 packets); ``stall``: seconds without progress before it is given up; ``roundtrip``: the vehicle's
    round-trip estimate (None: one of its own)."""
    started: float
    path: bytes = b""
    session: int = 0                     # replies echo it: another engine's (another session's) are not ours
    max_bursts: int = BURSTS
    stall: float = STALL_SECONDS
    estimate: int | None = None          # the open's size: ArduPilot's guess, shown, never relied on
    chunks: dict[int, bytes] = field(default_factory=dict)    # offset -> data
    end: int | None = None               # the file's real size, once a short packet or an EOF says it
    bound: int | None = None             # the file ends at or before this (a ReadFile's EOF)
    phase: str = "open"                  # open, read, done
    seq: int = 0
    sent: dict[int, tuple[int, int, float]] = field(default_factory=dict)   # seq -> (opcode, offset, when)
    open_sent: float = -1.0
    opens: int = 0
    burst: int | None = None             # the running burst's seq
    next_burst: int | None = 0           # where the next BurstReadFile starts (None: none to send)
    reset: bool = False                  # the file was open already: ResetSessions before the next open
    bursts: int = 0
    heard: float = 0.0                   # last FTP frame from the vehicle
    gap: float = 0.0                     # smoothed time between a burst's packets (by their seqs)
    last_packet: tuple[int, float] | None = None              # (seq, when) of the last burst packet heard
    burst_timed: int | None = None       # the burst whose first packet timed the link
    progress: float = 0.0                # last answer to the open or new byte of the file
    asked: dict[int, float] = field(default_factory=dict)     # gap offset -> when asked
    tries: dict[int, int] = field(default_factory=dict)       # gap offset -> ReadFiles sent
    reads_sent: int = 0
    reads_answered: int = 0              # ReadFiles whose chunk came back while asked
    frames: int = 0                      # FTP frames received (the cost on the radio)
    roundtrip: RoundTrip | None = None

    def __post_init__(self) -> None:
        self.heard = self.progress = self.started
        if self.roundtrip is None:
            self.roundtrip = RoundTrip(initial=FIRST_GUESS)

    @property
    def received(self) -> int:
        return sum(len(c) for c in self.chunks.values())

    @property
    def total(self) -> int | None:
        """The size to show: the real one once known, else the vehicle's estimate."""
        return self.end if self.end is not None else self.estimate

    def _request(self, target: tuple[int, int], opcode: int, offset: int = 0, data: bytes = b"", size=None, now=0.0):
        self.seq = (self.seq + 1) & 0xFFFF
        self.sent[self.seq] = (opcode, offset, now)
        return _frame(target, self.seq, self.session, opcode, len(data) if size is None else size, offset, data)

    # -- where the bytes go: kept in ``chunks`` here (FtpSpanRead hands them on) ------------------------------
    def _held(self, offset: int) -> bool:
        return offset in self.chunks

    def _keep(self, offset: int, data: bytes) -> None:
        self.chunks[offset] = data

    def _top(self) -> int:
        """The end of the highest chunk slot received."""
        return max(self.chunks, default=-CHUNK) + CHUNK

    def _whole_to(self, bound: int) -> bool:
        """The last chunk below ``bound`` is full (every one below it has come)."""
        last = max((o for o in self.chunks if o < bound), default=None)
        return last is None or len(self.chunks[last]) == CHUNK

    def _known_top(self) -> int:
        return self.end if self.end is not None else self.bound if self.bound is not None else self._top()

    def missing(self, most: int | None = None) -> list[int]:
        """Offsets of the chunks not received below what is known of the file (its end, else the highest chunk);
        the first ``most`` of them where that is all the caller needs."""
        return [o for o in range(0, self._known_top(), CHUNK) if o not in self.chunks]

    def _learn_end(self) -> None:
        """A bound below which every chunk has arrived, the last one full: the file ends exactly there."""
        if self.end is None and self.bound is not None and not self.missing(1) and self._whole_to(self.bound):
            self.end = self.bound

    # -- the vehicle's answers ----------------------------------------------------------------------
    def on_message(self, m, now: float) -> str | None:
        """A FILE_TRANSFER_PROTOCOL reply; returns why the transfer failed, else None."""
        payload = bytes(m.payload)
        seq, session, opcode, size, req_opcode, burst_complete, _, offset = HEADER.unpack(payload[:12])
        if session != self.session:
            return None                         # another engine's file (the parameters' or a log's)
        data = payload[12:12 + size]
        self.frames += 1
        self.heard = now
        if 0 < (seq - self.seq) & 0xFFFF < 0x8000:
            # the next request follows the vehicle's last seq, as pymavlink's MAVFTP does: ArduPilot answers a
            # request whose seq is one below its last reply's with that reply again (a re-request)
            self.seq = seq
        if opcode == OP_NAK:
            return self._on_nak(seq, req_opcode, offset, data[0] if data else 0, now)
        if opcode != OP_ACK:
            return None
        if req_opcode == OP_OPEN_RO and self.phase == "open" and size >= 4:
            self.estimate = struct.unpack("<I", data[:4])[0]
            if self.opens == 1 and self.open_sent >= 0:          # opened once: the ACK answers it (Karn)
                self.roundtrip.sample(now - self.open_sent)
            self._opened(now)
        elif req_opcode in (OP_READ, OP_BURST) and self.phase == "read" and offset % CHUNK == 0 and data:
            if req_opcode == OP_BURST:
                self._burst_packet(seq, now)
            if not self._held(offset):
                self._keep(offset, data)
                self.progress = now
            if len(data) < CHUNK:
                self.end = offset + len(data)
                if req_opcode == OP_BURST and self.burst is not None:
                    self.sent.pop(self.burst, None)     # only its NAK EOF can follow: the gaps are read now
                    self.burst = None
            sent = self.asked.pop(offset, None)
            if sent is not None and req_opcode == OP_READ:
                self.reads_answered += 1
            if sent is not None and self.tries.get(offset) == 1:     # asked once: the answer is its own (Karn)
                self.roundtrip.sample(now - sent)
            if req_opcode == OP_READ:
                self._answered_read((seq - 1) & 0xFFFF)
            elif burst_complete and self.burst is not None:
                self.sent.pop(self.burst, None)
                self.burst = None
                self.next_burst = offset + CHUNK        # the vehicle stopped at 500 packets: ask for more
            self._learn_end()
        return None

    def _burst_packet(self, seq: int, now: float) -> None:
        """Learn the burst's pace; a packet after the burst was judged over says the vehicle is still bursting:
        the ReadFiles sent meanwhile wait behind it in its queue, so their time starts again. The first packet
        heard of a burst answers its one BurstReadFile: it times the link."""
        asked = self.sent.get(self.burst) if self.burst is not None else None
        if asked is not None and self.burst_timed != self.burst:
            self.burst_timed = self.burst
            self.roundtrip.sample(now - asked[2])
        if self.last_packet is not None and 0 < (seq - self.last_packet[0]) & 0xFFFF < 50:
            each = (now - self.last_packet[1]) / ((seq - self.last_packet[0]) & 0xFFFF)
            self.gap = each if not self.gap else 0.7 * self.gap + 0.3 * each
        self.last_packet = (seq, now)
        if self.burst is None:
            for offset in self.asked:
                self.asked[offset] = now

    def _answered_read(self, request: int) -> None:
        """The vehicle answers its queue in order: a ReadFile sent before this one and still unanswered was lost,
        or its answer was: it is asked again at once."""
        self.sent.pop(request, None)
        for seq, (opcode, offset, _) in list(self.sent.items()):
            if opcode == OP_READ and 0 < (request - seq) & 0xFFFF < 1000:
                del self.sent[seq]
                self.asked.pop(offset, None)

    def _opened(self, now: float) -> None:
        self.phase, self.progress = "read", now

    def _on_nak(self, seq: int, req_opcode: int, offset: int, error: int, now: float) -> str | None:
        if req_opcode == OP_OPEN_RO and self.phase == "open":
            if error == ERR_FAIL and self.opens > 1:
                self._opened(now)                       # our earlier open was ACKed, its ACK lost: it is open
                return None
            if error == ERR_FAIL and not self.reset:    # open from before (a fetch given up): close, open again
                self.reset, self.open_sent = True, -1.0
                return None
            return f"was refused: the vehicle said {NAK_TEXT.get(error, error)} to the open of {self.path.decode()}"
        if req_opcode == OP_READ:
            request = self.sent.get((seq - 1) & 0xFFFF)
            self._answered_read((seq - 1) & 0xFFFF)
        elif req_opcode == OP_BURST:                    # the burst's seqs count up from its request's
            mine = [s for s, (op, _, _) in self.sent.items() if op == OP_BURST and 0 < (seq - s) & 0xFFFF < 1000]
            request = self.sent.pop(min(mine, key=lambda s: (seq - s) & 0xFFFF)) if mine else None
        else:
            return None
        if request is None or self.phase != "read":
            return None                                 # an answer to something no longer asked
        _, asked_at, _ = request
        if error != ERR_EOF:
            return f"was refused: the vehicle said {NAK_TEXT.get(error, error)} to a read at byte {asked_at:,}"
        if req_opcode == OP_READ:
            self.asked.pop(asked_at, None)
            self.bound = asked_at if self.bound is None else min(self.bound, asked_at)
        else:
            if self.burst is not None and self.sent.get(self.burst) is None:
                self.burst = None                       # this burst is over
            if offset % CHUNK:                          # after a short packet: the end itself
                self.end = offset
            else:   # after a full packet, its offset; 0 when the burst began at the end (or after one packet)
                limit = offset + CHUNK if offset > 0 else asked_at or CHUNK
                self.bound = limit if self.bound is None else min(self.bound, limit)
        self._learn_end()
        return None

    # -- the ticker ----------------------------------------------------------------------------------

    def service(self, now: float, target: tuple[int, int]) -> tuple[list, str | None]:
        """Messages to send, and why it failed (None while it goes on)."""
        if self.phase == "done":
            return [], None
        if now - self.progress >= self.stall:
            if self.phase == "open":
                return [], f"got no answer to the open of {self.path.decode()} in {self.stall:g} s"
            return [], f"stalled at byte {self.received:,}" + (
                f" (the file has {self.end:,})" if self.end is not None else
                f" (about {self.estimate:,} by the vehicle's estimate)" if self.estimate else "") + \
                f": nothing new for {self.stall:g} s"
        if self.phase == "open":
            if self.open_sent < 0 or now - self.open_sent >= OPEN_RETRY:
                self.opens += 1
                self.open_sent = now
                first = [self._request(target, OP_RESET, now=now)] if self.reset and self.opens == 2 else []
                return first + [self._request(target, OP_OPEN_RO, 0, self.path, now=now)], None
            return [], None
        out = []
        if self.next_burst is not None and (self.end is None or self.next_burst < self.end):
            if self.bursts >= self.max_bursts:
                return [], f"gave up: {self.bursts} bursts did not bring the whole file"
            self.bursts += 1
            out.append(self._request(target, OP_BURST, self.next_burst, size=CHUNK, now=now))
            self.burst, self.next_burst, self.heard = self.seq, None, now
            return out, None
        if self.burst is not None:
            if now - self.heard < max(BURST_QUIET, self.roundtrip.timeout(), BURST_GAPS * self.gap):
                return [], None
            self.sent.pop(self.burst, None)             # its end was lost, or it stalled
            self.burst = None
            if self.end is None and self.bound is None and self.bursts < self.max_bursts and self._top():
                # burst on from past the last packet heard; the gaps are read once the file's end is known: read
                # one by one (a few in flight), a burst's gaps at 30 % loss took ten times the burst itself
                self.next_burst = self._top()
                return self.service(now, target)
        missing = self.missing(2 * READ_WINDOW_MAX)
        if not missing and self.end is None and self.bound is None:
            # the tail's packets and the EOF were all lost: burst again from the first byte not read
            self.next_burst = self._top()
            return self.service(now, target)
        if not missing and self.end is not None:
            self.phase = "done"
            return [self._request(target, OP_TERMINATE, now=now)], None
        timeout = max(READ_TIMEOUT_MIN, self.roundtrip.timeout())
        for offset, sent in list(self.asked.items()):
            if now - sent >= timeout:
                del self.asked[offset]
        window = self._read_window()
        for offset in missing:
            if len(self.asked) >= window:
                break
            if offset not in self.asked:
                if self.tries.get(offset, 0) >= READ_TRIES:
                    return out, f"gave up: byte {offset:,} of the file asked {READ_TRIES} times without an answer"
                self.tries[offset] = self.tries.get(offset, 0) + 1
                self.reads_sent += 1
                self.asked[offset] = now
                out.append(self._request(target, OP_READ, offset, size=CHUNK, now=now))
        return out, None

    def _read_window(self) -> int:
        """ReadFiles out at once: READ_WINDOW, more for the share of requests the link loses (the reads answered
        are the product of both ways' delivery; half of it each way's), so that as many reach the vehicle's queue
        as on a clean link. One too many is only dropped by a full queue, as the link would have lost it."""
        if self.reads_sent < 20:
            return READ_WINDOW
        each_way = max(0.5, (self.reads_answered / self.reads_sent) ** 0.5)
        return max(READ_WINDOW, min(READ_WINDOW_MAX, round(READ_WINDOW / each_way)))

    def terminate(self, target: tuple[int, int]):
        """TerminateSession: the vehicle closes the file (sent when FTP is given up)."""
        return self._request(target, OP_TERMINATE)

    @property
    def done(self) -> bool:
        return self.phase == "done"

    def data(self) -> bytes | None:
        """The whole file once every chunk to its end is held, else None."""
        if self.end is None:
            return None
        data = b"".join(self.chunks[o] for o in sorted(self.chunks) if o < self.end)
        return data if len(data) == self.end else None


@dataclass
class FtpSpanRead(FtpRead):
    """A read whose bytes are not kept here (a log of hundreds of MB): each new chunk is left in ``taken`` for the
    caller to write, and what is held is the caller's ``held`` (driver.logs.ranges.Ranges: sorted spans, found by
    binary search), so a resumed read loads nothing and a tick looks only at the first gaps."""
    held: object = None
    taken: tuple | None = None           # (offset, data) of the chunk the last reply brought, if new

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.held is not None:        # a resumed read's first burst begins at the first chunk not held
            first = self.missing(1)
            self.next_burst = first[0] if first else self._top()

    @property
    def received(self) -> int:
        return self.held.total()

    def _held(self, offset: int) -> bool:
        upto = offset + CHUNK if self.end is None else min(offset + CHUNK, self.end)
        return self.held.held_from(offset) >= upto > offset

    def _keep(self, offset: int, data: bytes) -> None:
        self.held.add(offset, offset + len(data))
        self.taken = (offset, data)

    def _top(self) -> int:
        return -(-self.held.spans[-1][1] // CHUNK) * CHUNK if self.held.spans else 0

    def _whole_to(self, bound: int) -> bool:
        return bound == 0 or self.held.held_from(bound - 1) >= bound

    def missing(self, most: int | None = None) -> list[int]:
        out: list[int] = []
        for a, b in self.held.missing(self._known_top()):
            for offset in range(a // CHUNK * CHUNK, b, CHUNK):
                if not out or out[-1] != offset:
                    out.append(offset)
                if most is not None and len(out) >= most:
                    return out
        return out


@dataclass
class FtpList:
    """ListDirectory of the first of ``folders`` the vehicle has (GCS_FTP ftp_list_dir): ``files`` {name: size} of
    ``folder``. A folder it has not: NAK FailErrno (opendir failed), the next is tried. Entries come a packet at a
    time from entry ``offset`` on, each ``F<name>\\t<size>`` or ``D<name>`` ended by NUL; NAK EOF after the last.
    One request at a time, asked again after :data:`LIST_RETRY` without its answer (same seq: the vehicle sends its
    last reply again)."""
    started: float
    folders: tuple = ()
    session: int = 0
    stall: float = STALL_SECONDS
    seq: int = 0
    files: dict = field(default_factory=dict)
    folder: bytes = b""
    tried: int = 0                       # index of the folder asked
    entry: int = 0                       # the next entry to ask for
    sent: float = -1.0                   # when the request out was sent (-1: send the next now)
    wait: float = 0.0                    # another session has a file open: ask again after this
    progress: float = 0.0
    phase: str = "list"

    def __post_init__(self) -> None:
        self.progress = self.started

    def _ask(self, target: tuple[int, int], now: float, again: bool):
        if not again:
            self.seq = (self.seq + 1) & 0xFFFF
        self.sent = now
        path = self.folders[self.tried]
        return _frame(target, self.seq, self.session, OP_LIST, len(path), self.entry, path)

    def terminate(self, target: tuple[int, int]):
        self.seq = (self.seq + 1) & 0xFFFF
        return _frame(target, self.seq, self.session, OP_TERMINATE, 0, 0)

    def service(self, now: float, target: tuple[int, int]) -> tuple[list, str | None]:
        if self.phase == "done":
            return [], None
        if now - self.progress >= self.stall:
            return [], f"got no answer to the listing of {self.folders[self.tried].decode()} in {self.stall:g} s"
        if self.sent < 0:
            return ([self._ask(target, now, False)] if now >= self.wait else []), None
        if now - self.sent >= LIST_RETRY:
            return [self._ask(target, now, True)], None
        return [], None

    def on_message(self, m, now: float) -> str | None:
        payload = bytes(m.payload)
        seq, session, opcode, size, req_opcode, _, _, _ = HEADER.unpack(payload[:12])
        if req_opcode != OP_LIST or session != self.session or seq != (self.seq + 1) & 0xFFFF or self.sent < 0 \
                or self.phase == "done":
            return None                                 # not the answer to the request out
        data = payload[12:12 + size]
        self.seq, self.sent = seq, -1.0
        if opcode == OP_ACK:
            self.progress = now
            for raw in data.split(b"\0"):
                if not raw:
                    continue
                self.entry += 1
                if raw[:1] == b"F" and b"\t" in raw:
                    name, _, length = raw[1:].partition(b"\t")
                    self.files[name.decode(errors="replace")] = int(length or 0)
            return None
        error = data[0] if data else 0
        if error == ERR_INVALID_SESSION:                # the parameters' file is read: after it (stall bounds it)
            self.wait = now + LIST_RETRY
            return None
        self.progress = now
        if error == ERR_EOF:
            self.phase, self.folder = "done", self.folders[self.tried]
            return None
        if self.tried + 1 < len(self.folders):
            self.tried, self.entry, self.files = self.tried + 1, 0, {}
            return None
        return "found no folder: " + ", ".join(f.decode() for f in self.folders) + \
            f" (the vehicle said {NAK_TEXT.get(error, error)})"

    @property
    def done(self) -> bool:
        return self.phase == "done"
