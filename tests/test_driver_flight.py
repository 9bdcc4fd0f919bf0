"""The driver flies the simulated ArduCopter end to end over a real TCP socket."""
from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.vehicle.state import CommandStatus, LandedState, SequencePhase

#: The deadman of the drivers that fly here (real seconds). The deadman is a real-time safety net, tested on
#: its own (test_driver_link.py); with its default 0.5 s a test thread that a busy machine stalls for half a
#: second would end a held stick early, and the vehicle would fly less far than the test holds it.
STICK_DEADMAN = 10.0


@pytest.fixture
def vehicle(sim, vehicle_factory):
    """conftest's ``vehicle`` (and so ``flying``), with a deadman no stalled test thread runs into."""
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", deadman=STICK_DEADMAN)
    assert v.wait_for(lambda s: s.connected, 10), "no heartbeat from the simulated vehicle"
    return v


def hold_velocity(vehicle, sim, forward, right, up, yaw_rate, sim_seconds):
    """Act as a pilot holding the sticks: refresh the command until ``sim_seconds`` of vehicle time pass.

    The command holds until the vehicle's clock has moved on ``sim_seconds``, however slowly this thread runs;
    fly a driver with a deadman far above the refresh (:data:`STICK_DEADMAN`)."""
    assert vehicle.config.deadman >= STICK_DEADMAN, "a stalled refresh would let the deadman end the stick"
    end = sim.truth().time + sim_seconds
    while sim.truth().time < end:
        assert vehicle.set_velocity(forward, right, up, yaw_rate)
        vehicle.wait_for(lambda s: sim.truth().time >= end, 0.1)   # paces the stream, like a 10 Hz stick


def settle(vehicle, sim, speed=0.15, timeout=20):
    assert vehicle.wait_for(lambda s: math.hypot(sim.truth().vn, sim.truth().ve) < speed, timeout), \
        "the vehicle did not come to rest"


def angle_between(a, b):
    return abs(math.degrees(math.atan2(math.sin(a - b), math.cos(a - b))))


def fly_forward_and_check_heading(vehicle, sim):
    before = sim.truth()
    hold_velocity(vehicle, sim, 2.0, 0.0, 0.0, 0.0, 2.0)
    vehicle.set_velocity(0, 0, 0, 0)
    after = sim.truth()
    dn, de = after.north - before.north, after.east - before.east
    distance = math.hypot(dn, de)
    # 2 m/s for 2 s with a first-order response: well over half of the ideal 4 m, never more than it
    assert 2.0 < distance < 4.6, distance
    assert angle_between(math.atan2(de, dn), before.yaw) < 12.0, (dn, de, math.degrees(before.yaw))
    # the driver's own estimate agrees with the truth
    s = vehicle.wait_for(lambda s: s.local and abs(s.local.north - sim.truth().north) < 0.6
                         and abs(s.local.east - sim.truth().east) < 0.6, 5)
    assert s is not None, (vehicle.state().local, sim.truth())


def test_takeoff_fly_turn_fly_land(vehicle, sim):
    progress = []
    future = vehicle.takeoff(3.0)
    while not future.done():
        s = vehicle.wait_for(lambda s: s.takeoff.phase not in progress[-1:], 1.0)
        if s is not None and s.takeoff.phase not in progress:
            progress.append(s.takeoff.phase)
    result = future.result()
    assert result.status is CommandStatus.ACCEPTED, str(result)
    assert SequencePhase.ARMING in progress and SequencePhase.CLIMBING in progress, progress
    assert vehicle.state().takeoff.phase is SequencePhase.DONE
    truth = sim.truth()
    assert truth.armed and truth.mode == "GUIDED" and truth.landed_state == LandedState.IN_AIR
    assert 2.8 < -truth.down < 3.4
    # the vehicle says so in its next EXTENDED_SYS_STATE, which may come after the climb was seen to end
    assert vehicle.wait_for(lambda s: s.landed_state is LandedState.IN_AIR, 5)

    fly_forward_and_check_heading(vehicle, sim)
    settle(vehicle, sim)

    yaw0 = sim.truth().yaw
    assert vehicle.set_yaw(90, relative=True, rate_deg_s=45).result(timeout=10).ok
    assert vehicle.wait_for(lambda s: angle_between(sim.truth().yaw, yaw0 + math.pi / 2) < 3, 30), \
        math.degrees(sim.truth().yaw - yaw0)
    fly_forward_and_check_heading(vehicle, sim)

    result = vehicle.land().result(timeout=10)
    assert result.ok, str(result)
    s = vehicle.wait_for(lambda s: not s.armed and s.landed_state is LandedState.ON_GROUND, 60)
    assert s is not None, vehicle.state()
    assert not sim.truth().armed and abs(sim.truth().down) < 0.1


