"""Parameters over MAVLink FTP (@PARAM/param.pck) as ArduCopter 4.6.3 serves them: the simulator answers message for
message as the recording does (tests/data/recordings/arducopter-4.6-sitl-ftp-params.*), and the driver reads the
file to its real end (the open's size is only an estimate), fills what the radio lost, and falls back to the list
when FTP stalls, telling the pilot why."""
from __future__ import annotations

import os
import struct
from types import SimpleNamespace

import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink
from pymavlink.mavftp import MAVFTP

from driver.sim import ftp as simftp

from ice_fixtures import eventually

RECORDING = os.path.join(os.path.dirname(__file__), "data", "recordings", "arducopter-4.6-sitl-ftp-params.tlog")


def _recorded_ftp() -> list[tuple]:
    """Every FILE_TRANSFER_PROTOCOL of the recording: (time, from the GCS, header fields..., data)."""
    log = mavutil.mavlink_connection(RECORDING)
    out = []
    while True:
        m = log.recv_match(type="FILE_TRANSFER_PROTOCOL")
        if m is None:
            return out
        payload = bytes(m.payload)
        seq, session, opcode, size, req_opcode, burst_complete, _, offset = simftp.HEADER.unpack(payload[:12])
        out.append((m._timestamp, m.get_srcSystem() == 255, seq, session, opcode, size, req_opcode, burst_complete,
                    offset, payload[12:12 + size], m))


def _recorded_files(records) -> dict[int, bytes]:
    """The files the recording read in bursts, by session."""
    chunks: dict[int, dict[int, bytes]] = {}
    for _, gcs, _, session, opcode, _, req_opcode, _, offset, data, _ in records:
        if not gcs and opcode == simftp.OP_ACK and req_opcode == simftp.OP_BURST:
            chunks.setdefault(session, {})[offset] = data
    return {s: b"".join(c[o] for o in sorted(c)) for s, c in chunks.items()}


def _with_defaults_flags(data: bytes) -> set[str]:
    """Names whose record carries a default (flag bit 4 of the type byte) in a param.pck with defaults."""
    names, last, data = set(), b"", data[6:]
    while data:
        if data[0] == 0:
            data = data[1:]
            continue
        ptype, lengths = data[0], data[1]
        name_len = (lengths >> 4) + 1
        name = last[:lengths & 15] + data[2:2 + name_len]
        value_len = {1: 1, 2: 2, 3: 4, 4: 4}[ptype & 15] * (2 if ptype & 0x10 else 1)
        if ptype & 0x10:
            names.add(name.decode())
        last, data = name, data[2 + name_len + value_len:]
    return names


@pytest.fixture(scope="module")
def recorded():
    records = _recorded_ftp()
    files = _recorded_files(records)
    plain = MAVFTP.ftp_param_decode(files[0])
    defaults_file = files[2]
    decoded = MAVFTP.ftp_param_decode(defaults_file)
    flagged = _with_defaults_flags(defaults_file)
    defaults = {n.decode(): v for n, v, _ in decoded.defaults}
    entries = [(n.decode(), t, v, defaults[n.decode()] if n.decode() in flagged else None) for n, v, t in plain.params]
    return SimpleNamespace(records=records, files=files, entries=entries)


class _Vehicle(simftp.FtpServer):
    """The simulator's FTP worker alone, serving the recorded vehicle's parameters; its replies are collected."""

    def __init__(self, entries) -> None:
        self.entries = entries
        self.config = SimpleNamespace(system_id=1)
        self.factory = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        self.sender = "gcs"
        self.t = 0.0
        self.sent: list = []
        self.banners = 0

    def ftp_entries(self):
        return self.entries

    def emit_to(self, msg, peer) -> None:
        self.sent.append(msg)

    def _banner(self) -> None:
        self.banners += 1


def _shape(header: tuple, data: bytes) -> tuple:
    """What a reply says: seq, session, opcode, size, req_opcode, burst_complete, offset, and a NAK's codes."""
    seq, session, opcode, size, req_opcode, burst_complete, offset = header
    return (seq, session, opcode, size, req_opcode, burst_complete, offset,
            tuple(data) if opcode == simftp.OP_NAK else None)


