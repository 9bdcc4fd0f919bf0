"""Calibrations end to end: the real driver over TCP against the simulated ArduCopter (both profiles), the
verdicts and reasons being the vehicle's own."""
from __future__ import annotations

import pytest

from driver.setup.model import AccelStep
from driver.vehicle.state import CommandStatus

from setup_fixtures import bench, texts  # noqa: F401

T = 30


def test_gyro_baro_and_level_answer_as_each_firmware_does(bench):
    sim, v = bench()
    assert v.setup.calibrate_gyro().result(T).status is CommandStatus.ACCEPTED
    baro = v.setup.calibrate_baro().result(T)
    assert baro.status is CommandStatus.ACCEPTED       # 4.x: IN_PROGRESS first, then ACCEPTED
    level = v.setup.calibrate_level().result(T)
    if bench.profile == "copter-4":
        assert level.status is CommandStatus.ACCEPTED
        assert v.wait_for(lambda s: any(m.text.startswith("Trim OK: roll=") for m in s.messages), T)
        assert "Barometer calibration complete" in texts(v)
    else:                                              # 3.3 has no level calibration by command
        assert level.status is CommandStatus.REFUSED and "FAILED" in level.reason


def confirm_each(cal, vehicle) -> list[int]:
    asked = []
    while not cal.verdict.done():
        state = vehicle.wait_for(lambda s: cal.verdict.done() or (s.setup.accel.step is AccelStep.WAITING
                                                                  and s.setup.accel.position not in asked), T)
        assert state is not None, "the vehicle stopped asking"
        if cal.verdict.done():
            break
        asked.append(state.setup.accel.position)
        assert cal.confirm_position().result(T).ok
    return asked


def solo_says_it_does_not_drive_its_accel_calibration(sim, v) -> bool:
    """3.3's six-position calibration asks by text and takes a bare COMMAND_ACK: refused here, with the reason,
    and nothing sent (the sim's 3.3 is not calibrating)."""
    if not v.state().firmware.startswith("3.3"):
        return False
    cal = v.setup.accel_calibration()
    result = cal.verdict.result(T)
    assert result.status is CommandStatus.REJECTED and "older way" in result.reason and cal.started.done()
    assert sim.autopilot.accel_step is None
    return True


def test_six_position_accel_calibration_succeeds_when_the_airframe_is_turned(bench):
    sim, v = bench(calibration_model=True)
    assert v.wait_for(lambda s: s.firmware, T)
    if solo_says_it_does_not_drive_its_accel_calibration(sim, v):
        return
    cal = v.setup.accel_calibration()
    assert cal.started.result(T).ok
    assert confirm_each(cal, v) == [1, 2, 3, 4, 5, 6]
    verdict = cal.verdict.result(T)
    assert verdict.status is CommandStatus.ACCEPTED and verdict.reason == "Calibration successful"
    assert v.state().setup.accel.step is AccelStep.SUCCESS
    if bench.profile == "copter-4":
        refused = v.arm().result(T)
        assert refused.status is CommandStatus.REFUSED and "Accels calibrated requires reboot" in refused.reason


def test_accel_calibration_fails_at_the_second_position_on_an_unturned_airframe_and_arming_is_refused(bench):
    sim, v = bench()
    assert v.wait_for(lambda s: s.firmware, T)
    if solo_says_it_does_not_drive_its_accel_calibration(sim, v):
        return
    cal = v.setup.accel_calibration()
    assert confirm_each(cal, v) == [1, 2]
    verdict = cal.verdict.result(T)
    assert verdict.status is CommandStatus.REFUSED and verdict.reason == "Calibration FAILED"
    assert v.set_mode("GUIDED").result(T).ok
    refused = v.arm().result(T)
    assert refused.status is CommandStatus.REFUSED and "3D Accel calibration needed" in refused.reason


def test_calibrations_while_armed_are_refused_before_they_go_out(bench):
    """No calibration starts while the vehicle is armed (the flight rules): the driver says why, and the vehicle
    never hears it (ArduPilot would refuse too, "Disarm to allow calibration", but a GCS does not lean on that)."""
    sim, v = bench()
    assert v.set_mode("GUIDED").result(T).ok and v.arm().result(T).ok
    calls = [v.setup.calibrate_gyro, v.setup.calibrate_baro, lambda: v.setup.compass_calibration().finished]
    if bench.profile == "copter-4":                    # 3.3's is not driven here (see above)
        calls.append(lambda: v.setup.accel_calibration().verdict)
    for result in (call().result(T) for call in calls):
        assert result.status is CommandStatus.REJECTED and "armed" in result.reason, result
    assert "CAL" not in sim.autopilot.last_command, sim.autopilot.last_command


def test_a_level_calibration_in_the_air_is_refused(flying, sim):
    result = flying.setup.calibrate_level().result(T)
    assert result.status is CommandStatus.REJECTED and "armed" in result.reason, result
    assert "CALIBRATION" not in sim.autopilot.last_command, sim.autopilot.last_command


