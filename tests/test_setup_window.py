"""Issue 32, the viewer: Vehicle › Setup on the real simulated ArduCopter 4.6.3 — a calibration from its page to
the vehicle's verdict, the accelerometer's six positions with the simulator's calibration model, the motor test
refused without the propellers' tick and while armed, the outputs and channels moving live."""
from __future__ import annotations

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QMenu

from lockstep_fixtures import lockstep_window  # noqa: F401  (fixtures)
from viewer_fixtures import app_style, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)


@pytest.fixture
def bench_window(sim_factory, vehicle_factory, window_factory):
    def make(**sim_options):
        sim = sim_factory(**sim_options)
        vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
        assert vehicle.wait_for(lambda s: s.connected and s.readiness.prearm_ok, 30), "vehicle not ready"
        return sim, vehicle, window_factory(vehicle)
    return make


def read(s) -> bool:
    """Every parameter read and no download running: a table shown from the cache while the vehicle's own list
    is still being read is complete too, and the download ending later would bring back values from before a
    write the test makes."""
    return s.parameters.complete and not s.parameters.downloading


def open_setup(w, page: str):
    menu = w.findChild(QMenu, "menuVehicle")
    action = next(a for a in menu.actions() if a.objectName() == "actionSetup")
    action.trigger()
    return w.setup.dialog.turn_to(page)


def test_gyro_calibration_from_the_page_to_the_vehicles_verdict(qtbot, bench_window):
    _sim, _vehicle, w = bench_window()
    page = open_setup(w, "Sensors")
    qtbot.mouseClick(page.gyro, Qt.LeftButton)
    qtbot.waitUntil(lambda: "accepted" in page.result.text(), timeout=10000)
    assert page.result.text().startswith("gyro calibration: accepted")


def test_accel_six_positions_with_the_calibration_model(qtbot, bench_window):
    _sim, vehicle, w = bench_window(calibration_model=True, speedup=20.0)
    page = open_setup(w, "Sensors")
    qtbot.mouseClick(page.accel_start, Qt.LeftButton)
    drawn = []
    for position in range(1, 7):
        qtbot.waitUntil(lambda p=position: page.next.isEnabled() and page.pose.position == p, timeout=20000)
        assert f"Position {position} of 6" in page.asked.text()
        drawn.append(page.pose.position)
        qtbot.mouseClick(page.next, Qt.LeftButton)
    qtbot.waitUntil(lambda: "accel calibration" in page.result.text() and "…" not in page.result.text(),
                    timeout=20000)
    assert drawn == [1, 2, 3, 4, 5, 6]
    assert "accepted" in page.result.text() and "successful" in page.result.text()
    qtbot.waitUntil(lambda: "Calibration successful" in page.said.toPlainText(), timeout=5000)   # its own words


def test_motor_test_needs_the_tick_and_a_disarmed_vehicle_and_the_outputs_move(qtbot, bench_window):
    _sim, vehicle, w = bench_window()
    page = open_setup(w, "Motors")
    qtbot.waitUntil(lambda: "propellers" in page.reason.text().lower(), timeout=5000)
    assert not page.test.isEnabled()
    assert vehicle.arm().result(timeout=20).ok
    page.props_off.setChecked(True)
    qtbot.waitUntil(lambda: "armed" in page.reason.text(), timeout=5000)
    assert not page.test.isEnabled()
    assert vehicle.disarm().result(timeout=20).ok
    qtbot.waitUntil(page.test.isEnabled, timeout=10000)
    qtbot.waitUntil(lambda: page.outputs.value(1) is not None, timeout=10000)
    idle = page.outputs.value(1)
    page.throttle.setValue(30.0)
    page.seconds.setValue(5.0)
    assert not page.stop.isEnabled()                 # idle, a stop would start a test (motor_test.cpp)
    qtbot.mouseClick(page.test, Qt.LeftButton)
    qtbot.waitUntil(lambda: (page.outputs.value(1) or 0) > idle, timeout=10000)
    qtbot.waitUntil(page.stop.isEnabled, timeout=5000)
    qtbot.mouseClick(page.stop, Qt.LeftButton)
    qtbot.waitUntil(lambda: page.outputs.value(1) == idle, timeout=10000)
    qtbot.waitUntil(lambda: not page.stop.isEnabled(), timeout=10000)


