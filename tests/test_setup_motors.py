"""The motor test and the radio end to end: SERVO_OUTPUT_RAW and RC_CHANNELS as the driver shows them from the
simulated vehicle (both profiles), and the driver's own refusals."""
from __future__ import annotations

import math

from driver.vehicle.state import CommandStatus

from ice_fixtures import eventually
from setup_fixtures import bench, texts  # noqa: F401

T = 30


def outputs_in_turn(vehicle, until, value: int) -> list[int]:
    """The outputs seen at ``value`` one after the other until ``until()`` (state changes only, no sleeps)."""
    seen: list[int] = []
    while not until():
        state = vehicle.wait_for(lambda s: until() or (
            [i + 1 for i, v in enumerate(s.setup.outputs.values[:4]) if v == value][:1] not in ([], seen[-1:])), T)
        assert state is not None
        spinning = [i + 1 for i, v in enumerate(state.setup.outputs.values[:4]) if v == value]
        if spinning and spinning[:1] != seen[-1:]:
            seen.append(spinning[0])
    return seen


def test_a_plus_quad_runs_motors_1_to_4_on_outputs_3_1_4_2_then_disarms(bench):
    sim, v = bench()
    sim.autopilot.params["FRAME_TYPE"] = 0                    # + quad, as the recording's SITL
    v.setup.watch_radio()
    assert v.wait_for(lambda s: s.setup.outputs.values[:4] == (1000, 1000, 1000, 1000), T)
    result = v.setup.motor_test(1, throttle_pct=20, seconds=2.0, count=4, propellers_removed=True).result(T)
    assert result.status is CommandStatus.ACCEPTED
    finished = outputs_in_turn(v, lambda: not sim.autopilot.motor_testing, 1200)
    assert finished == ([3, 1, 4, 2] if bench.profile == "copter-4" else [3])     # 3.3 takes no count
    assert v.wait_for(lambda s: not s.armed and s.setup.outputs.values[:4] == (1000,) * 4, T)
    if bench.profile == "copter-4":
        assert "starting motor test" in texts(v) and "finished motor test" in texts(v)


def test_pwm_and_stop_cut_the_output_at_once(bench):
    sim, v = bench()
    sim.autopilot.params["FRAME_TYPE"] = 0
    assert v.setup.motor_test(2, pwm=1300, seconds=60, propellers_removed=True).result(T).ok
    assert v.wait_for(lambda s: s.setup.outputs.output(1) == 1300, T)
    assert v.setup.motor_test_running
    assert v.setup.stop_motor_test().result(T).ok
    assert v.wait_for(lambda s: s.setup.outputs.output(1) == 1000, T)          # the output cut
    # and the vehicle ends its test at its next loop, disarmed (the driver's "disarmed" is no sign of it: the 1 Hz
    # heartbeat may never have shown the test's arming, so waiting on it caught the sim mid-loop, 3 runs in 4)
    assert eventually(lambda: not sim.autopilot.motor_testing and not sim.autopilot.armed, T)


def test_the_driver_refuses_a_motor_test_without_the_propellers_off_armed_or_with_bad_values(bench):
    sim, v = bench()
    refused = v.setup.motor_test(1, throttle_pct=20, seconds=2)
    assert refused.result(T).status is CommandStatus.REJECTED and "propellers" in refused.result().reason
    for kwargs in (dict(throttle_pct=math.nan), dict(throttle_pct=120), dict(pwm=5000), dict(throttle_pct=10, pwm=1200),
                   dict(throttle_pct=10, seconds=0), dict(throttle_pct=10, seconds=math.inf)):
        kwargs.setdefault("seconds", 2)
        assert v.setup.motor_test(1, propellers_removed=True, **kwargs).result(T).status is CommandStatus.REJECTED
    assert v.set_mode("GUIDED").result(T).ok and v.arm().result(T).ok
    assert v.wait_for(lambda s: s.armed, T)
    armed = v.setup.motor_test(1, throttle_pct=20, seconds=2, propellers_removed=True).result(T)
    assert armed.status is CommandStatus.REJECTED and "armed" in armed.reason
    assert sim.autopilot.motor_testing is False


def test_the_transmitters_sticks_show_in_the_rc_channels(bench):
    sim, v = bench()
    v.setup.watch_radio()
    state = v.wait_for(lambda s: s.setup.rc.channel(3) == 1000, T)
    assert state.setup.rc.values[:8] == (1500, 1500, 1000, 1500, 1800, 1000, 1000, 1800)
    sim.autopilot.move_stick(3, 1620)
    assert v.wait_for(lambda s: s.setup.rc.channel(3) == 1620, T)


def test_the_test_runs_until_the_vehicle_ends_it_even_when_another_station_stops_it(bench):
    """The running state is the vehicle's: its "finished motor test" (4.x) or its disarm (3.3 says nothing),
    not a clock guess."""
    from pymavlink.dialects.v20 import ardupilotmega as mavlink

    from driver.sim.gcs import OtherGroundStation

    sim, v = bench()
    assert v.setup.motor_test(1, throttle_pct=20, seconds=25, propellers_removed=True).result(T).ok
    assert v.wait_for(lambda s: s.setup.motor_test_running and s.armed, T)
    other = OtherGroundStation(f"tcp:127.0.0.1:{sim.tcp_port}", mavlink1=bench.profile == "solo").start()
    try:
        ack = other.command(mavlink.MAV_CMD_DO_MOTOR_TEST, 1, 0, 0, 0, 0)
        assert ack is not None and ack.result == mavlink.MAV_RESULT_ACCEPTED
    finally:
        other.close()
    assert v.wait_for(lambda s: not s.setup.motor_test_running, 15)
    assert not sim.autopilot.motor_testing, (sim.autopilot.motor_test, sim.autopilot.motor_queue, sim.autopilot.t, sim.autopilot.armed)


def test_stop_is_sent_only_while_a_test_runs(bench):
    """DO_MOTOR_TEST with timeout 0 while none runs starts a test that arms then disarms the vehicle
    (motor_test.cpp): an idle Stop is refused here, and the armed vehicle stays armed."""
    sim, v = bench()
    assert v.set_mode("GUIDED").result(T).ok and v.arm().result(T).ok
    assert v.wait_for(lambda s: s.armed, T)
    refused = v.setup.stop_motor_test().result(T)
    assert refused.status is CommandStatus.REJECTED and "no motor test is running" in refused.reason
    assert v.state().armed and sim.autopilot.armed


def test_a_sequence_rests_half_each_motors_seconds_and_the_solo_runs_one_motor(bench):
    sim, v = bench()
    assert v.setup.motor_test(1, throttle_pct=20, seconds=4, count=4, propellers_removed=True).result(T).ok
    starts = [entry[0] for entry in sim.autopilot.motor_queue]      # the next motors (the first may be out)
    if bench.profile == "copter-4":                  # motor_test.cpp: timeout, then 0.5 x timeout at rest
        gaps = [round(b - a, 6) for a, b in zip(starts, starts[1:])]
        assert len(gaps) >= 2 and set(gaps) == {6.0}
    else:                                            # 3.3's motor_test.pde takes no count
        assert sim.autopilot.motor_test is not None or len(starts) == 1
        assert len(starts) <= 1
    assert v.setup.stop_motor_test().result(T).ok
    assert v.wait_for(lambda s: not s.setup.motor_test_running and not s.armed, T)
