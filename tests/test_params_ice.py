"""The parameters over Ice: list, get and set in the mavlinkserver.ice extension, and the IceDrone client
providing the same Drone methods as the embedded driver."""
from __future__ import annotations

from driver.params.model import ParamType
from driver.vehicle.state import CommandStatus

from ice_fixtures import drone_factory, eventually, ice_server, server_factory, mavlinkserver  # noqa: F401


def test_list_get_and_set_through_the_client(vehicle, sim, ice_server, drone_factory):
    drone = drone_factory(ice_server)
    assert drone.wait_for(lambda s: s.connected, 10)
    assert drone.fetch_parameters().result(timeout=30).ok
    # the answer can come before the state that shows it over Ice; a table kept in the cache is complete while it is
    # still read again (its indexes come with the vehicle's list), so: complete, and no longer downloading
    s = drone.wait_for(lambda s: s.parameters.complete and not s.parameters.downloading, 10)
    assert s is not None and s.parameters.received == 1392
    assert s.parameters.get("FS_GCS_ENABLE").type is ParamType.INT8
    assert s.parameters.get("RTL_ALT").index == sim.autopilot.params.index_of("RTL_ALT")
    result = drone.set_parameter("WPNAV_SPEED", 800).result(timeout=15)
    assert result.ok and result.command == "param WPNAV_SPEED=800", result
    assert sim.autopilot.params["WPNAV_SPEED"] == 800.0
    assert drone.wait_for(lambda s: s.parameters.get("WPNAV_SPEED").value == 800.0, 5)
    refused = drone.set_parameter("RTL_ALT", 1e9).result(timeout=15)
    assert refused.status is CommandStatus.REJECTED and "outside 200 to 300000 cm" in refused.reason
    assert drone.set_parameter("RTL_ALT", 1e9, allow_out_of_bounds=True).result(timeout=15).ok
    assert sim.autopilot.params["RTL_ALT"] == 1_000_000_000
    unknown = drone.set_parameter("NO_SUCH_PARAM", 1).result(timeout=20)
    assert unknown.status is CommandStatus.TIMED_OUT and "no parameter NO_SUCH_PARAM" in unknown.reason
    assert drone.parameter_metadata.get("WPNAV_SPEED").units == "cm/s"


def test_get_by_pattern_and_only_the_summary_when_nothing_changed(vehicle, ice_server, drone_factory):
    assert vehicle.fetch_parameters().result(timeout=30).ok
    import Ice
    com = Ice.initialize()
    try:
        prx = mavlinkserver.VehiclePrx.checkedCast(com.stringToProxy(
            ice_server.client_properties()["UAVViewer.Vehicle.Proxy"]))
        one = prx.getParameters("rtl_alt", -1)
        assert [(p.name, p.type) for p in one.params] == [("RTL_ALT", 6)] and one.expected == 1392
        group = prx.getParameters("FENCE_*", -1)
        assert len(group.params) > 4 and all(p.name.startswith("FENCE_") for p in group.params)
        again = prx.getParameters("*", one.revision)
        assert again.params == [] and again.revision == one.revision and not again.downloading
    finally:
        com.destroy()