def test_the_simulated_param_file_is_byte_for_byte_the_recorded_one(recorded):
    """Same parameters, same packet size: the same bytes, pad bytes included (15,311 in 239-byte packets, 15,632 in
    16-byte ones, 15,488 with defaults)."""
    files = recorded.files
    assert (len(files[0]), len(files[1]), len(files[2])) == (15311, 15632, 15488)
    assert simftp.pack(recorded.entries, 239) == files[0] == files[3]
    assert simftp.pack(recorded.entries, 16) == files[1]
    assert simftp.pack(recorded.entries, 239, with_defaults=True) == files[2]


def test_the_simulator_answers_the_recorded_requests_as_the_vehicle_did(recorded):
    """Every request the GCS sent in the recording, fed to the simulator's FTP worker: the answers have the recorded
    opcodes, sizes, offsets, seqs, sessions, burst_complete and NAK codes, packet for packet."""
    vehicle = _Vehicle(recorded.entries)
    records = recorded.records
    start = records[0][0]
    mine, theirs = [], []
    for i, (t, gcs, *_rest, msg) in enumerate(records):
        if not gcs:
            continue
        vehicle.t = t - start
        vehicle.sender = "gcs"
        msg.target_system = 1
        vehicle._on_file_transfer_protocol(msg)
        while vehicle.ftp_busy:
            vehicle.ftp_packet(paced=False)
        for m in vehicle.sent:
            header = simftp.HEADER.unpack(bytes(m.payload)[:12])
            mine.append(_shape(header[:6] + header[7:], bytes(m.payload)[12:12 + header[3]]))
        vehicle.sent.clear()
        for r in records[i + 1:]:
            if r[1]:
                break
            theirs.append(_shape(r[2:9], r[9]))
    assert len(theirs) == sum(1 for r in records if not r[1]) == 1200     # every recorded reply, in order
    assert mine == theirs
    assert vehicle.banners == 4                      # each open of param.pck (not the refused ones) sent the banner


# -- the driver against the simulated vehicle -------------------------------------------------------------------
def _requests(sim) -> list[tuple[int, int, int]]:
    """Record the FTP requests the vehicle gets: (opcode, size, offset)."""
    seen: list[tuple[int, int, int]] = []
    autopilot = sim.autopilot
    take = autopilot._on_file_transfer_protocol

    def recording(msg):
        _, _, opcode, size, _, _, _, offset = simftp.HEADER.unpack(bytes(msg.payload)[:12])
        seen.append((opcode, size, offset))
        take(msg)
    autopilot._on_file_transfer_protocol = recording
    return seen


def _lose_replies(sim, lost) -> list:
    """The vehicle's FTP replies for which ``lost(reply)`` says so never reach the link."""
    autopilot = sim.autopilot
    send = autopilot._ftp_send
    dropped = []

    def sending(reply):
        if lost(reply):
            dropped.append((reply.opcode, reply.offset, len(reply.data)))
            autopilot.ftp_last, autopilot.ftp_last_send = reply, autopilot.t
            return
        send(reply)
    autopilot._ftp_send = sending
    return dropped


def _ftp_vehicle(sim, vehicle_factory):
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.connected and s.firmware, 10)     # AUTOPILOT_VERSION offers FTP
    return vehicle


def _holds_entries(table, entries) -> None:
    assert table.complete and table.expected == len(entries)
    for index, (name, _, value, _) in enumerate(entries):
        p = table.get(name)
        assert p is not None and p.index == index, name
        if not name.startswith("SR0_"):
            assert abs(p.value - value) <= 1e-6 * max(1.0, abs(value)), (name, p.value, value)


def test_the_file_is_read_to_its_real_end_not_to_the_opens_estimate(sim, vehicle_factory):
    """The open says 12 bytes a parameter (16,704 for 1,392); the file is smaller: one burst to its end, the short
    last packet and the NAK EOF end it, nothing is asked past it, and every parameter is the vehicle's."""
    requests = _requests(sim)
    vehicle = _ftp_vehicle(sim, vehicle_factory)
    result = vehicle.fetch_parameters(refresh=True).result(timeout=30)
    assert result.ok and "over MAVLink FTP" in result.reason, result
    size = len(simftp.pack(simftp.sim_entries(sim.autopilot.params), simftp.CHUNK))
    assert size < 12 * 1392 and f"({size:,} bytes" in result.reason, (size, result.reason)
    assert eventually(lambda: len(requests) >= 3, 5)              # TerminateSession goes after the answer
    assert [op for op, _, _ in requests] == [simftp.OP_OPEN_RO, simftp.OP_BURST, simftp.OP_TERMINATE], requests
    assert requests[1][1:] == (simftp.CHUNK, 0)
    _holds_entries(vehicle.state().parameters, simftp.sim_entries(sim.autopilot.params))


