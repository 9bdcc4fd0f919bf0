"""The simulated ArduCopter's parameters against the real one: tests/data/recordings/arducopter-4.6-sitl-params.

The recording is parsed here, never transcribed: its list (names, types, count, order) and the answers it shows to
reads by index and by name, to an unknown name, and to sets (a float, an int8, an int8 sent as REAL32, an
out-of-range value, an unknown name)."""
from __future__ import annotations

import collections

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.sim import SimConfig
from driver.sim.autopilot import MODES, Autopilot
from driver.sim.params import SimParams
from recordings import PARAMS
from test_sim import GroundStation, airborne, wait_until  # noqa: F401
from test_sim_recordings import read_tlog

FAST = dict(speedup=10.0, ready_after=0.5)


@pytest.fixture(scope="module")
def recorded():
    """(the list: index -> (name, type, value), every PARAM_VALUE after the first list, what was sent)."""
    frames = read_tlog(PARAMS + ".tlog")
    listed, later = {}, []
    for _, m in frames:
        if m.get_type() == "PARAM_VALUE" and m.get_srcSystem() == 1:
            if m.param_index != 65535 and m.param_index not in listed:
                listed[m.param_index] = (m.param_id, m.param_type, m.param_value)
            else:
                later.append(m)
    return listed, later


@pytest.fixture
def gs(sim_factory):
    sim = sim_factory(**FAST)
    station = GroundStation(sim.tcp_port)
    yield station
    station.close()


def _values(gs, since, n, timeout=10):
    assert wait_until(lambda: len(gs.messages("PARAM_VALUE", since)) >= n, timeout), len(gs.messages("PARAM_VALUE", since))
    return gs.messages("PARAM_VALUE", since)


def test_the_table_is_arducopters_own(recorded):
    listed, _ = recorded
    table = SimParams()
    assert len(table) == len(listed) == 1392
    assert [(table.names[i], table.type_of(table.names[i])) for i in range(1392)] == \
        [(listed[i][0], listed[i][1]) for i in range(1392)]
    assert collections.Counter(t for _, t, _ in listed.values()) == collections.Counter(
        table.type_of(n) for n in table.names) == {2: 418, 4: 328, 6: 86, 9: 560}


def test_the_list_streams_every_parameter_with_its_type_and_the_banner(gs, recorded):
    listed, _ = recorded
    mark = gs.mark()
    gs.send(gs.encoder.param_request_list_encode(1, 1))
    got = _values(gs, mark, 1392)
    assert [(m.param_index, m.param_id, m.param_type, m.param_count) for m in got] == \
        [(i, listed[i][0], listed[i][1], 1392) for i in range(1392)]
    texts = [m.text for m in gs.messages("STATUSTEXT", mark)]
    assert any(t.startswith("ArduCopter V") for t in texts) and any(t.startswith("Frame:") for t in texts)
    by_name = {m.param_id: m.param_value for m in got}
    assert by_name["WPNAV_SPEED"] == 1000.0 and by_name["RTL_ALT"] == 1500 and by_name["FS_GCS_ENABLE"] == 0


def test_reads_by_index_and_by_name_answer_as_recorded_and_unknown_names_get_silence(gs):
    mark = gs.mark()
    for index in (0, 1, 1391):
        gs.send(gs.encoder.param_request_read_encode(1, 1, b"", index))
    gs.send(gs.encoder.param_request_read_encode(1, 1, b"FS_GCS_ENABLE", -1))
    got = _values(gs, mark, 4)
    assert [(m.param_id, m.param_index, m.param_type) for m in got] == [
        ("FORMAT_VERSION", 0, 4), ("SYSID_THISMAV", 1, 4), ("SERIAL7_OPTIONS", 1391, 4), ("FS_GCS_ENABLE", 65535, 2)]
    mark = gs.mark()
    gs.send(gs.encoder.param_request_read_encode(1, 1, b"NO_SUCH_PARAM", -1))
    gs.send(gs.encoder.param_request_read_encode(1, 1, b"", 1392))
    gs.send(gs.encoder.param_set_encode(1, 1, b"NO_SUCH_PARAM", 1.0, mavlink.MAV_PARAM_TYPE_REAL32))
    gs.send(gs.encoder.param_request_read_encode(1, 1, b"", 2))                  # a marker after them
    got = _values(gs, mark, 1)
    assert [m.param_id for m in got] == ["SYSID_MYGCS"]


def test_sets_are_obeyed_unchecked_in_the_true_type(gs, sim_factory, recorded):
    _, later = recorded
    echoes = {m.param_id: m for m in later}          # the recording's answers to its sets
    mark = gs.mark()
    sets = [(b"WPNAV_SPEED", 750.0, mavlink.MAV_PARAM_TYPE_REAL32),
            (b"FS_GCS_ENABLE", 1.0, mavlink.MAV_PARAM_TYPE_INT8),
            (b"FS_GCS_ENABLE", 1.0, mavlink.MAV_PARAM_TYPE_REAL32),        # an int8 sent as REAL32: obeyed
            (b"RTL_ALT", 1e9, mavlink.MAV_PARAM_TYPE_INT32)]                # out of range: stored
    for name, value, ptype in sets:
        gs.send(gs.encoder.param_set_encode(1, 1, name, value, ptype))
    got = _values(gs, mark, 4)
    for m in got:
        recorded_echo = echoes[m.param_id]
        assert (m.param_value, m.param_type, m.param_index, m.param_count) == (
            recorded_echo.param_value, recorded_echo.param_type, 65535, 1392)


