"""The simulator's log serving, message for message as ArduCopter 4.6.3 in
tests/data/recordings/arducopter-4.6-sitl-logs.events.txt (its README lists the facts checked here)."""
from __future__ import annotations

import struct

from driver.sim.dataflash import LogFolder, write_flight_log
from driver.sim.ftp import HEADER
from driver.sim.gcs import OtherGroundStation


def station(sim_factory, tmp_path, sizes):
    folder = LogFolder(str(tmp_path / "logs"))
    for size in sizes:
        write_flight_log(folder, size)
    sim = sim_factory(log_dir=folder.folder)
    return OtherGroundStation(f"tcp:127.0.0.1:{sim.tcp_port}"), folder


def quiet_after(gcs, kind: str, since: int, quiet: float = 0.5) -> list:
    """Every ``kind`` heard from ``since`` until none came for ``quiet`` s."""
    while gcs.wait(kind, quiet, since=len(gcs.messages)) is not None:
        pass
    return [m for m in gcs.messages[since:] if m.get_type() == kind]


def test_log_requests_as_the_recording(sim_factory, tmp_path):
    gcs, folder = station(sim_factory, tmp_path, [20_000])
    size = folder.entries()[0][1]
    with gcs:
        mark = gcs.mark()
        gcs.send(gcs.mav.log_request_list_encode(1, 1, 0, 0xFFFF))
        entries = quiet_after(gcs, "LOG_ENTRY", mark)
        assert [(e.id, e.num_logs, e.last_log_num, e.size) for e in entries] == [(1, 1, 1, size)]
        # ids past the last log: a flood of size-0 entries counting up, stopped by LOG_REQUEST_END; a
        # LOG_REQUEST_DATA meanwhile is dropped
        mark = gcs.mark()
        gcs.send(gcs.mav.log_request_list_encode(1, 1, 100, 200))
        first = gcs.wait("LOG_ENTRY", 5, since=mark)
        assert (first.id, first.size, first.time_utc, first.last_log_num) == (100, 0, 0, 1)
        gcs.send(gcs.mav.log_request_data_encode(1, 1, 1, 0, 900))
        assert gcs.wait(lambda m: m.get_type() == "LOG_ENTRY" and m.id > 300, 10, since=mark)
        gcs.send(gcs.mav.log_request_end_encode(1, 1))
        flood = quiet_after(gcs, "LOG_ENTRY", mark)
        assert flood[-1].id > 300 and all(e.size == 0 for e in flood)
        assert not [m for m in gcs.messages[mark:] if m.get_type() == "LOG_DATA"]
        # windows: N packets then silence; one crossing the end ends short; past the end: one of count 0
        for ofs, count, expect in ((0, 900, [(o, 90) for o in range(0, 900, 90)]),
                                   (12345, 270, [(12345, 90), (12435, 90), (12525, 90)]),
                                   (size - 100, 360, [(size - 100, 90), (size - 10, 10)]),
                                   (size + 1000, 180, [(size + 1000, 0)])):
            mark = gcs.mark()
            gcs.send(gcs.mav.log_request_data_encode(1, 1, 1, ofs, count))
            got = quiet_after(gcs, "LOG_DATA", mark)
            assert [(m.ofs, m.count) for m in got] == expect
        mark = gcs.mark()
        gcs.send(gcs.mav.log_request_data_encode(1, 1, 99, 0, 900))     # no such log: nothing at all
        assert quiet_after(gcs, "LOG_DATA", mark) == []


def test_a_list_of_one_log_ends_within_its_request(sim_factory, tmp_path):
    """handle_log_request_list sends the first LOG_ENTRY at once (handle_log_send_listing): with one log the listing
    is over before the next message is read, so a second LOG_REQUEST_LIST right behind it is answered too (a listing
    of more logs runs on, and a second LIST meets "Log download in progress" as during a transfer, below)."""
    gcs, folder = station(sim_factory, tmp_path, [20_000])
    with gcs:
        mark = gcs.mark()
        gcs.send(gcs.mav.log_request_list_encode(1, 1, 0, 0xFFFF))
        gcs.send(gcs.mav.log_request_list_encode(1, 1, 0, 0xFFFF))
        assert [e.id for e in quiet_after(gcs, "LOG_ENTRY", mark)] == [1, 1]
        assert not [m for m in gcs.messages[mark:] if m.get_type() == "STATUSTEXT" and "in progress" in m.text]


def test_log_folder_over_ftp_as_the_recording(sim_factory, tmp_path):
    gcs, folder = station(sim_factory, tmp_path, [3_000, 5_000])
    seq = [0]

    def ftp(opcode, path=b"", offset=0, size=None):
        seq[0] += 1
        payload = HEADER.pack(seq[0], 0, opcode, len(path) if size is None else size, 0, 0, 0, offset) + path
        mark = gcs.mark()
        gcs.send(gcs.mav.file_transfer_protocol_encode(0, 1, 1, list(payload.ljust(251, b"\0"))))
        reply = bytes(gcs.wait("FILE_TRANSFER_PROTOCOL", 5, since=mark).payload)
        header = HEADER.unpack(reply[:12])
        return header[2], reply[12:12 + header[3]]

    with gcs:
        op, data = ftp(3, b"logs")
        names = [e for e in data.split(b"\0") if e]
        assert op == 128 and b"D." in names and b"D.." in names
        sizes = {n: s for n, s, _ in folder.entries()}
        assert f"F00000002.BIN\t{sizes[2]}".encode() in names and f"F00000001.BIN\t{sizes[1]}".encode() in names
        assert ftp(3, b"logs", len(names)) == (129, bytes([6]))           # EOF past the last entry
        assert ftp(3, b"/APM/LOGS") == (129, bytes([10]))
        assert ftp(3, b"") == (129, bytes([3]))
        op, data = ftp(4, b"logs/00000002.BIN")
        assert op == 128 and struct.unpack("<I", data)[0] == sizes[2]


