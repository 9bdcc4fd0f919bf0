"""The link's hard days: a TCP link that stays open but goes silent, a vehicle that forgets our streams, and
other components of the vehicle's system that must not be taken for the autopilot."""
from __future__ import annotations

import os
import socket
import time

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.vehicle.state import LinkStatus


def driver_ends(port: int) -> set[int]:
    """Local ports of the established TCP connections to ``port`` on this machine (Linux: /proc/net/tcp)."""
    ends = set()
    with open("/proc/net/tcp", encoding="ascii") as f:
        for line in f.readlines()[1:]:
            local, remote, state = line.split()[1:4]
            if state == "01" and int(remote.split(":")[1], 16) == port:       # 01: ESTABLISHED
                ends.add(int(local.split(":")[1], 16))
    return ends


@pytest.mark.skipif(not os.path.exists("/proc/net/tcp"), reason="reads the TCP connections from /proc/net/tcp")
def test_a_half_open_tcp_link_is_reopened(sim, vehicle_factory):
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", loss_timeout=1.0)
    assert vehicle.wait_for(lambda s: s.connected, 10)
    before = driver_ends(sim.tcp_port)
    assert len(before) == 1, before

    sim.faults.link_down = True                 # the socket stays open; nothing comes through it either way
    s = vehicle.wait_for(lambda s: s.link.status is LinkStatus.LOST, 10)
    assert s is not None, vehicle.state().link
    # the driver gives up on that socket and opens a new one: a half-open link never errors by itself
    s = vehicle.wait_for(lambda s: driver_ends(sim.tcp_port) - before, 30)
    assert s is not None, (driver_ends(sim.tcp_port), [m.text for m in vehicle.state().messages])
    sim.faults.link_down = False
    s = vehicle.wait_for(lambda s: s.connected, 15)
    assert s is not None, vehicle.state().link
    assert any(m.text == "Link recovered" for m in s.messages), [m.text for m in s.messages]
    after = driver_ends(sim.tcp_port)
    assert len(after) == 1 and not after & before, (before, after)    # the old socket is closed, not leaked
    # the vehicle is heard on the new link: its telemetry moves the state again
    count = s.link.packets_received
    assert vehicle.wait_for(lambda s: s.link.packets_received > count + 10 and s.connected, 10)
    assert sim.clients == 1


def stop_all_streams(sim, stream: int = mavlink.MAV_DATA_STREAM_ALL) -> None:
    """Another ground station turns every stream (or one) off: to the vehicle it is as if it forgot our rates."""
    out = mavlink.MAVLink(None, srcSystem=254, srcComponent=190)
    with socket.create_connection(("127.0.0.1", sim.tcp_port), timeout=5) as other:
        other.sendall(mavlink.MAVLink_request_data_stream_message(1, 1, stream, 0, 0).pack(out))
        seen = sim.truth().time
        deadline = time.monotonic() + 10
        # hold the connection (reading what the vehicle says to it) until the vehicle has read the request
        while not any(kind == "REQUEST_DATA_STREAM" and t >= seen for t, kind, _ in list(sim.received_messages)):
            assert time.monotonic() < deadline, "the vehicle never read the request"
            other.settimeout(0.05)
            try:
                other.recv(65536)
            except socket.timeout:
                pass


def test_one_stream_lost_is_requested_again_while_the_others_flow(vehicle, sim):
    """A REQUEST_DATA_STREAM lost on a lossy link leaves that one stream off: ATTITUDE keeps coming, but without
    SYS_STATUS and GPS_RAW_INT the pilot would never see the vehicle ready to arm (real SITL at 30 % loss)."""
    assert vehicle.wait_for(lambda s: s.readiness.ready_to_arm, 15)
    stop_all_streams(sim, mavlink.MAV_DATA_STREAM_EXTENDED_STATUS)
    stopped_at = sim.truth().time
    asked = vehicle.wait_for(lambda s: any(kind == "REQUEST_DATA_STREAM" and t > stopped_at
                                           for t, kind, _ in list(sim.received_messages)), 30)
    assert asked is not None, "the stream was never requested again"
    assert vehicle.wait_for(lambda s: s.readiness.ready_to_arm, 10)


