"""A UDP link pinned to the vehicle: another sender on the network (here, another port on loopback) can
neither speak for the vehicle nor hear our commands, unless the pilot allows that sender with --allow."""
from __future__ import annotations

import socket

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.sim.autopilot import MODES
from test_driver_solo import free_udp_port


class Spoofer:
    """A second process's socket on the same Wi-Fi (loopback here): claims to be vehicle 1 and listens."""

    def __init__(self, port: int):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.setblocking(False)
        self.address = self.sock.getsockname()
        self.port = port
        self.codec = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        self.sent = 0

    def send(self, msg) -> None:
        self.sock.sendto(msg.pack(self.codec), ("127.0.0.1", self.port))
        self.codec.seq = (self.codec.seq + 1) % 256
        self.sent += 1

    def spoof(self) -> None:
        """A heartbeat saying LAND and disarmed, an ACK for a takeoff, a message for the pilot."""
        self.send(mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                                    mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MODES["LAND"], 3, 3))
        self.send(mavlink.MAVLink_command_ack_message(mavlink.MAV_CMD_NAV_TAKEOFF, mavlink.MAV_RESULT_ACCEPTED))
        self.send(mavlink.MAVLink_statustext_message(mavlink.MAV_SEVERITY_CRITICAL, b"spoofed: land now"))

    def heard(self) -> int:
        n = 0
        while True:
            try:
                self.sock.recvfrom(65536)
            except BlockingIOError:
                return n
            n += 1

    def close(self) -> None:
        self.sock.close()


def _our_heartbeats(sim) -> int:
    return sum(kind == "HEARTBEAT" for _, kind, _ in list(sim.received_messages))


def test_spoofed_heartbeats_acks_and_texts_from_another_address_are_ignored(sim_factory, vehicle_factory):
    port = free_udp_port()
    vehicle = vehicle_factory(f"udpin:127.0.0.1:{port}")
    sim = sim_factory(udp_out=f"127.0.0.1:{port}", tcp_port=None)
    s = vehicle.wait_for(lambda s: s.connected and s.mode, 10)
    assert s is not None and s.link.pinned_to.startswith("127.0.0.1:")
    mode = s.mode
    spoofer = Spoofer(port)
    try:
        for _ in range(5):
            spoofer.spoof()
        s = vehicle.wait_for(lambda s: s.link.foreign_packets >= spoofer.sent, 10)
        assert s is not None, "the spoofed datagrams were not counted as foreign"
        heard = _our_heartbeats(sim)
        assert vehicle.wait_for(lambda s: _our_heartbeats(sim) >= heard + 2, 10)   # we kept speaking meanwhile
        s = vehicle.state()
        assert s.mode == mode and s.system_id == 1
        assert not any(m.text == "spoofed: land now" for m in s.messages)
        assert any("Ignored MAVLink from 127.0.0.1:%d" % spoofer.address[1] in m.text for m in s.messages)
        assert spoofer.heard() == 0, "our frames reached a stranger"
        assert vehicle.takeoff(2.0).result(timeout=60).ok   # the real vehicle still flies
    finally:
        spoofer.close()


def test_a_sender_named_with_allow_is_read_but_never_sent_to(sim_factory, vehicle_factory, tmp_path):
    port = free_udp_port()
    controller = Spoofer(port)                           # the Solo's controller: system 51, its radio's status
    controller.codec = mavlink.MAVLink(None, srcSystem=51, srcComponent=68)
    log = tmp_path / "allowed.tlog"
    try:
        vehicle = vehicle_factory(f"udpin:127.0.0.1:{port}", tlog_path=str(log),
                                  allowed_senders=(f"127.0.0.1:{controller.address[1]}",))
        sim = sim_factory(udp_out=f"127.0.0.1:{port}", tcp_port=None)
        assert vehicle.wait_for(lambda s: s.connected, 10)
        controller.send(mavlink.MAVLink_statustext_message(mavlink.MAV_SEVERITY_INFO, b"controller says hello"))
        assert vehicle.wait_for(lambda s: log.exists() and b"controller says hello" in log.read_bytes(), 10), \
            "the allowed sender's frame was not read"
        heard = _our_heartbeats(sim)
        assert vehicle.wait_for(lambda s: _our_heartbeats(sim) >= heard + 2, 10)
        assert vehicle.state().link.foreign_packets == 0
        assert controller.heard() == 0, "an allowed sender must still not receive our commands"
    finally:
        controller.close()
