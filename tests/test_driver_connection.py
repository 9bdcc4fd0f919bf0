"""What the driver accepts as a link before it tries to open one, and flight logs of sessions that never
met a vehicle."""
from __future__ import annotations

import os
import struct
import time
import socket

import pytest

from driver.link.connection import connection_problem
from driver.vehicle import Vehicle, VehicleConfig


@pytest.mark.parametrize("text", ["udpin:0.0.0.0:14550", "udpout:192.168.1.10:14550", "tcp:127.0.0.1:5760",
                                  "tcpin:0.0.0.0:5760", "udp:127.0.0.1:14550", "/dev/ttyUSB0",
                                  "/dev/ttyACM0,115200", "COM3"])
def test_connection_strings_that_may_be_links(text):
    assert connection_problem(text) is None


@pytest.mark.parametrize("text,words", [("foo:bar", "not a connection string"), ("bogus", "not a connection"),
                                        ("", "empty"), ("tcp:127.0.0.1", "needs HOST:PORT"),
                                        ("udpin::14550", "needs HOST:PORT"), ("tcp:h:0", "1 to 65535"),
                                        ("udpout:h:port", "1 to 65535"), ("/nope/a.tlog", "no such flight log")])
def test_connection_strings_that_cannot_be(text, words):
    assert words in connection_problem(text)


def test_a_tlog_that_exists_is_a_link(tmp_path):
    path = tmp_path / "f.tlog"
    path.write_bytes(b"")
    assert connection_problem(str(path)) is None


def test_a_session_whose_link_never_opened_leaves_no_empty_log(tmp_path):
    """A radio not plugged in: the link retries, nothing is sent or received, no 0-byte log is left."""
    path = tmp_path / "flight.tlog"
    v = Vehicle(VehicleConfig(connection=str(tmp_path / "ttyUSB-not-plugged"), tlog_path=str(path))).start()
    assert v.wait_for(lambda s: any("cannot open" in m.text for m in s.messages), 5)
    assert path.exists()                                  # opened at start: a bad folder shows at once
    v.close()
    assert not path.exists()


def test_a_session_waiting_for_a_vehicle_logs_what_it_sent(tmp_path):
    path = tmp_path / "flight.tlog"
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as peer:
        peer.bind(("127.0.0.1", 0))
        peer.settimeout(10)
        v = Vehicle(VehicleConfig(connection=f"udpout:127.0.0.1:{peer.getsockname()[1]}",
                                  tlog_path=str(path))).start()
        sent = peer.recv(512)                             # our GCS heartbeat went out...
        v.close()
    assert sent[:1] in (b"\xfe", b"\xfd")
    assert sent in path.read_bytes()                      # ...and is in the log


def test_a_flown_session_keeps_its_log(sim, vehicle_factory, tmp_path):
    path = tmp_path / "kept.tlog"
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", tlog_path=str(path))
    assert v.wait_for(lambda s: s.connected, 10)
    v.close()
    assert os.path.getsize(path) > 0


def test_a_replay_dates_its_messages_when_they_were_recorded(sim, vehicle_factory, tmp_path):
    """Messages of a replayed flight carry the recording's time, not the time it is watched."""
    recorded = tmp_path / "live.tlog"
    live = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", tlog_path=str(recorded))
    assert live.wait_for(lambda s: s.connected, 10)
    assert live.arm().result(timeout=10).ok
    assert live.wait_for(lambda s: s.armed, 10)
    live.close()
    day = 86400.0
    data, out, i = recorded.read_bytes(), bytearray(), 0      # the same flight, one day earlier
    from driver.link.transport import frame_length
    while i + 9 <= len(data):
        n = frame_length(data, i + 8)
        stamp = struct.unpack_from(">Q", data, i)[0] - int(day * 1e6)
        out += struct.pack(">Q", stamp) + data[i + 8:i + 8 + n]
        i += 8 + n
    yesterday = tmp_path / "yesterday.tlog"
    yesterday.write_bytes(bytes(out))
    replay = vehicle_factory(str(yesterday), tlog_path=None, replay_speed=16.0)
    state = replay.wait_for(lambda s: s.armed, 20)              # "Vehicle 1 connected", then armed
    assert state is not None and state.messages
    assert all(abs(m.time - (time.time() - day)) < 600 for m in state.messages), state.messages