def test_a_file_that_is_a_multiple_of_the_packet_ends_by_the_eof_nak(sim, vehicle_factory):
    """No short packet: the NAK EOF (its offset the last full packet's) alone says where the file ends."""
    entries = simftp.sim_entries(sim.autopilot.params)
    while len(simftp.pack(entries, simftp.CHUNK)) % simftp.CHUNK:
        entries = entries[:-1]
    sim.autopilot.ftp_entries = lambda: entries
    naks = []
    _lose_replies(sim, lambda r: r.opcode == simftp.OP_NAK and naks.append(r.offset) and False)
    requests = _requests(sim)
    vehicle = _ftp_vehicle(sim, vehicle_factory)
    result = vehicle.fetch_parameters(refresh=True).result(timeout=30)
    assert result.ok and "over MAVLink FTP" in result.reason, result
    size = len(simftp.pack(entries, simftp.CHUNK))
    assert naks == [size - simftp.CHUNK]                         # the recorded rule: the last full packet's offset
    assert eventually(lambda: len(requests) >= 3, 5)              # TerminateSession goes after the answer
    assert [op for op, _, _ in requests] == [simftp.OP_OPEN_RO, simftp.OP_BURST, simftp.OP_TERMINATE], requests
    _holds_entries(vehicle.state().parameters, entries)


def test_chunks_the_radio_lost_are_read_again_in_the_bursts_packet_size(sim, vehicle_factory):
    """Two packets lost mid-burst, then the short last one and the EOF: the gaps are read with ReadFile of the
    burst's packet size, the tail asked for again, and the table is complete."""
    size = len(simftp.pack(simftp.sim_entries(sim.autopilot.params), simftp.CHUNK))
    last = size - size % simftp.CHUNK
    first_time = {3 * simftp.CHUNK, 40 * simftp.CHUNK, last, size}

    def lost(reply):
        if reply.req_opcode == simftp.OP_BURST and reply.offset in first_time:
            first_time.discard(reply.offset)
            return True
        return False
    dropped = _lose_replies(sim, lost)
    requests = _requests(sim)
    vehicle = _ftp_vehicle(sim, vehicle_factory)
    result = vehicle.fetch_parameters(refresh=True).result(timeout=30)
    assert result.ok and "over MAVLink FTP" in result.reason, result
    assert len(dropped) == 4 and not first_time
    reads = {(size_, offset) for op, size_, offset in requests if op == simftp.OP_READ}
    assert {(simftp.CHUNK, 3 * simftp.CHUNK), (simftp.CHUNK, 40 * simftp.CHUNK)} <= reads, requests
    assert all(s == simftp.CHUNK and o <= size for s, o in reads), requests
    _holds_entries(vehicle.state().parameters, simftp.sim_entries(sim.autopilot.params))


def _fall_back(sim, vehicle_factory) -> tuple:
    vehicle = _ftp_vehicle(sim, vehicle_factory)
    seen: list[str] = []
    future = vehicle.fetch_parameters(refresh=True)
    while not future.done() and len(seen) < 500:
        s = vehicle.wait_for(lambda s: s.parameters.detail not in seen[-1:], 1)
        if s is not None:
            seen.append(s.parameters.detail)
    return vehicle, future.result(timeout=60), seen


def test_a_stalled_ftp_read_falls_back_to_the_list_and_the_pilot_is_told_why(sim, vehicle_factory):
    """The vehicle goes silent on FTP after ten packets: after STALL_SECONDS without a new byte the list is read,
    and the progress, the result and the messages say why."""
    from driver.params.ftp import STALL_SECONDS
    sent = []
    _lose_replies(sim, lambda r: sent.append(r) or len(sent) > 10)
    vehicle, result, seen = _fall_back(sim, vehicle_factory)
    assert result.ok and "over MAVLink FTP" not in result.reason, result
    note = f"MAVLink FTP stalled at byte {9 * simftp.CHUNK:,}"
    assert note in result.reason and "read the list instead" in result.reason, result.reason
    assert f"nothing new for {STALL_SECONDS:g} s" in result.reason
    assert any(note in d and "reading the list instead" in d for d in seen), seen
    assert any(note in m.text for m in vehicle.state().messages)
    _holds_entries(vehicle.state().parameters, simftp.sim_entries(sim.autopilot.params))


