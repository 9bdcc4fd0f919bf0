"""Reading every parameter through the driver: the whole list, then re-asking what the radio lost."""
from __future__ import annotations

import os

import pytest

from driver.params.cache import ParameterCache
from driver.params.model import ParamType
from driver.vehicle.state import CommandStatus

from ice_fixtures import eventually


def _same_as_sim(table, sim) -> None:
    """Every parameter as the vehicle holds it (SRn_ rates aside: REQUEST_DATA_STREAM rewrites them without a
    PARAM_VALUE, in ArduPilot as in the sim)."""
    params = sim.autopilot.params
    assert table.complete and table.expected == len(params) == 1392
    for name in params.names:
        p = table.get(name)
        assert p is not None, name
        assert (p.type, p.index) == (ParamType(params.type_of(name)), params.index_of(name)), name
        if name.startswith("SR0_"):
            continue
        assert abs(p.value - params[name]) <= 1e-6 * max(1.0, abs(params[name])), (name, p.value, params[name])


@pytest.fixture
def listing(sim, vehicle_factory):
    """The driver reading the classic list (PARAM_REQUEST_LIST), not the FTP file."""
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", param_ftp=False)
    assert v.wait_for(lambda s: s.connected, 10)
    return v


def test_a_clean_link_brings_the_whole_list_into_the_state(listing, sim):
    vehicle = listing
    result = vehicle.fetch_parameters().result(timeout=30)
    assert result.status is CommandStatus.ACCEPTED, result
    table = vehicle.state().parameters
    _same_as_sim(table, sim)
    assert not table.downloading and table.detail == ""
    assert table.get("FS_GCS_ENABLE").type is ParamType.INT8 and table.get("RTL_ALT").type is ParamType.INT32
    again = vehicle.fetch_parameters().result(timeout=5)                     # complete: answered at once
    assert again.ok and "already complete" in again.reason


def test_thirty_percent_loss_each_way_still_ends_with_every_parameter(listing, sim):
    vehicle = listing
    sim.faults.uplink.loss = sim.faults.downlink.loss = 0.3
    seen = []
    future = vehicle.fetch_parameters(refresh=True)
    while not future.done():                                              # progress while it runs
        s = vehicle.wait_for(lambda s: s.parameters.downloading, 1)
        if s is not None:
            seen.append(s.parameters.detail)
        if len(seen) > 3:
            break
    result = future.result(timeout=90)
    assert result.status is CommandStatus.ACCEPTED, result
    assert "asked again by index" in result.reason
    assert any(d for d in seen)
    sim.faults.uplink.loss = sim.faults.downlink.loss = 0.0
    _same_as_sim(vehicle.state().parameters, sim)


def test_a_lost_link_ends_the_download_and_the_next_asks_only_for_what_is_missing(vehicle_factory, sim_factory):
    sim = sim_factory(radio_baud=57600)                      # about 155 a second (x4 sped up): time to cut it
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", loss_timeout=1.0, param_ftp=False)
    assert vehicle.wait_for(lambda s: s.connected, 10)
    future = vehicle.fetch_parameters()
    assert vehicle.wait_for(lambda s: s.parameters.received > 100, 20)
    sim.faults.link_down = True
    result = future.result(timeout=20)
    assert result.status is CommandStatus.TIMED_OUT and "link lost" in result.reason, result
    partial = vehicle.state().parameters
    assert 100 < partial.received < 1392 and not partial.complete and "link lost" in partial.detail
    sim.faults.link_down = False
    assert vehicle.wait_for(lambda s: s.connected, 10)
    lists_before = sum(1 for _, kind, _ in sim.received_messages if kind == "PARAM_REQUEST_LIST")
    result = vehicle.fetch_parameters().result(timeout=60)
    assert result.ok, result
    assert sum(1 for _, kind, _ in sim.received_messages if kind == "PARAM_REQUEST_LIST") == lists_before
    _same_as_sim(vehicle.state().parameters, sim)