def test_the_behaviour_reads_the_table(sim_factory):
    sim = sim_factory(**FAST)
    params = sim.autopilot.params
    assert params.get("WPNAV_SPEED") == 1000.0 and params.get("NO_SUCH_PARAM") is None
    params["FS_GCS_ENABLE"] = 1.7                    # an int8 holds 1, as AP_Param::set_float rounds
    assert params["FS_GCS_ENABLE"] == 1
    params["RTL_ALT"] = 1e12                         # int32: held in range
    assert params["RTL_ALT"] == 2 ** 31 - 1


def test_a_radio_streams_the_list_no_faster_than_its_bandwidth(sim_factory):
    sim = sim_factory(speedup=1.0, ready_after=0.5, radio_baud=57600)
    gs = GroundStation(sim.tcp_port)
    try:
        mark = gs.mark()
        start = sim.truth().time
        gs.send(gs.encoder.param_request_list_encode(1, 1))
        _values(gs, mark, 100)
        rate = 100 / (sim.truth().time - start)
        assert rate < 57600 / 10 / 37 * 1.1           # bytes a second over a PARAM_VALUE frame's 37 bytes
    finally:
        gs.close()


def test_the_gcs_failsafe_follows_fs_gcs_enable(flying, sim):
    """ArduCopter's failsafe_gcs_check: off by default; on, a silent ground station makes it RTL (GUIDED is an
    autopilot mode), and hearing it again clears the failsafe without changing the mode back."""
    sim.faults.uplink.loss = 1.0                                   # the ground station falls silent
    assert wait_until(lambda: sim.autopilot.t - sim.autopilot.gcs_seen > 6.0, 10)
    assert sim.truth().mode == "GUIDED" and not sim.autopilot.gcs_failsafe
    sim.faults.uplink.loss = 0.0
    assert flying.set_parameter("FS_GCS_ENABLE", 1).result(timeout=10).ok
    assert flying.set_parameter("WPNAV_SPEED", 750).result(timeout=10).ok
    assert sim.autopilot.wp_speed() == 7.5                       # the behaviour reads the table
    sim.faults.uplink.loss = 1.0
    assert wait_until(lambda: sim.truth().mode == "RTL", 10), sim.truth()
    sim.faults.uplink.loss = 0.0
    assert flying.wait_for(lambda s: any(m.text == "GCS Failsafe Cleared" for m in s.messages), 10)
    assert any(m.text == "GCS Failsafe" for m in flying.state().messages) and sim.truth().mode == "RTL"


def test_fs_options_lets_a_pilot_controlled_mode_carry_on(flying, sim):
    assert flying.set_parameter("FS_GCS_ENABLE", 1).result(timeout=10).ok
    assert flying.set_mode("LOITER").result(timeout=10).ok
    sim.faults.uplink.loss = 1.0
    assert wait_until(lambda: sim.autopilot.gcs_failsafe, 10)
    assert sim.truth().mode == "LOITER"                            # FS_OPTIONS 16 (the default): carry on
    sim.faults.uplink.loss = 0.0
    assert flying.wait_for(lambda s: any(m.text == "GCS Failsafe - Continuing Pilot Control" for m in s.messages), 10)


def test_a_gcs_failsafe_during_autos_landing_carries_on_landing_with_fs_options_8():
    """failsafe_gcs_on_event asks copter.flightmode->is_landing(): AUTO's land item is landing too."""
    sent = []
    ap = Autopilot(SimConfig(ready_after=0.0), emit=sent.append)
    ap.step(0.02)
    factory = mavlink.MAVLink(None, 255, 190)
    for cmd, *p in ((176, 1, 4), (400, 1), (22, 0, 0, 0, 0, 0, 0, 5)):
        msg = factory.command_long_encode(1, 1, cmd, 0, *(list(p) + [0] * (7 - len(p))))
        msg.pack(factory)
        ap.handle(msg)
    while ap.landed_state() != mavlink.MAV_LANDED_STATE_IN_AIR and ap.t < 30:
        ap.step(0.02)
    ap.mode, ap.auto_stage, ap.rtl_phase = MODES["AUTO"], "land", "land"    # as AUTO's NAV_LAND descends
    assert ap.landed_state() == mavlink.MAV_LANDED_STATE_LANDING
    ap.params["FS_GCS_ENABLE"], ap.params["FS_OPTIONS"] = 1, 8               # bit 3 only: continue landing
    ap._gcs_failsafe_action()
    texts = [m.text for m in sent if m.get_type() == "STATUSTEXT"]
    assert "GCS Failsafe - Continuing Landing" in texts and ap.mode == MODES["AUTO"]
