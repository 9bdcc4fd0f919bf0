"""The 3DR Solo's real path: the vehicle (through its controller) pushes UDP to the ground station, which
listens with ``udpin``; stock firmware speaks MAVLink 1 only, newer firmware MAVLink 2. Flown end to end."""
from __future__ import annotations

import math
import socket

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.vehicle.state import CommandStatus, LandedState

from test_driver_flight import STICK_DEADMAN, hold_velocity


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("mavlink2", [False, True], ids=["MAVLink 1 (stock Solo)", "MAVLink 2"])
def test_solo_over_udpin_takes_off_flies_and_lands(mavlink2, sim_factory, vehicle_factory):
    port = free_udp_port()
    vehicle = vehicle_factory(f"udpin:127.0.0.1:{port}", deadman=STICK_DEADMAN)   # listening before it pushes
    sim = sim_factory(udp_out=f"127.0.0.1:{port}", tcp_port=None, mavlink2=mavlink2)
    assert vehicle.wait_for(lambda s: s.connected, 10), vehicle.state().link
    assert vehicle.state().system_id == 1

    result = vehicle.takeoff(3.0).result(timeout=60)
    assert result.status is CommandStatus.ACCEPTED, str(result)
    truth = sim.truth()
    assert truth.armed and truth.mode == "GUIDED" and truth.altitude > 2.8, truth

    # the sticks: forward 2 m/s for 2 s of the vehicle's time, along its nose
    before = sim.truth()
    hold_velocity(vehicle, sim, 2.0, 0.0, 0.0, 0.0, 2.0)
    assert vehicle.set_velocity(0.0, 0.0, 0.0, 0.0)
    after = sim.truth()
    dn, de = after.north - before.north, after.east - before.east
    assert 2.0 < math.hypot(dn, de) < 4.6, (dn, de)
    assert abs(math.degrees(math.remainder(math.atan2(de, dn) - before.yaw, 2 * math.pi))) < 12, (dn, de)
    assert any(frame == mavlink.MAV_FRAME_BODY_OFFSET_NED for _, frame, *_ in list(sim.received_setpoints))

    result = vehicle.land().result(timeout=10)
    assert result.status is CommandStatus.ACCEPTED, str(result)
    assert vehicle.wait_for(lambda s: not sim.truth().armed, 60), sim.truth()
    truth = sim.truth()
    assert truth.landed_state == LandedState.ON_GROUND and abs(truth.down) < 0.1 and truth.mode == "LAND"
    assert vehicle.wait_for(lambda s: not s.armed and s.mode == "LAND", 10)

    # the protocol: a MAVLink 1 vehicle only ever heard MAVLink 1 from us; a MAVLink 2 one is followed to 2
    versions = [version for _, _, version in list(sim.received_messages)]
    assert versions
    if mavlink2:
        assert vehicle.state().link.mavlink_version == 2 and versions[-1] == 2
    else:
        assert vehicle.state().link.mavlink_version == 1 and set(versions) == {1}, set(versions)
        assert sim.server.ignored_v2 == 0               # nothing went out that this vehicle cannot read