def test_a_known_vehicle_shows_its_cached_table_at_once_and_names_what_changed(sim, vehicle_factory, tmp_path):
    folder = str(tmp_path / "params")
    url = f"tcp:127.0.0.1:{sim.tcp_port}"
    first = vehicle_factory(url, param_cache=folder)
    assert first.wait_for(lambda s: s.connected and s.firmware, 10)
    assert first.fetch_parameters().result(timeout=30).ok
    saved = ParameterCache(folder).path(1, first.state().firmware)
    assert eventually(lambda: os.path.exists(saved), 5)                  # written off the reader's lock
    first.close()
    # changed meanwhile (another station); RTL_LOIT_TIME is not one of the few read by name at connect
    sim.autopilot.params["RTL_LOIT_TIME"] = 7000
    again = vehicle_factory(url, param_cache=folder)
    s = again.wait_for(lambda s: s.connected and s.firmware, 10)
    future = again.fetch_parameters()                                    # the cache is read off this thread
    shown = again.wait_for(lambda s: "from the cache" in s.parameters.detail, 10).parameters
    assert shown.received == 1392 and shown.downloading and "from the cache" in shown.detail
    assert shown.get("RTL_LOIT_TIME").value == 5000                       # what it was: not checked yet
    assert future.result(timeout=30).ok
    assert again.state().parameters.get("RTL_LOIT_TIME").value == 7000
    assert any("1 changed since this vehicle was last seen: RTL_LOIT_TIME" in m.text for m in again.state().messages)
    other = vehicle_factory(url, param_cache=folder)                       # refresh: the cache is not shown
    assert other.wait_for(lambda s: s.connected and s.firmware, 10)
    other.fetch_parameters(refresh=True)
    assert "from the cache" not in other.state().parameters.detail
    assert s.system_id == 1


def test_over_ftp_the_whole_table_comes_as_one_file(sim, vehicle_factory):
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.connected and s.firmware, 10)     # AUTOPILOT_VERSION offers FTP
    sim.faults.uplink.loss = sim.faults.downlink.loss = 0.3
    result = vehicle.fetch_parameters(refresh=True).result(timeout=60)
    assert result.ok and "over MAVLink FTP" in result.reason, result
    assert not any(kind == "PARAM_REQUEST_LIST" for _, kind, _ in sim.received_messages)
    sim.faults.uplink.loss = sim.faults.downlink.loss = 0.0
    _same_as_sim(vehicle.state().parameters, sim)


def test_a_vehicle_whose_ftp_does_not_answer_gets_the_list(sim, vehicle_factory):
    sim.autopilot._on_file_transfer_protocol = lambda msg: None             # advertised, but silent
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.connected and s.firmware, 10)
    seen = []
    future = vehicle.fetch_parameters()
    while not future.done() and len(seen) < 200:
        s = vehicle.wait_for(lambda s: s.parameters.detail not in seen[-1:], 1)
        if s is not None:
            seen.append(s.parameters.detail)
    result = future.result(timeout=30)
    assert result.ok and "over MAVLink FTP" not in result.reason, result
    assert any("no answer to the open" in d and "reading the list" in d for d in seen), seen
    _same_as_sim(vehicle.state().parameters, sim)


def test_a_few_lost_heartbeats_pause_the_download_instead_of_ending_it(sim_factory, vehicle_factory):
    sim = sim_factory(radio_baud=57600)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", loss_timeout=1.0, param_ftp=False)
    assert vehicle.wait_for(lambda s: s.connected, 10)
    future = vehicle.fetch_parameters()
    assert vehicle.wait_for(lambda s: s.parameters.received > 100, 20)
    sim.faults.outage(1.5)                              # lost for about half a second: under two loss timeouts
    assert vehicle.wait_for(lambda s: not s.connected, 5)
    result = future.result(timeout=60)
    assert result.ok, result
    _same_as_sim(vehicle.state().parameters, sim)
