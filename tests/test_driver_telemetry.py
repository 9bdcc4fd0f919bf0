"""The telemetry reducer: pure folds from MAVLink to state, and what hostile telemetry can never do."""
from __future__ import annotations

import dataclasses
import math
import random
from collections import ChainMap

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.vehicle import telemetry
from driver.vehicle.state import Battery, VehicleState
from ice_fixtures import eventually

ENC = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
NAN, INF = float("nan"), float("inf")


def fold(state: VehicleState, msg) -> VehicleState:
    return dataclasses.replace(state, **telemetry.fold(ChainMap({}, state.__dict__), msg))


def numbers(value, path="state"):
    """Every number in a snapshot, with where it is."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return
    if isinstance(value, (int, float)):
        yield path, value
    elif dataclasses.is_dataclass(value):
        for f in dataclasses.fields(value):
            yield from numbers(getattr(value, f.name), f"{path}.{f.name}")
    elif isinstance(value, (tuple, list)):
        for i, v in enumerate(value):
            yield from numbers(v, f"{path}[{i}]")


def hostile_messages():
    """Each telemetry message the reducer reads, with NaN, infinity and extremes in its fields."""
    yield ENC.attitude_encode(0, NAN, 0.1, 0.2, 0, 0, 0)
    yield ENC.attitude_encode(0, 0.1, INF, 0.2, 0, 0, 0)
    yield ENC.attitude_encode(0, 0.1, 0.1, 0.2, 0, -INF, 1e30)
    yield ENC.global_position_int_encode(0, 2_000_000_000, 0, 100_000, 3000, 0, 0, 0, 0)
    yield ENC.global_position_int_encode(0, 1, 1, 2_000_000_000, 2_000_000_000, 0, 0, 0, 0)
    yield ENC.vfr_hud_encode(NAN, INF, 9000, 65535, NAN, -INF)
    yield ENC.sys_status_encode(0, 0, 0, 0, 65535, -1, 120, 0, 0, 0, 0, 0, 0)
    yield ENC.battery_status_encode(0, 0, 0, 32767, [65535] * 10, -1, -1, -1, 127)
    yield ENC.scaled_pressure_encode(0, NAN, INF, 32767)
    yield ENC.wind_encode(NAN, INF, NAN)
    yield ENC.home_position_encode(2_000_000_000, 0, 0, 0, 0, 0, [1, 0, 0, 0], 0, 0, 0)
    yield ENC.gps_raw_int_encode(0, 3, 0, 0, 0, 65535, 65535, 65535, 65535, 255)


def test_hostile_values_never_reach_the_state():
    state = VehicleState()
    for msg in hostile_messages():
        state = fold(state, msg)
        bad = [(p, v) for p, v in numbers(state) if isinstance(v, float) and not math.isfinite(v)]
        assert not bad, (msg, bad)
    assert state.rejected_values >= 8
    assert state.position is None and state.home is None and state.attitude.roll == 0.0
    assert state.battery.remaining is None and state.environment.wind_speed is None


def test_a_rejected_message_keeps_the_last_good_values():
    good = fold(VehicleState(), ENC.attitude_encode(0, 0.1, -0.2, 1.5, 0.01, 0.02, 0.03))
    after = fold(good, ENC.attitude_encode(0, NAN, -0.2, 1.5, 0.01, 0.02, 0.03))
    assert after.attitude == good.attitude and after.rejected_values == good.rejected_values + 1


@pytest.mark.parametrize("seed", range(5))
def test_fuzzed_fields_never_give_a_non_finite_state(seed):
    rng = random.Random(seed)
    pick = lambda: rng.choice([NAN, INF, -INF, 1e38, -1e38, 0.0, rng.uniform(-1e6, 1e6)])  # noqa: E731
    ints = lambda bits: rng.choice([0, -1, 2 ** (bits - 1) - 1, -(2 ** (bits - 1)), rng.randrange(-1000, 1000)])  # noqa: E731
    state = VehicleState()
    for _ in range(300):
        msg = rng.choice([
            lambda: ENC.attitude_encode(0, pick(), pick(), pick(), pick(), pick(), pick()),
            lambda: ENC.vfr_hud_encode(pick(), pick(), ints(16), rng.randrange(0, 65536), pick(), pick()),
            lambda: ENC.wind_encode(pick(), pick(), pick()),
            lambda: ENC.scaled_pressure_encode(0, pick(), pick(), ints(16)),
            lambda: ENC.global_position_int_encode(0, ints(32), ints(32), ints(32), ints(32), ints(16), ints(16),
                                                   ints(16), rng.randrange(0, 65536)),
        ])()
        state = fold(state, msg)
    bad = [(p, v) for p, v in numbers(state) if isinstance(v, float) and not math.isfinite(v)]
    assert not bad, bad


def test_the_reducer_is_pure():
    state = VehicleState()
    before = dataclasses.asdict(state)
    view = ChainMap({}, state.__dict__)
    changes = telemetry.fold(view, ENC.attitude_encode(0, 0.1, 0.2, 0.3, 0, 0, 0))
    assert dataclasses.asdict(state) == before and view.maps[0] == {}
    assert set(changes) == {"attitude", "boot"}          # the vehicle's clock rides on its time_boot_ms


def test_a_clock_going_back_is_a_restart_and_reordering_is_not():
    state = VehicleState()
    for time_ms, restarts in ((60_000, 0), (61_000, 0), (60_500, 0), (62_000, 0), (1_500, 1), (2_000, 1)):
        state = fold(state, ENC.attitude_encode(time_ms, 0.1, 0.2, 0.3, 0, 0, 0))
        assert state.boot.restarts == restarts, (time_ms, state.boot)
    assert state.boot.seconds == 2.0
    state = fold(state, ENC.system_time_encode(0, 900))         # SYSTEM_TIME's clock is the same one
    assert state.boot.restarts == 1                              # (only 1.1 s back: reordering)
    state = fold(state, ENC.system_time_encode(0, 100))
    assert state.boot.restarts == 1
    state = fold(state, ENC.attitude_encode(6_000, 0.1, 0.2, 0.3, 0, 0, 0))      # a slow stream's, 4.5 s older:
    state = fold(state, ENC.system_time_encode(0, 1_500))                         # still no restart
    assert state.boot.restarts == 1
    assert VehicleState().boot.heard_param_count(1397).heard_param_count(1397).restarts == 0
    assert VehicleState().boot.heard_param_count(1397).heard_param_count(1401).restarts == 1


@pytest.mark.parametrize("volts, cells", [(12.6, 3), (11.1, 3), (10.0, 3), (16.8, 4), (14.8, 4), (13.4, 4),
                                          (25.2, 6), (4.2, 1)])
def test_cell_count_inferred_from_the_first_voltage(volts, cells):
    assert telemetry.infer_cells(volts) == cells


def test_the_autopilots_battery_failsafe_state_decides_low():
    state = VehicleState(battery=Battery())
    state = fold(state, ENC.sys_status_encode(0, 0, 0, 0, 12600, 500, 90, 0, 0, 0, 0, 0, 0))
    assert state.battery.cells == 3 and not state.battery.low
    voltages = [12600] + [65535] * 9
    critical = ENC.battery_status_encode(0, 0, 0, 2500, voltages, 500, 1000, 100, 90, time_remaining=0,
                                         charge_state=mavlink.MAV_BATTERY_CHARGE_STATE_CRITICAL)
    state = fold(state, critical)
    assert state.battery.low and state.battery.charge_state == mavlink.MAV_BATTERY_CHARGE_STATE_CRITICAL


def test_per_cell_voltages_give_the_cell_count():
    state = fold(VehicleState(), ENC.battery_status_encode(0, 0, 0, 2500, [4100] * 4 + [65535] * 6, 500, 1000,
                                                           100, 80))
    assert state.battery.cells == 4 and state.battery.cells_source == "vehicle"
    assert abs(state.battery.voltage - 16.4) < 1e-6


def test_hostile_telemetry_over_the_link_shows_the_pilot_no_nan(vehicle, sim):
    """Hostile frames with valid CRCs from the vehicle's own system: the state and the Ice Pose3D stay
    finite, the pilot is told once."""
    from driver.ice.convert import pose_enu
    assert vehicle.wait_for(lambda s: s.position is not None, 20)
    # the sim's own telemetry stops first: the driver folds the newest message of each kind it read at once, and
    # on a loaded machine it read the hostile frames together with the sim's next good ones, which then won
    outages = sim.faults.counters.downlink.outage_lost
    sim.faults.link_down = True
    assert eventually(lambda: sim.faults.counters.downlink.outage_lost > outages + 5, 10)
    enc = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    for msg in [*hostile_messages(), ENC.statustext_encode(6, b"after the hostile frames")]:
        sim.inject(msg.pack(enc))
    # the marker comes after them on the same stream: once it is shown, they have all been read
    assert vehicle.wait_for(lambda s: any(m.text == "after the hostile frames" for m in s.messages), 10)
    s = vehicle.wait_for(lambda s: s.rejected_values >= 3, 5)   # the newest of each kind is folded
    assert s is not None, vehicle.state().rejected_values
    bad = [(p, v) for p, v in numbers(s) if isinstance(v, float) and not math.isfinite(v)]
    assert not bad, bad
    assert sum("impossible telemetry" in m.text for m in s.messages) == 1
    assert all(math.isfinite(v) for v in pose_enu(s))


def test_no_position_yet_is_not_a_position_at_zero_zero():
    """ArduPilot sends GLOBAL_POSITION_INT with 0, 0 until it has a position: that is unknown, not the Gulf
    of Guinea."""
    state = fold(VehicleState(), ENC.global_position_int_encode(0, 0, 0, 5000, 0, 0, 0, 0, 65535))
    state = fold(state, ENC.home_position_encode(0, 0, 0, 0, 0, 0, [1, 0, 0, 0], 0, 0, 0))
    assert state.position is None and state.home is None and state.local is None
