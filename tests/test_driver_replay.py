"""Flight logs: a damaged .tlog still replays, the replay speed stays in its range, and appending keeps the
earlier flight."""
from __future__ import annotations

import random
import struct

import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.vehicle import Vehicle, VehicleConfig

T0 = 1_700_000_000.0                                   # when the handmade logs were "recorded"
ARMED = mavlink.MAV_MODE_FLAG_SAFETY_ARMED | mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
STABILIZE, LAND = 0, 9


class Recorder:
    """Builds .tlog records (8-byte big-endian µs stamp, then the frame) as the vehicle (system 1) sent them."""

    def __init__(self):
        self.mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        self.mav.robust_parsing = True

    def record(self, t: float, msg) -> bytes:
        frame = msg.pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) % 256
        return struct.pack(">Q", int(round(t * 1e6))) + frame

    def heartbeat(self, t: float, mode: int, armed: bool = False) -> bytes:
        return self.record(t, mavlink.MAVLink_heartbeat_message(
            mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
            ARMED if armed else mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, mode, mavlink.MAV_STATE_STANDBY, 3))

    def text(self, t: float, text: str) -> bytes:
        return self.record(t, mavlink.MAVLink_statustext_message(mavlink.MAV_SEVERITY_INFO, text.encode()))


def flight_log(damage: bytes = b"") -> bytes:
    """Disarmed in STABILIZE, the damage, then armed in LAND with five numbered messages."""
    rec = Recorder()
    before = b"".join(rec.heartbeat(T0 + 0.1 * i, STABILIZE) for i in range(5)) + rec.text(T0 + 0.5, "before")
    after = b"".join(rec.heartbeat(T0 + 1.0 + 0.1 * i, LAND, armed=True) + rec.text(T0 + 1.05 + 0.1 * i, f"after {i}")
                     for i in range(5))
    return before + damage + after


def cut_record() -> bytes:
    """A record the recorder could not finish (power lost mid-write): its stamp and 7 bytes of its frame."""
    return Recorder().heartbeat(T0 + 0.6, STABILIZE)[:8 + 7]


DAMAGE = {
    "garbage": bytes(b for b in random.Random(5).randbytes(400) if b not in (0xFE, 0xFD)),
    "a record cut short": cut_record(),
    # erased flash (0xFF), then a byte that starts a MAVLink 1 frame: eight bytes that read as a stamp
    # hundreds of thousands of years from now, in front of something frame-shaped with a bad checksum
    "garbage that looks like a record": b"\xff" * 12 + b"\xfe\x09" + bytes(range(1, 21)),
}


@pytest.mark.parametrize("damage", list(DAMAGE))
def test_a_damaged_log_resynchronises_and_plays_the_later_frames(damage, vehicle_factory, tmp_path):
    path = tmp_path / "damaged.tlog"
    path.write_bytes(flight_log(DAMAGE[damage]))
    replay = vehicle_factory(str(path), tlog_path=None, replay_speed=64)
    s = replay.wait_for(lambda s: any(m.text == "before" for m in s.messages), 10)
    assert s is not None, replay.state().messages
    # the frames after the damage: at most the one record the damage ran into is lost
    later = [f"after {i}" for i in range(1, 5)]
    s = replay.wait_for(lambda s: set(later) <= {m.text for m in s.messages}, 10)
    assert s is not None, ([m.text for m in replay.state().messages], replay.replay.position,
                           replay.replay.duration)
    assert (s.mode, s.armed) == ("LAND", True)
    texts = [m.text for m in s.messages if m.source == "vehicle"]
    assert texts.index("before") < texts.index("after 1") < texts.index("after 4"), texts
    assert replay.wait_for(lambda s: replay.replay.finished, 10)


def test_the_replay_speed_is_kept_from_0_1_to_64(vehicle_factory, tmp_path):
    path = tmp_path / "flight.tlog"
    path.write_bytes(flight_log())
    replay = vehicle_factory(str(path), tlog_path=None, replay_speed=1.0)
    control = replay.replay
    for asked, kept in ((64.0, 64.0), (1000.0, 64.0), (2.5, 2.5), (0.1, 0.1), (0.01, 0.1), (0.0, 0.1),
                        (-8.0, 0.1), (float("inf"), 64.0)):
        control.speed = asked
        assert control.speed == kept, (asked, control.speed)


@pytest.mark.parametrize("asked, kept", [(1000.0, 64.0), (0.01, 0.1)])
def test_the_configured_replay_speed_is_kept_in_the_same_range(asked, kept, tmp_path):
    path = tmp_path / "flight.tlog"
    path.write_bytes(flight_log())
    replay = Vehicle(VehicleConfig(connection=str(path), replay_speed=asked, tlog_path=None))
    try:
        assert replay.replay.speed == kept
    finally:
        replay.close()


def read_log(path) -> list:
    log = mavutil.mavlink_connection(str(path))
    messages = []
    while (m := log.recv_match()) is not None:
        messages.append(m)
    return messages


@pytest.mark.parametrize("append", [True, False])
def test_tlog_append_keeps_the_earlier_flight(append, sim, vehicle_factory, tmp_path):
    path = tmp_path / "flight.tlog"
    rec = Recorder()
    earlier = rec.heartbeat(T0, STABILIZE) + rec.text(T0 + 0.1, "the earlier flight")
    path.write_bytes(earlier)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", tlog_path=str(path), tlog_append=append)
    assert vehicle.wait_for(lambda s: s.connected and s.link.packets_received > 20, 10)
    vehicle.close()
    data = path.read_bytes()
    messages = read_log(path)
    texts = [m.text for m in messages if m.get_type() == "STATUSTEXT"]
    assert "BAD_DATA" not in {m.get_type() for m in messages}
    this_session = [m for m in messages if m._timestamp > T0 + 1.0]
    assert sum(m.get_type() == "HEARTBEAT" and m.get_srcSystem() == 1 for m in this_session) >= 1
    if append:
        assert data.startswith(earlier) and len(data) > len(earlier)
        assert texts[0] == "the earlier flight", texts
    else:
        assert not data.startswith(earlier) and "the earlier flight" not in texts, texts