def test_a_refused_ftp_read_falls_back_to_the_list_at_once(sim, vehicle_factory, monkeypatch):
    """A NAK other than EOF (here the vehicle's errno answer to a read) gives FTP up: the list is read."""
    monkeypatch.setattr(simftp._OpenFile, "read", lambda self, offset, count: None)
    requests = _requests(sim)
    vehicle, result, seen = _fall_back(sim, vehicle_factory)
    assert eventually(lambda: any(op == simftp.OP_TERMINATE for op, _, _ in requests), 5), requests
    assert result.ok and "over MAVLink FTP" not in result.reason, result
    assert "MAVLink FTP was refused: the vehicle said failed (errno) to a read at byte 0" in result.reason, result
    assert any("was refused" in d and "reading the list instead" in d for d in seen), seen
    _holds_entries(vehicle.state().parameters, simftp.sim_entries(sim.autopilot.params))


def test_a_file_left_open_by_an_earlier_session_is_reset_and_read(sim, vehicle_factory):
    """The vehicle still has param.pck open in our session (a fetch given up before its TerminateSession got
    through): the open gets NAK 1, ResetSessions closes it, the next open reads the file over FTP."""
    vehicle = _ftp_vehicle(sim, vehicle_factory)
    autopilot = sim.autopilot
    autopilot.ftp_file = simftp._OpenFile(autopilot.ftp_entries(), False)
    autopilot.ftp_session, autopilot.ftp_last_send = 0, autopilot.t + 60.0       # open, and not idle
    requests = _requests(sim)
    result = vehicle.fetch_parameters(refresh=True).result(timeout=30)
    assert result.ok and "over MAVLink FTP" in result.reason, result
    ops = [op for op, _, _ in requests]
    assert ops[:4] == [simftp.OP_OPEN_RO, simftp.OP_RESET, simftp.OP_OPEN_RO, simftp.OP_BURST], requests


def test_the_consoles_param_fetch_reads_over_ftp(sim, vehicle_factory):
    import io

    from driver.console.console import Console
    vehicle = _ftp_vehicle(sim, vehicle_factory)
    out = io.StringIO()
    Console(vehicle, stdout=out).onecmd("param fetch")
    assert eventually(lambda: "parameters: accepted" in out.getvalue(), 30), out.getvalue()
    assert "over MAVLink FTP" in out.getvalue(), out.getvalue()


def test_a_value_written_while_the_file_is_read_is_not_put_back_by_the_file(sim, vehicle_factory):
    """param.pck holds the values of when it was opened. A set confirmed by its echo while the file is still read
    is newer: the finished file must not put the old value back in the table the pilot sees."""
    holding = [True]
    # the burst's data is held back (lost on the way) until the set is done: the read then fills those gaps
    _lose_replies(sim, lambda r: holding[0] and r.opcode == simftp.OP_ACK and r.req_opcode == simftp.OP_BURST)
    requests = _requests(sim)
    vehicle = _ftp_vehicle(sim, vehicle_factory)
    before = sim.autopilot.params["WPNAV_ACCEL"]
    fetch = vehicle.fetch_parameters(refresh=True)
    assert eventually(lambda: any(op == simftp.OP_BURST for op, _, _ in requests), 5)    # the file is open
    written = vehicle.set_parameter("WPNAV_ACCEL", before + 150).result(timeout=10)
    assert written.ok, written
    holding[0] = False
    result = fetch.result(timeout=30)
    assert result.ok and "over MAVLink FTP" in result.reason, result
    assert sim.autopilot.params["WPNAV_ACCEL"] == before + 150
    assert vehicle.wait_for(lambda s: not s.parameters.downloading, 5)
    p = vehicle.state().parameters.get("WPNAV_ACCEL")
    assert p.value == before + 150 and p.index >= 0, p
