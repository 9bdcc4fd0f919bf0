"""Commands the pilot has beyond takeoff, sticks and land, each checked on what the simulated vehicle did:
return to launch, arming and disarming (forced or not), Stop outside GUIDED, an absolute heading, a go-to
before the vehicle has sent its home, and a reboot."""
from __future__ import annotations

import math
import threading

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.sim.autopilot import Autopilot
from driver.vehicle.state import CommandStatus, LandedState


def angle_between(a: float, b: float) -> float:
    """Degrees between two angles in radians."""
    return abs(math.degrees(math.remainder(a - b, 2 * math.pi)))


def until(vehicle, sim, condition, timeout: float):
    """The simulated vehicle's truth once ``condition(truth)`` holds (checked as the driver's state moves on)."""
    if vehicle.wait_for(lambda s: condition(sim.truth()), timeout) is None:
        return None
    return sim.truth()


def test_return_to_launch_flies_home_lands_and_disarms(flying, sim):
    # climb no higher than 4 m and do not loiter over home: the whole return takes a few seconds
    for name, value in (("RTL_ALT", 400), ("RTL_LOIT_TIME", 0)):
        result = flying.set_parameter(name, value).result(timeout=15)
        assert result.status is CommandStatus.ACCEPTED, str(result)
    assert flying.go_to(8.0, -6.0, 4.0).result(timeout=5).ok
    assert until(flying, sim, lambda t: math.hypot(t.north - 8.0, t.east + 6.0) < 0.5, 40), sim.truth()

    result = flying.return_to_launch().result(timeout=10)
    assert result.status is CommandStatus.ACCEPTED, str(result)
    assert sim.truth().mode == "RTL"
    home = until(flying, sim, lambda t: math.hypot(t.north, t.east) < 0.5 and t.ground_speed < 0.3, 40)
    assert home is not None and home.armed and home.mode == "RTL", sim.truth()
    landed = until(flying, sim, lambda t: not t.armed, 60)
    assert landed is not None, sim.truth()
    assert abs(landed.down) < 0.1 and math.hypot(landed.north, landed.east) < 1.0
    assert flying.wait_for(lambda s: not s.armed and s.mode == "RTL", 10), flying.state()


def test_arming_refused_is_forced_and_disarming_on_the_ground(sim_factory, vehicle_factory):
    sim = sim_factory(auto_disarm_after=0)          # never disarms by itself: only our commands change arming
    sim.faults.refuse_arm = "Check fence"
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.connected and s.readiness.gps_ok, 15)

    refused = vehicle.arm().result(timeout=10)
    assert refused.status is CommandStatus.REFUSED and "Check fence" in refused.reason, str(refused)
    assert not sim.truth().armed
    forced = vehicle.arm(force=True).result(timeout=10)
    assert forced.status is CommandStatus.ACCEPTED, str(forced)
    assert sim.truth().armed
    assert vehicle.wait_for(lambda s: s.armed, 5)

    disarmed = vehicle.disarm().result(timeout=10)
    assert disarmed.status is CommandStatus.ACCEPTED, str(disarmed)
    assert not sim.truth().armed
    assert vehicle.wait_for(lambda s: not s.armed, 5)

    assert vehicle.arm(force=True).result(timeout=10).ok and sim.truth().armed
    forced = vehicle.disarm(force=True).result(timeout=10)      # on the ground a forced disarm goes through
    assert forced.status is CommandStatus.ACCEPTED, str(forced)
    assert not sim.truth().armed


def test_disarm_in_flight_is_refused_even_forced(flying, sim):
    """While the vehicle may be airborne the driver sends no disarm, plain or forced (the motors would stop and
    the vehicle fall): only the confirmed emergency motor stop. It keeps flying, and never heard one."""
    since = sim.truth().time
    refused = flying.disarm().result(timeout=10)
    assert refused.status is CommandStatus.REJECTED and "airborne" in refused.reason, str(refused)
    forced = flying.disarm(force=True).result(timeout=10)
    assert forced.status is CommandStatus.REJECTED, str(forced)
    later = until(flying, sim, lambda t: t.time > since + 1.0, 10)
    assert later is not None and later.armed and later.altitude > 2.5, later
    assert not [kind for t, kind, _ in list(sim.received_messages) if t >= since and kind == "COMMAND_LONG"]
    assert flying.state().armed


def test_stop_outside_guided_holds_in_guided(vehicle, sim):
    assert vehicle.takeoff(6.0).result(timeout=60).ok
    assert vehicle.land().result(timeout=10).ok
    assert until(vehicle, sim, lambda t: t.mode == "LAND" and t.vd > 0.3, 20), sim.truth()   # coming down

    result = vehicle.stop().result(timeout=10)
    assert result.status is CommandStatus.ACCEPTED, str(result)
    assert sim.truth().mode == "GUIDED" and "the sticks fly" in result.reason   # issue 21: sticks live again
    stopped = until(vehicle, sim, lambda t: abs(t.vd) < 0.05 and t.ground_speed < 0.1, 20)
    assert stopped is not None, sim.truth()
    assert stopped.armed and stopped.altitude > 1.0
    later = until(vehicle, sim, lambda t: t.time >= stopped.time + 2.0, 10)
    assert later is not None and later.mode == "GUIDED" and later.armed
    assert abs(later.altitude - stopped.altitude) < 0.2, (stopped.altitude, later.altitude)   # held, not landing
    assert later.landed_state == LandedState.IN_AIR
    assert vehicle.wait_for(lambda s: s.mode == "GUIDED" and s.can_fly_velocity, 5)