def test_the_solo_answers_no_ftp(sim_factory, tmp_path):
    sim = sim_factory(profile="solo", log_dir=str(tmp_path))
    with OtherGroundStation(f"tcp:127.0.0.1:{sim.tcp_port}", mavlink1=True) as gcs:
        mark = gcs.mark()
        reset = HEADER.pack(1, 0, 2, 0, 0, 0, 0, 0).ljust(251, b"\0")
        gcs.send(gcs.mav.file_transfer_protocol_encode(0, 1, 1, list(reset)))
        assert gcs.wait("FILE_TRANSFER_PROTOCOL", 1.5, since=mark) is None
        assert gcs.wait("HEARTBEAT", 5, since=mark) is not None


def test_a_request_during_a_transfer_is_dropped(sim_factory, tmp_path):
    """AP_Logger_MAVLinkLogTransfer: while LOG_DATA streams, a new LOG_REQUEST_DATA on that link is dropped
    silently and a LOG_REQUEST_LIST with "Log download in progress"; LOG_REQUEST_END frees it."""
    folder = LogFolder(str(tmp_path / "logs"))
    write_flight_log(folder, 20_000)
    sim = sim_factory(log_dir=folder.folder, radio_baud=200_000)          # ~180 LOG_DATA a second
    with OtherGroundStation(f"tcp:127.0.0.1:{sim.tcp_port}") as gcs:
        mark = gcs.mark()
        gcs.send(gcs.mav.log_request_data_encode(1, 1, 1, 0, 0xFFFFFFFF))
        assert gcs.wait("LOG_DATA", 5, since=mark)
        gcs.send(gcs.mav.log_request_data_encode(1, 1, 1, 18_001, 90))
        gcs.send(gcs.mav.log_request_list_encode(1, 1, 0, 0xFFFF))
        assert gcs.wait(lambda m: m.get_type() == "STATUSTEXT" and m.text == "Log download in progress", 5,
                        since=mark)
        gcs.send(gcs.mav.log_request_end_encode(1, 1))
        data = quiet_after(gcs, "LOG_DATA", mark)
        offsets = [m.ofs for m in data]
        bad = [(i, offsets[i - 2:i + 3]) for i in range(1, len(offsets)) if offsets[i] < offsets[i - 1]]
        assert not bad and 18_001 not in offsets      # one stream in order, the window dropped
        assert not [m for m in gcs.messages[mark:] if m.get_type() == "LOG_ENTRY"]


def test_small_requests_streamed_back_to_back_are_all_served(sim_factory, tmp_path):
    """handle_log_request_data serves a request at once, up to num_sends packets (SITL: 40), and one that ends
    there ends the transfer: the next request of the same batch is served too (MAVProxy streams its gap
    requests so). Asking for more than one call sends leaves a transfer running: what comes then is dropped."""
    folder = LogFolder(str(tmp_path / "logs"))
    write_flight_log(folder, 200_000)
    sim = sim_factory(log_dir=folder.folder)
    windows = [(ofs, 90 * n) for ofs, n in ((1000, 1), (5000, 3), (9001, 40), (60_000, 2), (90_000, 1),
                                             (120_000, 5), (150_000, 1), (170_000, 7))]
    with OtherGroundStation(f"tcp:127.0.0.1:{sim.tcp_port}") as gcs:
        mark = gcs.mark()
        for ofs, count in windows:
            gcs.send(gcs.mav.log_request_data_encode(1, 1, 1, ofs, count))
        got = quiet_after(gcs, "LOG_DATA", mark)
        assert sorted((m.ofs, m.count) for m in got) == [(ofs + i, 90) for ofs, count in windows
                                                         for i in range(0, count, 90)]


def test_the_solo_moves_its_transfer_to_a_new_request(sim_factory, tmp_path):
    """3.3 (ardupilot-solo GCS_Logs.cpp) has no "download in progress" check: a LOG_REQUEST_DATA for the log being
    sent sets the transfer's offset and count, so a stream ends where the new window does."""
    folder = LogFolder(str(tmp_path / "logs"))
    write_flight_log(folder, 60_000)
    sim = sim_factory(log_dir=folder.folder, profile="solo", radio_baud=200_000)
    with OtherGroundStation(f"tcp:127.0.0.1:{sim.tcp_port}", mavlink1=True) as gcs:
        mark = gcs.mark()
        gcs.send(gcs.mav.log_request_data_encode(1, 1, 1, 0, 0xFFFFFFFF))
        assert gcs.wait("LOG_DATA", 5, since=mark)
        gcs.send(gcs.mav.log_request_data_encode(1, 1, 1, 50_001, 180))
        got = quiet_after(gcs, "LOG_DATA", mark)
        assert [(m.ofs, m.count) for m in got[-2:]] == [(50_001, 90), (50_091, 90)]
        assert max(m.ofs for m in got if m.ofs < 50_001) < 20_000       # the stream stopped for it