def test_yaw_rate_turns_the_nose(flying, sim):
    yaw0 = sim.truth().yaw
    hold_velocity(flying, sim, 0, 0, 0, 0.5, 2.0)          # +0.5 rad/s: nose right (clockwise)
    turned = math.atan2(math.sin(sim.truth().yaw - yaw0), math.cos(sim.truth().yaw - yaw0))
    assert 0.5 < turned < 1.1, math.degrees(turned)
    assert sim.received_setpoints[-1][2] == 1479               # velocity + yaw-rate mask


def test_stop_holds_position(sim, vehicle_factory):
    # a deadman far longer than the test: only stop() can bring the setpoint to zero here
    flying = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", deadman=60.0)
    assert flying.takeoff(3.0).result(timeout=60).ok
    hold_velocity(flying, sim, 2.0, 1.0, 0, 0, 1.0)
    assert not flying.state().setpoint.is_zero
    assert flying.stop().result(timeout=5).ok
    assert flying.state().setpoint.is_zero
    settle(flying, sim)
    held = sim.truth()
    end = held.time + 2.0
    flying.wait_for(lambda s: sim.truth().time >= end, 10)
    now = sim.truth()
    assert math.hypot(now.north - held.north, now.east - held.east) < 0.3
    assert abs(now.down - held.down) < 0.3 and now.mode == "GUIDED"


def test_go_to_a_local_point(flying, sim):
    for north, east, alt in ((0, 0, 500.0), (400.0, 400.0, 5.0), (0, 0, -2.0), (math.nan, 0, 5)):
        refused = flying.go_to(north, east, alt).result(timeout=5)
        assert refused.status is CommandStatus.REJECTED, refused
    assert not any(m[1] == "SET_POSITION_TARGET_GLOBAL_INT" for m in list(sim.received_messages))
    assert flying.go_to(6.0, -4.0, 5.0).result(timeout=5).ok
    assert flying.wait_for(lambda s: math.hypot(sim.truth().north - 6.0, sim.truth().east + 4.0) < 0.5
                           and abs(-sim.truth().down - 5.0) < 0.4, 40), sim.truth()


def test_climb_with_velocity(flying, sim):
    alt0 = -sim.truth().down
    hold_velocity(flying, sim, 0, 0, 1.0, 0, 2.0)
    assert -sim.truth().down - alt0 > 1.0


def test_land_during_takeoff_aborts_it(vehicle, sim):
    assert vehicle.wait_for(lambda s: s.readiness.ready_to_arm, 20)
    takeoff = vehicle.takeoff(5.0)
    assert vehicle.wait_for(lambda s: s.takeoff.phase is SequencePhase.CLIMBING, 20)
    busy = vehicle.set_mode("LOITER").result(timeout=2)
    assert busy.status is CommandStatus.REJECTED and "takeoff" in busy.reason
    assert vehicle.land().result(timeout=10).ok
    assert takeoff.result(timeout=10).status is CommandStatus.ABORTED
    assert vehicle.wait_for(lambda s: s.mode == "LAND", 5)
    assert vehicle.wait_for(lambda s: not s.armed, 60)