def test_radio_bars_follow_the_transmitter(qtbot, bench_window):
    sim, _vehicle, w = bench_window()
    page = open_setup(w, "Radio")
    qtbot.waitUntil(lambda: page.channels.value(1) is not None, timeout=10000)
    sim.autopilot.move_stick(1, 1900)
    qtbot.waitUntil(lambda: page.channels.value(1) == 1900, timeout=10000)
    assert "channels received" in page.status.text()


def test_summary_says_each_area(qtbot, bench_window):
    _sim, vehicle, w = bench_window()
    page = open_setup(w, "Summary")
    assert vehicle.wait_for(lambda s: s.firmware, 10)
    qtbot.waitUntil(lambda: page.firmware.text().startswith(f"ArduCopter V{vehicle.state().firmware}, board: "),
                    timeout=10000)
    qtbot.waitUntil(lambda: page.verdict("Radio") == "done", timeout=10000)
    assert page.verdict("Motors") == "done"
    assert vehicle.arm().result(timeout=20).ok
    qtbot.waitUntil(lambda: page.verdict("Motors") == "not applicable", timeout=10000)


def test_radio_calibration_writes_only_moved_channels_after_the_review(qtbot, bench_window):
    sim, vehicle, w = bench_window()
    page = open_setup(w, "Radio")
    assert vehicle.wait_for(lambda s: read(s) and s.parameters.get("RC1_MIN") is not None, 30)
    qtbot.waitUntil(lambda: page.channels.value(1) is not None, timeout=10000)
    qtbot.mouseClick(page.start, Qt.LeftButton)
    for pwm in (1100, 1900, 1520):
        sim.autopilot.move_stick(1, pwm)
        qtbot.waitUntil(lambda p=pwm: page.channels.value(1) == p, timeout=10000)
    qtbot.mouseClick(page.finish, Qt.LeftButton)
    plan = page.plan.toPlainText()
    assert "RC1_MIN 1100, RC1_MAX 1900, RC1_TRIM 1520" in plan
    assert "RC2: never moved" in plan and "not written" in plan
    qtbot.mouseClick(page.write, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.params.review is not None and w.params.review.isVisible(), timeout=5000)
    assert set(w.params.model.pending) == {"RC1_MIN", "RC1_MAX", "RC1_TRIM"}     # nothing of RC2..
    assert vehicle.state().parameters.get("RC1_MIN").value == 1000                  # not before Write
    qtbot.mouseClick(w.params.review.write_button, Qt.LeftButton)
    assert vehicle.wait_for(lambda s: s.parameters.get("RC1_MIN").value == 1100
                            and s.parameters.get("RC1_MAX").value == 1900
                            and s.parameters.get("RC1_TRIM").value == 1520, 15)   # the vehicle's echo
    assert sim.autopilot.params["RC1_MIN"] == 1100


def test_flight_modes_light_the_switch_slot_and_write_through_the_review(qtbot, bench_window):
    sim, vehicle, w = bench_window()
    page = open_setup(w, "Flight modes")
    assert vehicle.wait_for(lambda s: read(s), 30)
    qtbot.waitUntil(lambda: page.modes[0].currentText() == "CIRCLE", timeout=5000)     # FLTMODE1 7 in the sim
    sim.autopilot.move_stick(5, 1300)                                                   # FLTMODE_CH 5
    qtbot.waitUntil(lambda: page.lit == 2, timeout=10000)
    sim.autopilot.move_stick(5, 1800)
    qtbot.waitUntil(lambda: page.lit == 6, timeout=10000)
    page.modes[5].setCurrentIndex(page.modes[5].findText("LOITER"))
    page.simple[1].setChecked(True)
    qtbot.mouseClick(page.write, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.params.review is not None and w.params.review.isVisible(), timeout=5000)
    assert w.params.model.pending == {"FLTMODE6": 5.0, "SIMPLE": 2.0}
    qtbot.mouseClick(w.params.review.write_button, Qt.LeftButton)
    assert vehicle.wait_for(lambda s: s.parameters.get("FLTMODE6").value == 5
                            and s.parameters.get("SIMPLE").value == 2, 15)


