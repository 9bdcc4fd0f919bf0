"""Our Ice extension ``mavlinkserver::Vehicle``: each command answers with the driver's outcome, and the
simulated vehicle really does it."""
from __future__ import annotations

import math

from ice_fixtures import communicator, ice_server, jde, mavlinkserver, server_factory  # noqa: F401


def until(vehicle, sim, condition, timeout: float):
    """The simulated vehicle's truth once ``condition(truth)`` holds."""
    if vehicle.wait_for(lambda s: condition(sim.truth()), timeout) is None:
        return None
    return sim.truth()


def test_arm_refused_forced_refused_then_armed_and_disarmed(sim_factory, vehicle_factory, server_factory, communicator):
    sim = sim_factory(auto_disarm_after=0)          # only our commands change arming
    sim.faults.refuse_arm = "Check fence"
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    server = server_factory(vehicle)
    ext = mavlinkserver.VehiclePrx.checkedCast(communicator.stringToProxy(server.proxy("Vehicle")))
    assert vehicle.wait_for(lambda s: s.connected and s.readiness.gps_ok, 15)

    refused = ext.arm(False)
    assert (refused.command, refused.status) == ("arm", "REFUSED") and "Check fence" in refused.reason, refused
    assert not sim.truth().armed
    forced = ext.arm(True)                          # skipping the pre-arm checks is not for an Ice client
    assert (forced.command, forced.status) == ("arm (forced)", "REJECTED") and "pre-arm" in forced.reason, forced
    assert not sim.truth().armed
    sim.faults.refuse_arm = None                    # the fence fixed at the vehicle
    armed = ext.arm(False)
    assert armed.status == "ACCEPTED", armed
    assert sim.truth().armed
    disarmed = ext.disarm(False)
    assert (disarmed.command, disarmed.status) == ("disarm", "ACCEPTED"), disarmed
    assert not sim.truth().armed
    assert vehicle.wait_for(lambda s: not s.armed, 5)


def test_go_to_yaw_stop_disarm_and_return_to_launch(flying, sim, jde):
    ext = jde.Vehicle
    for name, value in (("RTL_ALT", 400), ("RTL_LOIT_TIME", 0)):   # a short return: 4 m up, no loiter
        assert flying.set_parameter(name, value).result(timeout=15).ok

    outcome = ext.goTo(6.0, -4.0, 5.0)
    assert outcome.status == "ACCEPTED", outcome
    there = until(flying, sim, lambda t: math.hypot(t.north - 6.0, t.east + 4.0) < 0.4
                  and abs(t.altitude - 5.0) < 0.3 and t.ground_speed < 0.2, 40)
    assert there is not None, sim.truth()

    outcome = ext.setYaw(225.0, False, 60.0)                       # an absolute heading: south-west
    assert outcome.status == "ACCEPTED", outcome
    turned = until(flying, sim, lambda t: abs(math.remainder(t.heading_deg - 225.0, 360.0)) < 2
                   and abs(t.yaw_rate) < 0.02, 30)
    assert turned is not None, sim.truth().heading_deg

    # on its way to a point 60 m north, Stop: the vehicle brakes and stays well short of it
    assert ext.goTo(60.0, -4.0, 5.0).status == "ACCEPTED"
    assert until(flying, sim, lambda t: t.ground_speed > 2.0, 20), sim.truth()
    outcome = ext.stop()
    assert outcome.status == "ACCEPTED", outcome
    stopped = until(flying, sim, lambda t: t.ground_speed < 0.1, 20)
    assert stopped is not None and stopped.mode == "GUIDED", sim.truth()
    assert stopped.north < 45.0, stopped
    later = until(flying, sim, lambda t: t.time > stopped.time + 2.0, 10)
    assert later is not None
    assert math.hypot(later.north - stopped.north, later.east - stopped.east) < 0.3, (stopped, later)

    outcome = ext.disarm(False)                                    # in the air: the flight rules say no
    assert outcome.status == "REJECTED" and "airborne" in outcome.reason, outcome
    assert sim.truth().armed and sim.truth().altitude > 4.0

    outcome = ext.returnToLaunch()
    assert outcome.status == "ACCEPTED", outcome
    assert sim.truth().mode == "RTL"
    home = until(flying, sim, lambda t: math.hypot(t.north, t.east) < 0.5 and t.ground_speed < 0.3, 40)
    assert home is not None and home.armed, sim.truth()
    landed = until(flying, sim, lambda t: not t.armed, 60)
    assert landed is not None and abs(landed.down) < 0.1 and landed.mode == "RTL", sim.truth()
