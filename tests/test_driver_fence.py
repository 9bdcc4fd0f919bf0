"""ArduPilot's fence: read from the vehicle's parameters, kept by go-to, the same through Ice."""
from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.core import frames
from driver.vehicle.state import CommandStatus, Fence, Velocity
from driver.vehicle.ticker import MASK_POSITION

from ice_fixtures import drone_factory, eventually, ice_server, server_factory  # noqa: F401


@pytest.mark.parametrize("profile, types", [("copter-4", 7), ("solo", 3)])
def test_the_fence_parameters_are_read_with_the_firmwares_defaults(sim_factory, vehicle_factory, profile, types):
    sim = sim_factory(profile=profile)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", mavlink_version=1 if profile == "solo" else 2)
    s = vehicle.wait_for(lambda s: s.fence.known, 15)
    assert s is not None, vehicle.state().fence
    assert s.fence == Fence(enabled=False, types=types, radius=300.0, alt_max=100.0)
    assert s.fence.circle is None and s.fence.ceiling is None          # off by default: nothing drawn, nothing kept


def test_go_to_outside_the_vehicles_fence_is_refused_with_its_reason_here_and_over_ice(
        flying, sim, ice_server, drone_factory):
    for name, value in (("FENCE_RADIUS", 30.0), ("FENCE_ENABLE", 1)):
        assert flying.set_parameter(name, value).result(timeout=10).ok
    s = flying.wait_for(lambda s: s.fence.circle == 30.0, 5)
    assert s is not None and s.fence.ceiling == 100.0

    refused = flying.go_to(40.0, 0.0, 5.0).result(timeout=5)
    assert refused.status is CommandStatus.REJECTED and "FENCE_RADIUS 30 m" in refused.reason

    drone = drone_factory(ice_server)
    assert drone.wait_for(lambda s: s.connected and s.fence.circle == 30.0, 10)
    over_ice = drone.go_to(0.0, -35.0, 5.0).result(timeout=10)
    assert over_ice.status is CommandStatus.REJECTED and "FENCE_RADIUS 30 m" in over_ice.reason
    assert drone.go_to(0.0, -20.0, 5.0).result(timeout=10).ok
    assert flying.wait_for(lambda s: abs(s.local.east + 20.0) < 1.0 and abs(s.local.north) < 1.0, 30)

    # the sticks can still push it out: the vehicle turns back by itself (FENCE_ACTION 1) and says so
    def pushed_west() -> bool:
        s = flying.state()
        forward, right, _ = Velocity(0.0, -2.0, 0.0).body(s.attitude.yaw)
        flying.set_velocity(forward, right, 0.0, 0.0)
        return bool(s.fence.breached)
    assert eventually(pushed_west, 30, interval=0.1)
    s = flying.wait_for(lambda s: s.mode == "RTL", 5)
    assert s is not None and sim.truth().mode == "RTL"
    assert any(m.text.startswith("Fence breached: outside FENCE_RADIUS") for m in s.messages)
    assert drone.wait_for(lambda s: s.fence.breached and s.mode == "RTL", 10)
    assert flying.wait_for(lambda s: s.fence.breached is False, 60)          # back inside on its way home


def test_the_simulated_vehicle_ignores_a_target_outside_its_fence(flying, sim):
    """What the driver spares the pilot: ArduCopter's ModeGuided::set_destination drops it without a word."""
    assert flying.set_parameter("FENCE_ENABLE", 1).result(timeout=10).ok
    assert flying.wait_for(lambda s: s.fence.circle == 300.0, 5)
    home = flying.state().home

    def target_then_barrier(north: float) -> None:
        lat, lon = frames.offset_latlon(home.lat, home.lon, north, 0.0)
        flying._post(mavlink.MAVLink_set_position_target_global_int_message(
            0, 1, 1, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, MASK_POSITION, int(lat * 1e7), int(lon * 1e7),
            5.0, 0, 0, 0, 0, 0, 0, 0, 0))
        # one link, handled in order: once this echo is back the target above was handled too
        assert flying.set_parameter("FENCE_MARGIN", 2.0).result(timeout=10).ok

    target_then_barrier(350.0)
    assert sim.autopilot.pos_target is None or sim.autopilot.pos_target[0] < 1.0
    target_then_barrier(250.0)
    assert sim.autopilot.guided == "position" and sim.autopilot.pos_target[0] == pytest.approx(250.0, abs=0.5)