def test_frame_is_drawn_and_a_change_asks_for_a_reboot(qtbot, bench_window):
    _sim, vehicle, w = bench_window()
    page = open_setup(w, "Frame")
    assert vehicle.wait_for(lambda s: read(s), 30)
    qtbot.waitUntil(lambda: page.drawing.frame == (1, 1), timeout=5000)       # the sim: "Frame: QUAD/X"
    assert [m.test for m in page.drawing.motors] == [1, 3, 4, 2]                 # AP_MotorsMatrix's test order
    assert not page.reboot.isVisible()
    page.frame_type.setCurrentIndex(page.frame_type.findData(0))
    qtbot.mouseClick(page.write, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.params.review is not None and w.params.review.isVisible(), timeout=5000)
    assert w.params.model.pending == {"FRAME_TYPE": 0.0}
    qtbot.mouseClick(w.params.review.write_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: page.drawing.frame == (1, 0) and page.reboot.isVisible(), timeout=15000)
    assert [m.test for m in page.drawing.motors] == [2, 4, 1, 3]
    assert "reboot" in page.status.text()


def test_power_voltage_calibration_scales_the_multiplier_through_the_review(qtbot, bench_window):
    _sim, vehicle, w = bench_window()
    page = open_setup(w, "Power")
    assert vehicle.wait_for(lambda s: read(s) and s.battery.voltage, 30)
    qtbot.waitUntil(lambda: "BATT_MONITOR 4" in page.info.text(), timeout=5000)
    page.measured_volts.setValue(12.0)
    qtbot.mouseClick(page.volts, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.params.review is not None and w.params.review.isVisible(), timeout=5000)
    reported = float(page.status.text().split("the vehicle reads ")[1].split(",")[0])
    proposed = w.params.model.pending["BATT_VOLT_MULT"]
    assert proposed == pytest.approx(10.1 * 12.0 / reported, rel=1e-3)
    assert vehicle.state().parameters.get("BATT_VOLT_MULT").value == pytest.approx(10.1)      # not before Write
    qtbot.mouseClick(w.params.review.write_button, Qt.LeftButton)
    assert vehicle.wait_for(lambda s: s.parameters.get("BATT_VOLT_MULT").value == pytest.approx(proposed), 15)


def test_failsafes_in_words_and_a_warning_when_none_is_left(qtbot, bench_window):
    _sim, vehicle, w = bench_window()
    page = open_setup(w, "Failsafes")
    assert vehicle.wait_for(lambda s: read(s), 30)
    qtbot.waitUntil(lambda: page.lines.topLevelItemCount() == 6
                    and "not read" not in page.lines.topLevelItem(2).text(1), timeout=5000)
    words = {page.lines.topLevelItem(i).text(0): page.lines.topLevelItem(i).text(1) for i in range(6)}
    assert words["Radio lost"].startswith("returns home (RTL) (FS_THR_ENABLE 1")
    assert words["Fence"].startswith("off")
    assert "No battery failsafe action" in page.warnings.text()
    assert "Neither the radio" not in page.warnings.text()
    assert vehicle.set_parameter("FS_THR_ENABLE", 0).result(timeout=15).ok
    qtbot.waitUntil(lambda: "Neither the radio nor the ground-station failsafe" in page.warnings.text(), timeout=5000)