def test_tumbled_compass_calibration_reports_every_compass_and_accept_writes_the_offsets(sim_factory,
                                                                                         vehicle_factory):
    sim = sim_factory(calibration_model=True, speedup=20.0)
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", command_timeout=0.5)
    assert v.wait_for(lambda s: s.connected and s.readiness.prearm_ok, T)
    cal = v.setup.compass_calibration()
    assert cal.started.result(T).ok
    assert v.wait_for(lambda s: len(s.setup.compass.progress) == 3, T)
    done = cal.finished.result(60)
    assert done.status is CommandStatus.ACCEPTED and "fitness 0.037" in done.reason
    reports = v.state().setup.compass.reports
    assert [r.compass for r in reports] == [0, 1, 2] and all(r.ok for r in reports)
    assert cal.accept().result(T).ok
    assert v.state().setup.compass.accepted
    assert sim.autopilot.params["COMPASS_OFS_X"] == pytest.approx(5.0, abs=0.01)
    assert sim.autopilot.params["COMPASS_OFS_Z"] == pytest.approx(-18.0, abs=0.01)


def test_unmoved_compass_calibration_stays_at_zero_and_a_cancel_needs_a_reboot(bench):
    sim, v = bench()
    cal = v.setup.compass_calibration()
    assert cal.started.result(T).ok
    state = v.wait_for(lambda s: len(s.setup.compass.progress) == 3, T)
    assert [p.percent for p in state.setup.compass.progress] == [0, 0, 0]
    assert cal.cancel().result(T).ok
    assert cal.finished.result(T).status is CommandStatus.ABORTED
    assert v.set_mode("GUIDED").result(T).ok
    refused = v.arm().result(T)
    assert refused.status is CommandStatus.REFUSED and "Compass calibrated requires reboot" in refused.reason


def test_compass_from_a_known_yaw_exists_on_4x_only(bench):
    sim, v = bench()
    result = v.setup.fixed_mag_yaw(353).result(T)
    if bench.profile == "copter-4":
        assert result.status is CommandStatus.ACCEPTED
    else:
        assert result.status is CommandStatus.REFUSED and "UNSUPPORTED" in result.reason
    assert v.setup.fixed_mag_yaw(float("nan")).result(T).status is CommandStatus.REJECTED


def test_the_previous_runs_repeated_verdict_does_not_settle_a_new_accel_calibration(sim_factory, vehicle_factory):
    """AP_AccelCal re-sends its last result every second until the next start: one sent before the vehicle read
    our new PREFLIGHT_CALIBRATION arrives while the new run is starting, and must not be taken as its verdict."""
    sim = sim_factory(calibration_model=True)
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", command_timeout=10.0)
    assert v.wait_for(lambda s: s.connected and s.readiness.prearm_ok, T)
    first = v.setup.accel_calibration()
    assert confirm_each(first, v) == [1, 2, 3, 4, 5, 6]
    assert first.verdict.result(T).status is CommandStatus.ACCEPTED
    sim.faults.uplink.latency = 2.0                  # real s: repeats of the old success cross our new start
    second = v.setup.accel_calibration()
    assert second.started.result(T).ok
    sim.faults.uplink.latency = 0.0
    state = v.wait_for(lambda s: s.setup.accel.step is AccelStep.WAITING, T)
    assert state.setup.accel.position == 1 and not second.verdict.done()


def test_accept_while_a_compass_still_runs_stops_every_calibrator_and_ends_the_run_with_the_vehicles_verdict(bench):
    """AP_Compass_Calibration.cpp _accept_calibration_mask: every calibrator is stopped, FAILED when one was not
    done; the run is over whatever the answer."""
    sim, v = bench()
    cal = v.setup.compass_calibration()
    assert cal.started.result(T).ok
    assert v.wait_for(lambda s: len(s.setup.compass.progress) == 3, T)
    refused = cal.accept().result(T)
    assert refused.status is CommandStatus.REFUSED
    assert cal.finished.result(T) == refused                       # the vehicle's verdict ends the run
    assert v.wait_for(lambda s: not s.setup.compass.running, T)
    assert sim.autopilot.mag_started is None                       # the vehicle stopped calibrating
    assert v.set_mode("GUIDED").result(T).ok
    refused = v.arm().result(T)
    assert refused.status is CommandStatus.REFUSED and "Compass calibrated requires reboot" in refused.reason


def test_a_second_compass_calibration_settles_the_first_as_superseded(bench):
    sim, v = bench()
    first = v.setup.compass_calibration()
    assert first.started.result(T).ok
    second = v.setup.compass_calibration()
    result = first.finished.result(T)
    assert result.status is CommandStatus.ABORTED and "superseded" in result.reason
    assert second.started.result(T).ok and not second.finished.done()
