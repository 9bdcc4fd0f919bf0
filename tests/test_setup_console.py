"""The console's setup verbs (MAVProxy's words) on the real driver and the simulated vehicle."""
from __future__ import annotations

import io

from driver.console.console import Console

from ice_fixtures import eventually

T = 30


def ready(sim_factory, vehicle_factory, **options):
    sim = sim_factory(**options)
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert v.wait_for(lambda s: s.connected and s.readiness.prearm_ok and s.position is not None, T)
    out = io.StringIO()
    return sim, v, Console(v, stdout=out), out


def test_gyrocal_calpress_level_and_accelcal_with_enter(sim_factory, vehicle_factory):
    sim, v, console, out = ready(sim_factory, vehicle_factory, calibration_model=True)
    for verb, words in (("gyrocal", "gyro calibration: accepted"), ("calpress", "barometer calibration: accepted"),
                        ("level", "level calibration: accepted"),
                        ("accelcalsimple", "simple accel calibration: accepted")):
        console.onecmd(verb)
        assert eventually(lambda: words in out.getvalue(), T), out.getvalue()
    console.onecmd("accelcal")
    for name in ("level", "on its left side", "on its right side", "nose down", "nose up", "on its back"):
        assert eventually(lambda: f"Place vehicle {name} and press Enter" in out.getvalue(), T), out.getvalue()
        console.onecmd("")
    assert eventually(lambda: "accel calibration: accepted (Calibration successful)" in out.getvalue(), T), \
        out.getvalue()


def test_magcal_start_status_cancel_and_yaw(sim_factory, vehicle_factory):
    sim, v, console, out = ready(sim_factory, vehicle_factory)
    console.onecmd("magcal status")
    assert "magcal: not running" in out.getvalue()
    console.onecmd("magcal start")
    assert eventually(lambda: len(v.state().setup.compass.progress) == 3, T)
    console.onecmd("magcal status")
    assert "compass 0: 0 % (status 2, attempt 1)" in out.getvalue(), out.getvalue()
    console.onecmd("magcal cancel")
    assert eventually(lambda: "cancel compass calibration: accepted" in out.getvalue(), T), out.getvalue()
    console.onecmd("magcal yaw 353")
    assert eventually(lambda: "compass from yaw 353: accepted" in out.getvalue(), T), out.getvalue()
    console.onecmd("magcal frobnicate")
    assert "usage: magcal start|accept|cancel|status" in out.getvalue()


def test_motortest_rc_and_adsb(sim_factory, vehicle_factory):
    sim, v, console, out = ready(sim_factory, vehicle_factory, adsb=3)
    console.onecmd("rc")            # the first 'rc' asks for RC_CHANNELS and waits for it, as against real SITL
    assert "rc in  1:1500 2:1500 3:1000 4:1500 5:1800 6:1000 7:1000 8:1800" in out.getvalue(), out.getvalue()
    console.onecmd("motortest 1 0 20 1")           # without the word: refused, nothing sent
    assert "take the propellers off, then end the line with 'props-off' (motortest 1 0 20 1 props-off)" in \
        out.getvalue(), out.getvalue()
    assert not sim.autopilot.motor_testing and "motor test 1" not in out.getvalue()
    console.onecmd("motortest 1 0 20 1 props-off")
    assert eventually(lambda: "motor test 1: accepted" in out.getvalue(), T), out.getvalue()
    assert eventually(lambda: 1200 in v.state().setup.outputs.values, T)
    console.onecmd("motortest stop")
    assert eventually(lambda: "stop motor test: accepted" in out.getvalue(), T), out.getvalue()
    console.onecmd("motortest 1 2 20 1")
    assert "usage: motortest MOTOR TYPE VALUE SECONDS [COUNT]" in out.getvalue()
    assert eventually(lambda: len(v.state().traffic.contacts) >= 3, T)
    console.onecmd("adsb")
    assert "SIM" in out.getvalue() and " m at " in out.getvalue() and "m/s" in out.getvalue(), out.getvalue()


def test_rc_asks_the_channels_off_again_and_a_second_rc_shows_fresh_ones(sim_factory, vehicle_factory):
    sim, v, console, out = ready(sim_factory, vehicle_factory)
    console.onecmd("rc")
    assert "rc in  1:1500 2:1500 3:1000" in out.getvalue(), out.getvalue()
    assert eventually(lambda: "RC_CHANNELS" not in sim.autopilot.intervals, T)      # the stream is off again
    sim.autopilot.move_stick(1, 1700)
    console.onecmd("rc")                            # asks again and waits for a fresh one
    assert "rc in  1:1700 2:1500 3:1000" in out.getvalue(), out.getvalue()
    assert eventually(lambda: "RC_CHANNELS" not in sim.autopilot.intervals, T)