def test_compass_progress_per_compass_fitness_and_accept(qtbot, bench_window):
    _sim, _vehicle, w = bench_window(calibration_model=True, speedup=20.0)
    page = open_setup(w, "Sensors")
    assert not page.compass_accept.isEnabled()
    qtbot.mouseClick(page.compass_start, Qt.LeftButton)
    qtbot.waitUntil(lambda: bool(page.compass_bars) and any(0 < bar.value() < 100 for bar, _ in page.compass_bars.values()),
                    timeout=30000)
    qtbot.waitUntil(lambda: "compass calibration: accepted" in page.result.text(), timeout=60000)
    qtbot.waitUntil(lambda: all(bar.value() == 100 and words.text().startswith("fitness ")
                                for bar, words in page.compass_bars.values()) and page.compass_accept.isEnabled(),
                    timeout=5000)
    qtbot.mouseClick(page.compass_accept, Qt.LeftButton)
    qtbot.waitUntil(lambda: page.result.text().startswith("accept compass calibration: accepted"), timeout=10000)
    qtbot.waitUntil(lambda: not page.compass_accept.isEnabled(), timeout=5000)


def test_a_calibration_refused_while_armed_says_why(qtbot, bench_window):
    _sim, vehicle, w = bench_window()
    page = open_setup(w, "Sensors")
    assert vehicle.arm().result(timeout=20).ok
    qtbot.waitUntil(lambda: page.notes.text().startswith("Armed: the vehicle refuses calibrations"), timeout=5000)
    qtbot.mouseClick(page.gyro, Qt.LeftButton)
    qtbot.waitUntil(lambda: "refused" in page.result.text() or "rejected" in page.result.text(), timeout=10000)
    assert "armed" in page.result.text() and "disarm" in page.result.text(), page.result.text()


def test_the_solos_33_says_what_it_lacks(qtbot, sim_factory, vehicle_factory, window_factory):
    sim = sim_factory(profile="solo")
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.connected and s.firmware.startswith("3.3"), 30)
    w = window_factory(vehicle)
    page = open_setup(w, "Sensors")
    qtbot.waitUntil(lambda: "does not handle a level calibration" in page.notes.text(), timeout=5000)
    assert "no compass calibration from a known yaw" in page.notes.text()
    assert "six-position accelerometer calibration the older way" in page.notes.text()
    assert not page.level.isEnabled() and not page.simple.isEnabled() and not page.fixed_yaw.isEnabled()
    assert page.gyro.isEnabled() and not page.accel_start.isEnabled()
    summary = w.setup.dialog.turn_to("Summary")
    qtbot.waitUntil(lambda: summary.verdict("Traffic (ADS-B)") == "not applicable", timeout=5000)


def test_all_motors_in_sequence_each_output_spins(qtbot, lockstep_window):
    """In lockstep the window is shown every SERVO_OUTPUT_RAW the driver reads: each motor's turn is seen however
    loaded the machine is (over a socket, a starved window could poll past a motor's two seconds)."""
    steps = lockstep_window()
    vehicle, w = steps.vehicle, steps.window
    page = open_setup(w, "Motors")
    steps.until(lambda: read(vehicle.state()) and len(vehicle.state().setup.outputs.values) >= 4
                and vehicle.state().readiness.prearm_ok, 30, "parameters, outputs and readiness")
    idle = vehicle.state().setup.outputs.values[:4]
    raised: set[int] = set()
    w.adapter.stateChanged.connect(lambda s: raised.update(
        i + 1 for i, us in enumerate(s.setup.outputs.values[:4]) if us > idle[i]))
    page.props_off.setChecked(True)
    page.all.setChecked(True)
    page.seconds.setValue(2.0)             # several SERVO_OUTPUT_RAW (10 Hz) per motor
    steps.until(page.test.isEnabled, 5, "the Test button")
    qtbot.mouseClick(page.test, Qt.LeftButton)
    steps.until(lambda: raised == {1, 2, 3, 4}, 20, "each motor spun")
    steps.until(lambda: page.result.text().startswith("motor test 1: accepted"), 2, "the answer shown")


