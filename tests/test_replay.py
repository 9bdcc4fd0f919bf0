"""The replay vehicle itself (driver/sim/replay.py): what it takes as the same request, which recorded answers
belong to which request, and that over a real socket it sends the recorded answers, in order, to this request,
and nothing else (a bare pymavlink ground station, test_sim.GroundStation, is the client).
"""
from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.sim.replay import FTP_HEADER, Recording, request_key
from test_sim import GroundStation, wait_until

from recordings import FLIGHT, FTP_PARAMS, GIMBAL, MISSION, PARAMS  # noqa: E402

codec = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)


def ftp(seq: int, session: int, opcode: int, size: int = 0, offset: int = 0, data: bytes = b""):
    payload = FTP_HEADER.pack(seq, session, opcode, size or len(data), 0, 0, 0, offset) + data
    return codec.file_transfer_protocol_encode(0, 1, 1, list(payload.ljust(251, b"\0")))


def ftp_header(m) -> tuple:
    return FTP_HEADER.unpack(bytes(m.payload)[:12])


def test_the_key_keeps_what_a_request_means_and_drops_what_changes_between_tries():
    # the sender's guess of the type, the target ids and the retry counter mean nothing to ArduPilot
    assert request_key(codec.param_set_encode(1, 1, b"FS_GCS_ENABLE", 1.0, mavlink.MAV_PARAM_TYPE_INT8)) == \
        request_key(codec.param_set_encode(0, 0, b"FS_GCS_ENABLE", 1.0, mavlink.MAV_PARAM_TYPE_REAL32))
    assert request_key(codec.param_set_encode(1, 1, b"FS_GCS_ENABLE", 1.0, 2)) != \
        request_key(codec.param_set_encode(1, 1, b"FS_GCS_ENABLE", 0.0, 2))
    assert request_key(codec.command_long_encode(1, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0)) == \
        request_key(codec.command_long_encode(1, 1, 400, 2, 1, 0, 0, 0, 0, 0, 0))
    # a read by index is not a read by name; a float parameter is compared as the wire's float32
    assert request_key(codec.param_request_read_encode(1, 1, b"", 5)) == ("PARAM_REQUEST_READ", 5)
    assert request_key(codec.param_request_read_encode(1, 1, b"RTL_ALT", -1)) == ("PARAM_REQUEST_READ", "RTL_ALT")
    assert request_key(codec.command_long_encode(1, 1, 195, 0, 0, 0, 0, 0, -35.36306, 149.16524, 0)) == \
        request_key(codec.command_long_encode(1, 1, 195, 0, 0, 0, 0, 0, -35.363059997558594, 149.1652374267578, 0))
    # FTP: not the seq nor the session, but the opcode, offset, size and path
    assert request_key(ftp(3, 0, 4, data=b"@PARAM/param.pck")) == request_key(ftp(90, 2, 4, data=b"@PARAM/param.pck"))
    assert request_key(ftp(3, 0, 15, 239, 0)) != request_key(ftp(3, 0, 15, 16, 0))
    # gimbal angles given: AP_Mount reads no rate, so NaN or 0 there are the same request; rates alone are not
    pitchyaw = mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW
    assert request_key(codec.command_long_encode(1, 1, pitchyaw, 0, -90, 0, math.nan, math.nan, 0, 0, 0)) == \
        request_key(codec.command_long_encode(1, 1, pitchyaw, 0, -90, 0, 0, 0, 0, 0, 0))
    assert request_key(codec.command_long_encode(1, 1, pitchyaw, 0, math.nan, math.nan, 20, 0, 0, 0, 0)) != \
        request_key(codec.command_long_encode(1, 1, pitchyaw, 0, math.nan, math.nan, 0, 0, 0, 0, 0))


def late_acks(recording: Recording) -> list:
    """(command, ACK time) of every COMMAND_ACK that came after the next request went out; each exchange's ACKs
    and mission items checked to answer its own request on the way."""
    late = []
    for n, ex in enumerate(recording.exchanges):
        acks = [m for _, m, _ in ex.answers if m.get_type() == "COMMAND_ACK"]
        assert all(ex.request.get_type() == "COMMAND_LONG" and m.command == ex.request.command for m in acks)
        following = recording.exchanges[n + 1].t if n + 1 < len(recording.exchanges) else math.inf
        late += [(m.command, ex.t + dt) for dt, m, _ in ex.answers
                 if m.get_type() == "COMMAND_ACK" and ex.t + dt > following]
        items = [m for _, m, _ in ex.answers if m.get_type() == "MISSION_ITEM_INT"]
        assert all(ex.request.get_type() == "MISSION_REQUEST_INT" and m.seq == ex.request.seq for m in items)
    return late