def test_set_yaw_turns_to_absolute_headings(flying, sim):
    assert angle_between(sim.truth().yaw, 0.0) < 3             # the simulated vehicle starts facing north
    for heading in (120.0, 60.0):                               # from 120 a relative turn by 60 would end at 180
        result = flying.set_yaw(heading, rate_deg_s=60).result(timeout=10)
        assert result.status is CommandStatus.ACCEPTED, str(result)
        settled = until(flying, sim, lambda t: angle_between(t.yaw, math.radians(heading)) < 2
                        and abs(t.yaw_rate) < 0.02, 30)
        assert settled is not None, (heading, sim.truth().heading_deg)
        assert flying.wait_for(lambda s: abs(math.remainder(s.heading_deg - heading, 360)) < 3, 5), \
            flying.state().heading_deg


def test_go_to_waits_for_the_vehicles_home(sim_factory, vehicle_factory, monkeypatch):
    """Targets are metres from home: before the vehicle has sent its home position a go-to is refused and
    nothing reaches the vehicle (never a target in the EKF origin's frame); once home is known it flies."""
    monkeypatch.setattr(Autopilot, "_msg_home_position", lambda self: None)     # home withheld
    sim = sim_factory()
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.takeoff(3.0).result(timeout=60).ok
    assert vehicle.state().home is None and vehicle.state().flying

    since = sim.truth().time
    refused = vehicle.go_to(5.0, -3.0, 4.0).result(timeout=5)
    assert refused.status is CommandStatus.REJECTED and "home" in refused.reason, str(refused)
    held = until(vehicle, sim, lambda t: t.time > since + 2.0, 10)
    assert held is not None and math.hypot(held.north, held.east) < 0.3 and abs(held.altitude - 3.0) < 0.3, held
    assert not [kind for t, kind, _ in list(sim.received_messages) if t >= since and kind.startswith("SET_POSITION")]

    monkeypatch.undo()                                   # the vehicle tells its home (it streams it at 0.5 Hz)
    assert vehicle.wait_for(lambda s: s.home is not None, 15), "HOME_POSITION never arrived"
    result = vehicle.go_to(5.0, -3.0, 4.0).result(timeout=5)
    assert result.status is CommandStatus.ACCEPTED, str(result)
    there = until(vehicle, sim, lambda t: math.hypot(t.north - 5.0, t.east + 3.0) < 0.4
                  and abs(t.altitude - 4.0) < 0.3 and t.ground_speed < 0.2, 40)
    assert there is not None, sim.truth()


def test_reboot_restarts_the_vehicle_but_never_while_armed(sim_factory, vehicle_factory):
    sim = sim_factory(auto_disarm_after=0)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.readiness.ready_to_arm, 15)
    assert vehicle.arm().result(timeout=10).ok
    refused = vehicle.reboot().result(timeout=10)
    assert refused.status is CommandStatus.REJECTED and "armed" in refused.reason, str(refused)
    assert sim.truth().armed and sim.autopilot.rebooting_until is None     # never sent: the driver refused it
    assert vehicle.disarm().result(timeout=10).ok
    assert vehicle.set_mode("ALT_HOLD").result(timeout=10).ok and sim.truth().mode == "ALT_HOLD"

    since = vehicle.state().messages[-1].index
    result = vehicle.reboot().result(timeout=10)
    assert result.status is CommandStatus.ACCEPTED, str(result)
    # the autopilot starts again: back in its power-on mode, saying who it is
    assert until(vehicle, sim, lambda t: t.mode == "STABILIZE", 20), sim.truth()
    s = vehicle.wait_for(lambda s: s.mode == "STABILIZE" and any(
        m.source == "vehicle" and m.text.startswith("ArduCopter") for m in s.messages_since(since)), 10)
    assert s is not None, [m.text for m in vehicle.state().messages_since(since)]
    assert s.connected and not s.armed


def test_a_refusal_keeps_the_vehicles_reason_among_other_messages(sim_factory, vehicle_factory):
    """The vehicle refuses to arm and says why while other messages keep coming (its start-up, a gimbal, a
    companion computer): the pilot is told the refusal's reason, not whatever was said last."""
    sim = sim_factory()
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.readiness.ready_to_arm, 15)
    sim.faults.refuse_arm = "Check fence"
    gimbal = mavlink.MAVLink(None, srcSystem=1, srcComponent=mavlink.MAV_COMP_ID_GIMBAL)
    stop = threading.Event()

    def chatter():
        n = 0
        while not stop.wait(0.02):                  # a stimulus, not a synchronisation: 50 lines a second
            n += 1
            sim.inject(mavlink.MAVLink_statustext_message(mavlink.MAV_SEVERITY_INFO, f"gimbal: {n}".encode())
                       .pack(gimbal))
    talker = threading.Thread(target=chatter, daemon=True)
    talker.start()
    try:
        result = vehicle.arm().result(timeout=10)
    finally:
        stop.set()
        talker.join(5)
    assert result.status is CommandStatus.REFUSED, str(result)
    assert "Check fence" in result.reason, result.reason
    assert not sim.truth().armed