def test_compass_accept_waits_until_no_compass_is_still_in_progress(qtbot, bench_window):
    """ArduPilot's accept stops every calibrator and fails when one still runs: Accept is offered only once every
    compass has reported."""
    from dataclasses import replace

    from driver.setup.model import CompassCalState, CompassProgress, CompassReport

    _sim, vehicle, w = bench_window()
    page = open_setup(w, "Sensors")
    state = vehicle.state()
    report = CompassReport(0, 4, 0.037, (5.0, 13.0, -18.0), False)
    still = CompassCalState(running=True, progress=(CompassProgress(1, 75, 3, 1), CompassProgress(2, 75, 3, 1)),
                            reports=(report,))
    w.setup.dialog.hide()                          # only this snapshot reaches the page
    page.show_state(replace(state, setup=replace(state.setup, compass=still)))
    assert not page.compass_accept.isEnabled()
    page.show_state(replace(state, setup=replace(state.setup, compass=replace(still, progress=(), reports=(
        report, replace(report, compass=1), replace(report, compass=2))))))
    assert page.compass_accept.isEnabled()


def test_a_late_answer_after_the_vehicle_changed_is_dropped_and_the_app_goes_on(qtbot, caplog, sim_factory,
                                                                                 vehicle_factory, window_factory):
    """The pages of the old vehicle are deleted when another is picked; a calibration's answer arriving after
    that must not reach them ("wrapped C/C++ object has been deleted" in a slot aborts the app)."""
    from PyQt5 import sip

    sims = [sim_factory(), sim_factory()]
    vehicles = [vehicle_factory(f"tcp:127.0.0.1:{s.tcp_port}") for s in sims]
    for v in vehicles:
        assert v.wait_for(lambda s: s.connected and s.readiness.prearm_ok, 30), "vehicle not ready"
    w = window_factory(vehicles[0])
    page = open_setup(w, "Sensors")
    sims[0].faults.uplink.latency = 1.0              # real s: the answer comes after the pages are gone
    qtbot.mouseClick(page.gyro, Qt.LeftButton)
    w.adapter.use(vehicles[1])
    qtbot.waitUntil(lambda: sip.isdeleted(page), timeout=5000)
    qtbot.waitUntil(lambda: "dropped the answer of gyro" in caplog.text, timeout=15000)
    assert any(r.command == "gyro calibration" and r.ok for r in vehicles[0].state().results)
    fresh = w.setup.dialog.pages["Sensors"]          # the new vehicle's pages work
    qtbot.mouseClick(fresh.gyro, Qt.LeftButton)
    qtbot.waitUntil(lambda: "accepted" in fresh.result.text(), timeout=10000)


def test_the_rc_stream_is_asked_off_on_pages_without_it_and_when_the_window_closes(qtbot, bench_window):
    sim, _vehicle, w = bench_window()
    page = open_setup(w, "Radio")
    qtbot.waitUntil(lambda: page.channels.value(1) is not None, timeout=10000)
    assert "RC_CHANNELS" in sim.autopilot.intervals
    w.setup.dialog.turn_to("Sensors")
    qtbot.waitUntil(lambda: "RC_CHANNELS" not in sim.autopilot.intervals, timeout=10000)
    w.setup.dialog.turn_to("Flight modes")
    qtbot.waitUntil(lambda: "RC_CHANNELS" in sim.autopilot.intervals, timeout=10000)
    w.setup.dialog.close()
    qtbot.waitUntil(lambda: "RC_CHANNELS" not in sim.autopilot.intervals, timeout=10000)