def test_every_answer_stays_with_the_request_it_answers():
    mission = Recording.load(MISSION + ".tlog")
    assert late_acks(mission) == []
    assert sum(1 for ex in mission.exchanges for _, m, _ in ex.answers if m.get_type() == "COMMAND_ACK") == 10
    # 2.03 s into the flight recording: REQUEST_MESSAGE's ACK came after the next command went out; it stays
    # with the REQUEST_MESSAGE (and so in the gimbal recording GET_HOME_POSITION's, after DO_SET_ROI_LOCATION)
    assert [command for command, _ in late_acks(Recording.load(FLIGHT + ".tlog"))] == \
        [mavlink.MAV_CMD_REQUEST_MESSAGE]
    assert [command for command, _ in late_acks(Recording.load(GIMBAL + ".tlog"))] == \
        [mavlink.MAV_CMD_GET_HOME_POSITION]
    # the FTP burst: 65 data packets and the NAK EOF, all with the burst (the banner texts came meanwhile)
    burst = next(ex for ex in Recording.load(FTP_PARAMS + ".tlog").exchanges
                 if ex.key == ("FILE_TRANSFER_PROTOCOL", 15, 0, 239, b""))
    replies = [ftp_header(m) for _, m, _ in burst.answers if m.get_type() == "FILE_TRANSFER_PROTOCOL"]
    assert [r[2] for r in replies] == [128] * 65 + [129]
    assert [r[0] for r in replies] == [ftp_header(burst.request)[0] + 1 + i for i in range(66)]


def test_over_tcp_the_recorded_answers_in_order_and_nothing_else(replay_factory):
    # from 3 s on: the boot's texts and parameters before the first request (telemetry) would mix in
    replay = replay_factory(PARAMS, speedup=50, telemetry_from=3.0)
    recording = replay.recording
    gs = GroundStation(replay.tcp_port)
    try:
        assert wait_until(lambda: any(m.get_type() == "HEARTBEAT" for m, _ in gs.frames), 5)
        first, second = (ex for ex in recording.exchanges_of("PARAM_REQUEST_LIST"))
        for ex in (first, second):
            mark = len(gs.frames)
            gs.send(codec.param_request_list_encode(1, 1))
            expected = [m for _, m, _ in ex.answers]
            assert wait_until(lambda: sum(m.get_type() == "PARAM_VALUE" for m, _ in gs.frames[mark:]) >= 1392, 10)
            got = [m for m, _ in gs.frames[mark:] if m.get_type() in ("PARAM_VALUE", "STATUSTEXT")]
            # the same answers, in the recorded order (the second list has the values the sets left)
            assert [m.to_dict() for m in got] == [m.to_dict() for m in expected]
        assert {m.param_id: m.param_value for _, m, _ in second.answers if m.get_type() == "PARAM_VALUE"}[
            "RTL_ALT"] == 1e9
        # each answer was due at its recorded delay after the request, at 50 times the pace (0.7 s in 14 ms)
        for ex, asked in zip((first, second), replay.requests):
            assert asked.schedule == tuple(dt / 50 for dt, _, _ in ex.answers)
        # asked a third time, or for a name never asked: nothing, and the replay says so
        gs.send(codec.param_request_list_encode(1, 1))
        gs.send(codec.param_request_read_encode(1, 1, b"NOPE_XYZ", -1))
        assert wait_until(lambda: len(replay.unanswered) == 2, 5)
        assert [(r.type, r.why) for r in replay.unanswered] == [
            ("PARAM_REQUEST_LIST", "its 2 recorded answer(s) are used up"), ("PARAM_REQUEST_READ", "not in the recording")]
        # telemetry goes on past the recording's end (15 s, 0.3 s here): a looped timeline
        recorded = sum(m.get_type() == "HEARTBEAT" for _, m, _ in recording.telemetry)
        assert wait_until(lambda: sum(m.get_type() == "HEARTBEAT" for m, _ in gs.frames) > 2 * recorded, 10)
        assert gs.bad == 0
    finally:
        gs.close()


def test_ftp_replies_answer_this_requests_seq_and_session(replay_factory):
    replay = replay_factory(FTP_PARAMS, speedup=50)
    recorded = next(ex for ex in replay.recording.exchanges if ex.key == ("FILE_TRANSFER_PROTOCOL", 15, 0, 239, b""))
    gs = GroundStation(replay.tcp_port)
    try:
        replies = lambda: [m for m, _ in gs.frames if m.get_type() == "FILE_TRANSFER_PROTOCOL"]  # noqa: E731
        gs.send(ftp(1000, 7, 4, data=b"@PARAM/param.pck"))          # OpenFileRO
        assert wait_until(lambda: len(replies()) == 1, 5)
        gs.send(ftp(65530, 7, 15, 239, 0))                          # BurstReadFile: its seq wraps at 65535
        assert wait_until(lambda: len(replies()) == 67, 5), len(replies())
        opened, *burst = [ftp_header(m) for m in replies()]
        assert opened[:3] == (1001, 7, 128) and opened[4] == 4       # seq + 1, our session, ACK of OpenFileRO
        assert [h[0] for h in burst] == [(65531 + i) & 0xFFFF for i in range(66)]
        assert {h[1] for h in burst} == {7}
        # beyond seq and session, the bytes the vehicle sent
        sent = [bytes(m.payload)[3:] for _, m, _ in recorded.answers if m.get_type() == "FILE_TRANSFER_PROTOCOL"]
        assert [bytes(m.payload)[3:] for m in replies()[1:]] == sent
        assert replay.unanswered == []
    finally:
        gs.close()