def test_arming_early_is_refused_with_the_vehicles_reason(sim_factory, vehicle_factory):
    sim = sim_factory(ready_after=600.0)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.connected, 10)
    # once its start-up messages are over (none for 2 s of its time): the refusal's words are then its own
    # (with other messages around, see test_driver_commands.py::test_a_refusal_keeps_the_vehicles_reason_...)
    heard = {"count": -1, "at": 0.0}

    def quiet(s) -> bool:
        now, count = sim.truth().time, len(s.messages)
        if count != heard["count"]:
            heard.update(count=count, at=now)
        return now - heard["at"] > 2.0
    assert vehicle.wait_for(quiet, 30), [m.text for m in vehicle.state().messages]
    assert not vehicle.state().readiness.ready_to_arm
    result = vehicle.arm().result(timeout=10)
    assert result.status is CommandStatus.REFUSED
    # the vehicle's own words ("PreArm: ..." or, on ArduCopter 4.x, "Arm: ...") and its ACK result
    refusals = [m.text for m in vehicle.state().messages
                if m.source == "vehicle" and m.text.startswith(("PreArm:", "Arm:"))]
    assert refusals and any(text in result.reason for text in refusals), (result.reason, refusals)
    assert "FAILED" in result.reason, result.reason
    assert result in vehicle.state().results


def test_takeoff_reports_a_refusal(sim_factory, vehicle_factory):
    sim = sim_factory()
    sim.faults.refuse_arm = "Check fence"
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    result = vehicle.takeoff().result(timeout=30)
    assert result.status is CommandStatus.REFUSED and "Check fence" in result.reason, str(result)
    assert vehicle.state().takeoff.phase is SequencePhase.FAILED
    assert not sim.truth().armed


def test_unanswered_command_is_retried_then_timed_out(vehicle, sim):
    assert vehicle.wait_for(lambda s: s.position is not None, 10)
    sim.faults.ignore_commands = {mavlink.MAV_CMD_COMPONENT_ARM_DISARM}
    sent_before = sum(1 for m in list(sim.received_messages) if m[1] == "COMMAND_LONG")
    result = vehicle.arm().result(timeout=20)
    assert result.status is CommandStatus.TIMED_OUT and result.attempts == 3, str(result)
    sent = sum(1 for m in list(sim.received_messages) if m[1] == "COMMAND_LONG") - sent_before
    assert sent == 3


def test_link_loss_is_detected_and_recovery_seen(sim, vehicle_factory):
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", loss_timeout=1.0)
    assert vehicle.wait_for(lambda s: s.connected, 10)
    sim.faults.link_down = True
    s = vehicle.wait_for(lambda s: s.link.status.value == "lost", 10)
    assert s is not None and s.link.heartbeat_age > 1.0 and s.link.lost_count == 1
    assert any(m.text.startswith("Link lost") for m in s.messages)
    sim.faults.link_down = False
    s = vehicle.wait_for(lambda s: s.connected, 10)
    assert s is not None and any(m.text == "Link recovered" for m in s.messages)


def test_tcp_link_reconnects_after_the_vehicle_restarts(sim_factory, vehicle_factory):
    sim = sim_factory()
    port = sim.tcp_port
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{port}", loss_timeout=1.0)
    assert vehicle.wait_for(lambda s: s.connected, 10)
    sim.stop()
    assert vehicle.wait_for(lambda s: s.link.status.value == "lost", 10)
    sim_factory(tcp_port=port)
    assert vehicle.wait_for(lambda s: s.connected, 15), vehicle.state().link
    assert vehicle.wait_for(lambda s: s.gps.fix_type > 0, 10)   # streams requested again


def test_heartbeats_stop_but_traffic_flows(sim, vehicle_factory):
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", loss_timeout=1.0)
    assert vehicle.wait_for(lambda s: s.connected, 10)
    sim.faults.heartbeats = False
    assert vehicle.wait_for(lambda s: s.link.status.value == "lost", 10)
    sim.faults.heartbeats = True
    assert vehicle.wait_for(lambda s: s.connected, 10)