def test_radio_calibration_takes_the_throttle_from_rcmap_throttle(qtbot, bench_window):
    """A transmitter with the throttle on channel 1 (RCMAP_THROTTLE 1) has its pitch on 3: channel 3's trim is
    its centre, channel 1's its lowest."""
    sim, vehicle, w = bench_window()
    page = open_setup(w, "Radio")
    assert vehicle.wait_for(lambda s: read(s) and s.parameters.get("RCMAP_THROTTLE") is not None, 30)
    assert vehicle.set_parameter("RCMAP_THROTTLE", 1).result(timeout=15).ok
    assert vehicle.set_parameter("RCMAP_PITCH", 3).result(timeout=15).ok
    qtbot.waitUntil(lambda: page.channels.value(1) is not None, timeout=10000)
    qtbot.mouseClick(page.start, Qt.LeftButton)
    for channel, pwms in ((1, (1900, 1100)), (3, (1100, 1900, 1500))):
        for pwm in pwms:
            sim.autopilot.move_stick(channel, pwm)
            qtbot.waitUntil(lambda c=channel, p=pwm: page.channels.value(c) == p, timeout=10000)
    qtbot.mouseClick(page.finish, Qt.LeftButton)
    plan = page.plan.toPlainText()
    assert "RC3_MIN 1000, RC3_MAX 1900, RC3_TRIM 1500" in plan, plan     # 1000: where the sim starts it
    assert "RC1_MIN 1100, RC1_MAX 1900, RC1_TRIM 1100" in plan, plan


def test_next_comes_back_after_a_position_confirm_that_got_no_answer(qtbot, bench_window):
    sim, _vehicle, w = bench_window(calibration_model=True)
    page = open_setup(w, "Sensors")
    qtbot.mouseClick(page.accel_start, Qt.LeftButton)
    qtbot.waitUntil(lambda: page.next.isEnabled() and page.pose.position == 1, timeout=20000)
    sim.faults.uplink.loss = 1.0                     # the confirm never reaches the vehicle
    qtbot.mouseClick(page.next, Qt.LeftButton)
    assert not page.next.isEnabled()
    qtbot.waitUntil(lambda: page.result.text().startswith("accel position"), timeout=20000)
    sim.faults.uplink.loss = 0.0
    qtbot.waitUntil(page.next.isEnabled, timeout=5000)   # the vehicle still asks for position 1
    qtbot.mouseClick(page.next, Qt.LeftButton)
    qtbot.waitUntil(lambda: page.next.isEnabled() and page.pose.position == 2, timeout=20000)


def test_the_mode_switch_slots_at_arducopters_edges():
    """RC_Channel::read_6pos_switch: below 1231, 1361, 1491, 1621, 1750; at or past 800 / 2200 no position."""
    from uavviewer.setup.modes_page import slot_of

    edges = {800: None, 801: 1, 1230: 1, 1231: 2, 1360: 2, 1361: 3, 1490: 3, 1491: 4, 1620: 4, 1621: 5,
             1749: 5, 1750: 6, 2199: 6, 2200: None, 0: None, None: None}
    assert {pwm: slot_of(pwm) for pwm in edges} == edges


def test_change_in_parameters_opens_the_rows_own_parameter(qtbot, bench_window):
    """The "Battery critical" row ends "(no voltage set: BATT_CRT_VOLT 0)": its parameter is BATT_FS_CRT_ACT,
    kept with the row, not read back from its words."""
    from PyQt5.QtWidgets import QPushButton

    _sim, vehicle, w = bench_window()
    page = open_setup(w, "Failsafes")
    assert vehicle.wait_for(lambda s: read(s), 30)
    qtbot.waitUntil(lambda: page.lines.topLevelItemCount() == 6
                    and "BATT_CRT_VOLT 0" in page.lines.topLevelItem(1).text(1), timeout=5000)
    change = next(b for b in page.findChildren(QPushButton) if b.text().startswith("Change in Parameters"))
    for row, name in ((1, "BATT_FS_CRT_ACT"), (4, "FS_EKF_ACTION"), (5, "FENCE_ENABLE")):
        page.lines.setCurrentItem(page.lines.topLevelItem(row))
        qtbot.mouseClick(change, Qt.LeftButton)
        qtbot.waitUntil(lambda n=name: w.params.page is not None and w.params.page.current_name() == n,
                        timeout=5000)