def test_streams_are_requested_again_when_the_vehicle_forgets_them(vehicle, sim):
    assert vehicle.wait_for(lambda s: s.readiness.ready_to_arm and s.position is not None, 15)
    stop_all_streams(sim)
    stopped_at = sim.truth().time
    # the vehicle really went quiet: the attitude stops changing for 2 s of the vehicle's time (with the
    # streams on it changes with every ATTITUDE); only heartbeats keep coming
    seen = {"attitude": None, "at": 0.0}

    def quiet(s) -> bool:
        now = sim.truth().time
        if s.attitude != seen["attitude"]:
            seen.update(attitude=s.attitude, at=now)
        return now - seen["at"] > 2.0
    assert vehicle.wait_for(quiet, 10), "the streams did not stop"
    assert vehicle.state().connected
    # the driver notices and asks again, and the telemetry comes back
    asked = vehicle.wait_for(lambda s: any(kind in ("REQUEST_DATA_STREAM", "COMMAND_LONG") and t > stopped_at
                                           for t, kind, _ in list(sim.received_messages)), 30)
    assert asked is not None, "the streams were never requested again"
    silent = vehicle.state().attitude
    assert vehicle.wait_for(lambda s: s.attitude != silent, 10), "the telemetry did not come back"
    assert vehicle.state().connected


def other_component(component: int, mav_type: int, autopilot: int, armed: bool, mode: int):
    """A HEARTBEAT of another component of the vehicle (system 1)."""
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=component)
    base = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (mavlink.MAV_MODE_FLAG_SAFETY_ARMED if armed else 0)
    return mav, mavlink.MAVLink_heartbeat_message(mav_type, autopilot, base, mode, mavlink.MAV_STATE_ACTIVE, 3)


def test_heartbeats_of_a_gimbal_or_companion_never_set_mode_or_arming(vehicle, sim):
    assert vehicle.wait_for(lambda s: s.mode == "STABILIZE" and not s.armed, 10)
    assert sim.truth().mode == "STABILIZE" and not sim.truth().armed
    # the autopilot falls silent for a moment, so that nothing of it can put right what the others claim
    sim.faults.heartbeats = False
    quiet_from = sim.truth().time + 0.1
    assert vehicle.wait_for(lambda s: sim.truth().time > quiet_from, 5)
    frames = b""
    for component, mav_type, autopilot in (
            (mavlink.MAV_COMP_ID_GIMBAL, mavlink.MAV_TYPE_GIMBAL, mavlink.MAV_AUTOPILOT_INVALID),
            (mavlink.MAV_COMP_ID_ONBOARD_COMPUTER, mavlink.MAV_TYPE_ONBOARD_CONTROLLER, mavlink.MAV_AUTOPILOT_INVALID),
            # a gimbal that calls itself ArduPilot (SToRM32 does): still not the autopilot's component
            (mavlink.MAV_COMP_ID_GIMBAL, mavlink.MAV_TYPE_GIMBAL, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA)):
        mav, beat = other_component(component, mav_type, autopilot, armed=True, mode=9)   # "armed, LAND"
        for _ in range(3):
            frames += beat.pack(mav)
            mav.seq = (mav.seq + 1) % 256
    gimbal = mavlink.MAVLink(None, srcSystem=1, srcComponent=mavlink.MAV_COMP_ID_GIMBAL)
    frames += mavlink.MAVLink_statustext_message(mavlink.MAV_SEVERITY_INFO, b"gimbal ready").pack(gimbal)
    sim.inject(frames)                          # in one piece: the text arrives after every heartbeat
    s = vehicle.wait_for(lambda s: any(m.text == "gimbal ready" for m in s.messages), 10)
    assert s is not None, [m.text for m in vehicle.state().messages]
    assert (s.mode, s.armed, s.vehicle_type, s.system_id) == ("STABILIZE", False, mavlink.MAV_TYPE_QUADROTOR, 1), s
    sim.faults.heartbeats = True
    assert vehicle.wait_for(lambda s: s.connected and s.mode == "STABILIZE" and not s.armed, 10)