def test_stop_during_takeoff_cancels_what_the_takeoff_asked(vehicle, sim):
    """The first NAV_TAKEOFF is lost; the pilot presses Stop; the retry must not launch the vehicle."""
    assert vehicle.wait_for(lambda s: s.readiness.ready_to_arm, 20)
    sim.faults.ignore_commands = {mavlink.MAV_CMD_NAV_TAKEOFF}
    takeoff = vehicle.takeoff(3.0)
    # Stop only once the vehicle has lost the first NAV_TAKEOFF: a command still on its way when the pilot
    # presses Stop cannot be called back, and the vehicle would rightly obey it
    assert vehicle.wait_for(lambda s: mavlink.MAV_CMD_NAV_TAKEOFF in sim.faults.ignored, 20)
    assert vehicle.state().takeoff.phase is SequencePhase.TAKING_OFF
    assert vehicle.stop().result(timeout=5).ok
    assert takeoff.result(timeout=5).status is CommandStatus.ABORTED
    sim.faults.ignore_commands = set()                  # the radio recovers
    n = len(sim.received_messages)
    # three command timeouts later nothing of the takeoff went out again and the vehicle stayed down
    end = sim.truth().time + 3 * vehicle.config.command_timeout * 4.0
    vehicle.wait_for(lambda s: sim.truth().time >= end, 30)
    assert sim.truth().landed_state == LandedState.ON_GROUND and -sim.truth().down < 0.2
    aborted = [r for r in vehicle.state().results if r.command.startswith("NAV_TAKEOFF")]
    assert aborted and aborted[-1].status is CommandStatus.ABORTED, aborted
    assert sum(1 for m in list(sim.received_messages)[n:] if m[1] == "COMMAND_LONG") == 0
    # the pilot is told the one that went out could still have reached the vehicle
    assert any("after NAV_TAKEOFF went out" in m.text for m in vehicle.state().messages)


def test_one_takeoff_at_a_time_even_after_an_abort(sim_factory, vehicle_factory):
    sim = sim_factory(ready_after=600.0)                # never ready: the sequence waits
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", ready_timeout=600.0)
    assert vehicle.wait_for(lambda s: s.connected and s.in_air is False, 10)     # it says it is on the ground
    first = vehicle.takeoff()
    assert vehicle.takeoff().result(timeout=2).status is CommandStatus.REJECTED
    assert vehicle.land().result(timeout=10).ok
    assert first.result(timeout=5).status is CommandStatus.ABORTED
    import threading
    threads = {t.name for t in threading.enumerate()}
    second = vehicle.takeoff()
    assert vehicle.wait_for(lambda s: s.takeoff.active, 5)
    # one thread model: the driver's ticker steps the sequence, no thread is started for it (the fixed
    # pool that settles results may still be filling up)
    started = {t.name for t in threading.enumerate()} - threads
    assert all(name.startswith("command-results") for name in started), started
    stopped = vehicle.stop().result(timeout=5)          # before liftoff Stop cancels, leaving the vehicle as it was
    assert stopped.ok and stopped.reason == "cancelled before liftoff: the vehicle was not changed", stopped
    assert second.result(timeout=5).status is CommandStatus.ABORTED


def test_a_slow_result_callback_delays_neither_link_nor_caller(vehicle, sim):
    import threading
    release = threading.Event()
    entered = threading.Event()

    def slow(_future):
        entered.set()
        release.wait(30)                                # e.g. a client that chains a blocking call

    assert vehicle.wait_for(lambda s: s.readiness.ready_to_arm, 15)   # both modes need a position
    loiter = vehicle.set_mode("LOITER")
    loiter.add_done_callback(slow)
    try:
        assert entered.wait(10)
        assert loiter.result().status is CommandStatus.ACCEPTED and sim.truth().mode == "LOITER"
        count = vehicle.state().link.packets_received
        assert vehicle.wait_for(lambda s: s.link.packets_received > count + 20, 10), "the link stalled"
        result = vehicle.set_mode("GUIDED").result(timeout=10)
        assert result.status is CommandStatus.ACCEPTED, str(result)
        assert sim.truth().mode == "GUIDED"
    finally:
        release.set()
