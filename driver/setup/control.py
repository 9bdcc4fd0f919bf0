"""Vehicle setup on the bench (``vehicle.setup``): calibrations, the motor test, the radio and the outputs, and
the ADS-B traffic the autopilot forwards.

How ArduCopter runs each (tests/data/recordings/arducopter-4.6-sitl-setup and -calib):

* gyro, baro, level: one PREFLIGHT_CALIBRATION each; the baro's first ACK is IN_PROGRESS (the command sender
  waits for the final one); the verdict is the ACK, the reason the vehicle's STATUSTEXT;
* accelerometer: PREFLIGHT_CALIBRATION p5=1, then the vehicle *asks* with COMMAND_LONG ACCELCAL_VEHICLE_POS
  (1..6) and the pilot confirms each with the same command; 16777215 is success, 16777216 failure
  (:class:`AccelCalibration`);
* compass: DO_START_MAG_CAL, MAG_CAL_PROGRESS per compass, MAG_CAL_REPORT, DO_ACCEPT_MAG_CAL or
  DO_CANCEL_MAG_CAL (:class:`CompassCalibration`); FIXED_MAG_CAL_YAW from a known heading;
* motor test: DO_MOTOR_TEST. The vehicle accepts it even armed (recorded): here it is refused unless the
  vehicle is disarmed and on the ground and the pilot said the propellers are off. It runs from the vehicle's
  ACCEPTED until it says "finished motor test" (4.x) or disarms (the test armed it; 3.3 says nothing), with
  motor_test.cpp's duration as a bound (:func:`motor_test_bound`).

Methods marked "(lock held)" run on the driver's reader or ticker with the state lock held; the rest may be
called from any thread and never wait on the network.
"""
from __future__ import annotations

import logging
import math
import threading
import time
from concurrent.futures import Future
from dataclasses import replace

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core.results import CommandResult, CommandStatus, Severity, chain
from ..traffic.approach import AlertLimits
from ..traffic.tracker import TrafficTracker
from .availability import unavailable, version
from .model import (
    ACCEL_FAILED, ACCEL_POSITIONS, ACCEL_SUCCESS, AccelCalState, AccelStep, CompassCalState, CompassProgress,
    CompassReport, RcChannels, ServoOutputs,
)

log = logging.getLogger(__name__)

__all__ = ["VehicleSetup", "AccelCalibration", "CompassCalibration", "SETUP_MESSAGES"]

SETUP_MESSAGES = ("RC_CHANNELS", "RC_CHANNELS_RAW", "SERVO_OUTPUT_RAW", "MAG_CAL_PROGRESS", "MAG_CAL_REPORT",
                  "COMMAND_LONG", "ADSB_VEHICLE")
RADIO_RATE_HZ = 10                 # RC_CHANNELS and SERVO_OUTPUT_RAW while a setup page watches
MOTOR_TEST_RATE_HZ = 25            # ... while a motor test runs: its first output change within 200 ms of the command
                                   # (at 10 Hz bench_setup saw it at 100 ms median but 201 ms worst); back to 10 after
TRAFFIC_REFRESH = 0.5              # s between traffic snapshots (ages, fading, alerts)
MOTOR_TEST_MAX_SECONDS = 600.0     # ArduCopter's MOTOR_TEST_TIMEOUT_MAX
MOTOR_TEST_MAX_SECONDS_33 = 30.0   # the Solo's 3.3 (motor_test.pde MOTOR_TEST_TIMEOUT_MS_MAX)
MOTOR_TEST_MARGIN = 3.0            # s past the vehicle's own duration before the test counts as over unheard
PWM_RANGE = (800, 2200)


class AccelCalibration:
    """One six-position accelerometer calibration. ``state`` is what the vehicle asked last; the pilot puts the
    vehicle there and calls :meth:`confirm_position`; ``verdict`` resolves with the vehicle's own verdict."""

    def __init__(self, setup: "VehicleSetup") -> None:
        self._setup = setup
        self.verdict: Future = Future()
        self.started: Future | None = None

    @property
    def state(self) -> AccelCalState:
        return self._setup._v.state().setup.accel

    @property
    def position(self) -> int | None:
        return self.state.position

    @property
    def position_name(self) -> str:
        return self.state.position_name

    def confirm_position(self) -> Future:
        """Tell the vehicle it is in the position it asked for (COMMAND_LONG ACCELCAL_VEHICLE_POS)."""
        position = self.position
        if position is None:
            return self._setup._v._finish("accel position", CommandStatus.REJECTED,
                                          "the vehicle is not asking for a position now")
        return self._setup._v._command_long(mavlink.MAV_CMD_ACCELCAL_VEHICLE_POS, (position,),
                                            f"accel position {position} ({ACCEL_POSITIONS[position]})")


class CompassCalibration:
    """One onboard compass calibration: progress and reports per compass, then accept or cancel."""

    def __init__(self, setup: "VehicleSetup") -> None:
        self._setup = setup
        self.started: Future | None = None
        self.finished: Future = Future()       # the reports of every compass in progress, or the cancel

    @property
    def state(self) -> CompassCalState:
        return self._setup._v.state().setup.compass

    def accept(self) -> Future:
        return self._setup.accept_compass()

    def cancel(self) -> Future:
        return self._setup.cancel_compass()


class VehicleSetup:
    """The setup part of one :class:`~driver.vehicle.Vehicle`."""

    def __init__(self, vehicle) -> None:
        self._v = vehicle
        self._store = vehicle._store
        self._accel: AccelCalibration | None = None
        self._compass: CompassCalibration | None = None
        self._test_until = 0.0                 # monotonic bound of our motor test (the vehicle ends it first)
        self._test_from = 0                    # the vehicle's words from this message index on
        self._test_armed = False               # the vehicle reported armed by the test
        self._traffic = TrafficTracker()
        self._traffic_at = 0.0
        self._alerted: dict[int, str] = {}          # each aircraft alerting now: what was said of it
        self._lock = threading.Lock()          # guards the procedure objects between callers

    # -- calibrations ------------------------------------------------------------------------------------
    def _calibration(self, name: str, params) -> Future:
        return self._v._command_long(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, params, name)

    def calibrate_gyro(self) -> Future:
        return self._calibration("gyro calibration", (1, 0, 0, 0, 0, 0, 0))

    def calibrate_baro(self) -> Future:
        return self._calibration("barometer calibration", (0, 0, 1, 0, 0, 0, 0))

    def calibrate_level(self) -> Future:
        return self._calibration("level calibration", (0, 0, 0, 0, 2, 0, 0))

    def calibrate_accel_simple(self) -> Future:
        return self._calibration("simple accel calibration", (0, 0, 0, 0, 4, 0, 0))

    def accel_calibration(self) -> AccelCalibration:
        """Start the six-position calibration; the vehicle asks for each position in turn."""
        cal = AccelCalibration(self)
        why = unavailable("accel", self._v.state().firmware)
        if why:                                 # 3.3: positions by text and COMMAND_ACK, not driven here
            cal.started = self._v._finish("accel calibration", CommandStatus.REJECTED, why)
            cal.verdict.set_result(cal.started.result())
            return cal
        with self._lock:
            old, self._accel = self._accel, cal
        self._supersede(old and old.verdict, "accel calibration")
        with self._store.lock:
            self._set(accel=AccelCalState(AccelStep.STARTING))
        cal.started = self._calibration("accel calibration", (0, 0, 0, 0, 1, 0, 0))
        cal.started.add_done_callback(lambda f: self._accel_started(cal, f.result()))
        return cal

    def _accel_started(self, cal: AccelCalibration, result: CommandResult) -> None:
        if result.ok:
            return
        with self._store.lock:
            if self._accel is cal:
                self._set(accel=AccelCalState(AccelStep.FAILED))
        self._v._notifier.settle(cal.verdict, result)

    def compass_calibration(self) -> CompassCalibration:
        """DO_START_MAG_CAL for every compass, no retry, no autosave (the pilot accepts), no reboot."""
        cal = CompassCalibration(self)
        with self._lock:
            old, self._compass = self._compass, cal
        self._supersede(old and old.finished, "compass calibration")
        with self._store.lock:
            self._set(compass=CompassCalState(running=True))
        cal.started = self._v._command_long(mavlink.MAV_CMD_DO_START_MAG_CAL, (0, 0, 0, 0, 0), "compass calibration")
        cal.started.add_done_callback(lambda f: self._compass_started(cal, f.result()))
        return cal

    def _compass_started(self, cal: CompassCalibration, result: CommandResult) -> None:
        if result.ok:
            return
        with self._store.lock:
            if self._compass is cal:            # (a refused start of a superseded run leaves the new one be)
                self._set(compass=CompassCalState())
        self._v._notifier.settle(cal.finished, result)

    def _supersede(self, outcome: Future | None, name: str) -> None:
        """A new run of ``name`` replaced one whose outcome was still to come: it ends, aborted."""
        if outcome is not None and not outcome.done():
            self._v._notifier.settle(outcome, self._store.record(name, CommandStatus.ABORTED,
                                                                 f"superseded by a new {name}"))

    def accept_compass(self) -> Future:
        """ArduPilot's accept stops every calibrator, and answers FAILED when one was not done
        (AP_Compass_Calibration.cpp _accept_calibration_mask): whatever the answer, the run is over and its
        result is the vehicle's verdict."""
        future = self._v._command_long(mavlink.MAV_CMD_DO_ACCEPT_MAG_CAL, (0,), "accept compass calibration")
        future.add_done_callback(lambda f: self._compass_ended(accepted=f.result().ok, verdict=f.result()))
        return future

    def cancel_compass(self) -> Future:
        future = self._v._command_long(mavlink.MAV_CMD_DO_CANCEL_MAG_CAL, (0,), "cancel compass calibration")
        future.add_done_callback(lambda f: f.result().ok and self._compass_ended(cancelled=True))
        return future

    def _compass_ended(self, accepted: bool = False, cancelled: bool = False,
                       verdict: CommandResult | None = None) -> None:
        with self._store.lock:
            state = self._store.view()["setup"].compass
            self._set(compass=replace(state, running=False, accepted=accepted, cancelled=cancelled,
                                      progress=() if cancelled or verdict is not None else state.progress))
            self._store.publish()
        cal = self._compass
        if cal is None:
            return
        if cancelled:
            verdict = self._store.record("compass calibration", CommandStatus.ABORTED, "cancelled")
        if verdict is not None:
            self._v._notifier.settle(cal.finished, verdict)

    def fixed_mag_yaw(self, yaw_deg: float, lat: float = 0.0, lon: float = 0.0) -> Future:
        """Calibrate the compasses from a known heading (large vehicles); lat/lon 0: the vehicle's own position."""
        if not (math.isfinite(yaw_deg) and 0.0 <= yaw_deg <= 360.0):
            return self._v._finish("compass from yaw", CommandStatus.REJECTED, "yaw must be 0 to 360 degrees")
        return self._v._command_long(mavlink.MAV_CMD_FIXED_MAG_CAL_YAW, (yaw_deg, 0, lat, lon),
                                     f"compass from yaw {yaw_deg:g}")

    # -- motor test -----------------------------------------------------------------------------------------
    def motor_test(self, motor: int, throttle_pct: float | None = None, pwm: int | None = None,
                   seconds: float = 2.0, count: int = 1, *, propellers_removed: bool = False) -> Future:
        """Spin ``motor`` (test order, 1 = front / front right) at ``throttle_pct`` % or ``pwm`` µs for
        ``seconds``; with ``count`` > 1 the next motors follow in test order. Only on the ground, disarmed,
        with the propellers off."""
        name = f"motor test {motor}"
        problem = _motor_test_problem(motor, throttle_pct, pwm, seconds, count, propellers_removed)
        if problem:
            return self._v._finish(name, CommandStatus.REJECTED, problem)
        firmware = self._v.state().firmware

        def problem(s) -> str | None:           # checked now and again as the command goes out (the flight rules
            if s.may_be_airborne:               # check it too: driver.vehicle.safety)
                return "the vehicle may be airborne (it has not reported itself landed and disarmed)"
            if s.armed:
                return "the vehicle is armed: disarm first"
            return None
        refusal = problem(self._v.state())
        if refusal:
            return self._v._finish(name, CommandStatus.REJECTED, refusal)
        kind, value = (0, float(throttle_pct)) if pwm is None else (1, float(pwm))
        self.watch_radio(MOTOR_TEST_RATE_HZ)
        with self._store.lock:
            self._test_from = self._store.message_index
        future = self._v._command_long(mavlink.MAV_CMD_DO_MOTOR_TEST, (motor, kind, value, seconds, count), name,
                                       guard=problem)
        return chain(future, lambda result: self._test_started(result, motor_test_bound(seconds, count, firmware)),
                     name)

    def _test_started(self, result: CommandResult, seconds: float) -> CommandResult:
        """The vehicle accepted: the test runs (set before the caller hears the answer)."""
        if result.ok:
            with self._store.lock:
                self._test_until = self._v.clock() + seconds + MOTOR_TEST_MARGIN
                self._test_armed = False
                self._set(motor_test_running=True)
                self._store.publish()
        return result

    def _test_ended(self, result: CommandResult) -> CommandResult:
        """The vehicle accepted the stop: it ends the test at its next loop."""
        if result.ok:
            with self._store.lock:
                self._test_until = 0.0
                self._set(motor_test_running=False)
                self._store.publish()
        return result

    @property
    def motor_test_running(self) -> bool:
        """As the vehicle reports it: from its ACCEPTED to its "finished motor test" or disarm."""
        return self._v.state().setup.motor_test_running

    def stop_motor_test(self) -> Future:
        """End the running test at its next loop: DO_MOTOR_TEST with timeout 0 (motor_test.cpp takes it as a new
        timeout). Only while one runs: sent otherwise it *starts* a test that arms, then disarms the vehicle."""
        def problem(s) -> str | None:           # checked now and again as the command goes out
            return None if s.setup.motor_test_running else "no motor test is running"
        refusal = problem(self._v.state())
        if refusal:
            return self._v._finish("stop motor test", CommandStatus.REJECTED, refusal)
        future = self._v._command_long(mavlink.MAV_CMD_DO_MOTOR_TEST, (1, 0, 0, 0, 0), "stop motor test",
                                       guard=problem)
        return chain(future, self._test_ended, "stop motor test")

    def watch_radio(self, rate_hz: int = RADIO_RATE_HZ) -> None:
        """Ask for RC_CHANNELS and SERVO_OUTPUT_RAW (the RC_CHANNELS stream: 3.3 and 4.x both have it)."""
        self._radio_stream(rate_hz)

    def unwatch_radio(self) -> None:
        """Back to the rate a connection asks for (none, as MAVProxy's): at 10 Hz the two messages take about
        18 % of a 57.6 kbaud radio, for nothing once no page shows them."""
        self._radio_stream(0)

    def _radio_stream(self, rate_hz: int) -> None:
        self._v._post(self._radio_request(rate_hz))

    def _radio_request(self, rate_hz: int):
        system, component = self._v._target_ids()
        return mavlink.MAVLink_request_data_stream_message(
            system, component, mavlink.MAV_DATA_STREAM_RC_CHANNELS, rate_hz, 1 if rate_hz else 0)

    def request_banner(self) -> Future:
        """MAV_CMD_DO_SEND_BANNER: the vehicle says its firmware, its board's id line and its frame again
        (state().autopilot); a refusal is kept there as the reason the board is not known."""
        future = self._v._command_long(mavlink.MAV_CMD_DO_SEND_BANNER, (), "send banner")
        future.add_done_callback(lambda f: self._banner_answered(f.result()))
        return future

    def _banner_answered(self, result: CommandResult) -> None:
        with self._store.lock:
            autopilot = self._store.view()["autopilot"]
            self._store.set(autopilot=replace(autopilot, asked="" if result.ok else f"DO_SEND_BANNER {result.status.value}"
                                              + (f": {result.reason}" if result.reason else "")))

    # -- traffic --------------------------------------------------------------------------------------------
    def set_alert_limits(self, limits: AlertLimits) -> AlertLimits:
        problem = limits.problem()
        if problem:
            raise ValueError(problem)
        self._traffic.limits = limits
        return limits

    # -- what the vehicle says (reader thread, lock held) ------------------------------------------------------
    def _set(self, **changes) -> None:
        self._store.set(setup=replace(self._store.view()["setup"], **changes))

    def on_message(self, m) -> None:
        getattr(self, "_on_" + m.get_type().lower())(m)

    def _on_rc_channels(self, m) -> None:
        count = m.chancount if 0 < m.chancount <= 18 else 18
        values = tuple(int(getattr(m, f"chan{i}_raw")) for i in range(1, count + 1))
        self._set(rc=RcChannels(tuple(0 if v == 0xFFFF else v for v in values),
                                None if m.rssi == 255 else m.rssi, time.time()))

    def _on_rc_channels_raw(self, m) -> None:
        if m.port != 0:
            return
        values = tuple(int(getattr(m, f"chan{i}_raw")) for i in range(1, 9))
        self._set(rc=RcChannels(tuple(0 if v == 0xFFFF else v for v in values),
                                None if m.rssi == 255 else m.rssi, time.time()))

    def _on_servo_output_raw(self, m) -> None:
        if m.port != 0:
            return
        count = 16 if m.get_msgbuf()[0] == 0xFD else 8
        values = tuple(int(getattr(m, f"servo{i}_raw", 0) or 0) for i in range(1, count + 1))
        self._set(outputs=ServoOutputs(values, time.time()))

    def _on_mag_cal_progress(self, m) -> None:
        state = self._store.view()["setup"].compass
        progress = {p.compass: p for p in state.progress}
        progress[m.compass_id] = CompassProgress(m.compass_id, int(m.completion_pct), m.cal_status, m.attempt)
        self._set(compass=replace(state, running=True, progress=tuple(progress[k] for k in sorted(progress))))

    def _on_mag_cal_report(self, m) -> None:
        state = self._store.view()["setup"].compass
        if state.accepted or state.cancelled:
            return                              # the last reports before the vehicle stopped sending them
        offsets = (float(m.ofs_x), float(m.ofs_y), float(m.ofs_z))
        if not all(math.isfinite(v) for v in (*offsets, m.fitness)):
            return
        reports = {r.compass: r for r in state.reports}
        reports[m.compass_id] = CompassReport(m.compass_id, m.cal_status, float(m.fitness), offsets, bool(m.autosaved))
        progress = tuple(p for p in state.progress if p.compass not in reports)
        self._set(compass=replace(state, progress=progress, reports=tuple(reports[k] for k in sorted(reports))))
        cal = self._compass
        if cal is not None and not progress and not cal.finished.done():
            ok = all(r.ok for r in reports.values())
            words = ", ".join(f"compass {r.compass} fitness {r.fitness:.3f}{'' if r.ok else ' FAILED'}"
                              for r in reports.values())
            self._v._notifier.settle(cal.finished, self._store.record_locked(
                "compass calibration", CommandStatus.ACCEPTED if ok else CommandStatus.REFUSED, words))

    def _on_command_long(self, m) -> None:
        """The vehicle asks (ACCELCAL_VEHICLE_POS): the next position, or the verdict."""
        if m.command != mavlink.MAV_CMD_ACCELCAL_VEHICLE_POS:
            return
        position = int(m.param1)
        state = self._store.view()["setup"].accel
        cal = self._accel
        if position in ACCEL_POSITIONS:
            if state.position != position:
                confirmed = state.confirmed + ((state.position,) if state.position else ())
                self._set(accel=AccelCalState(AccelStep.WAITING, position, confirmed, state.texts))
            return
        if position not in (ACCEL_SUCCESS, ACCEL_FAILED) or not self._verdict_is_this_runs(state, cal):
            return
        ok = position == ACCEL_SUCCESS
        self._set(accel=AccelCalState(AccelStep.SUCCESS if ok else AccelStep.FAILED, None, state.confirmed))
        if cal is not None and not cal.verdict.done():
            said = [t.text for t in self._store.messages_since(0)[-5:] if t.source == "vehicle"
                    and "alibration" in t.text]
            reason = said[-1] if said else ("Calibration successful" if ok else "Calibration FAILED")
            self._v._notifier.settle(cal.verdict, self._store.record_locked(
                "accel calibration", CommandStatus.ACCEPTED if ok else CommandStatus.REFUSED, reason))

    @staticmethod
    def _verdict_is_this_runs(state: AccelCalState, cal: AccelCalibration | None) -> bool:
        """AP_AccelCal re-sends its last result every second until the next start (AP_AccelCal.cpp update()):
        one sent before the vehicle read our new start reaches us while the new run is starting. A verdict is this
        run's once the vehicle asked a position of it, or once it acknowledged the start (the same link carries the
        old repeats before that ACK, none after it). Told once: the later repeats find the run settled."""
        if state.step is AccelStep.WAITING:
            return True
        return (state.step is AccelStep.STARTING and cal is not None and cal.started is not None
                and cal.started.done() and cal.started.result().ok)

    def _on_adsb_vehicle(self, m) -> None:
        self._traffic.on_adsb_vehicle(m, self._v.clock())

    # -- the ticker (lock held) ------------------------------------------------------------------------------
    def _follow_motor_test(self, now: float, state) -> list:
        """The test ends when the vehicle says so ("finished motor test", 4.x), disarms (the test armed it; 3.3
        says nothing), or past its bound; then the outputs go back to the pages' rate."""
        said = self._store.messages_since(self._test_from)
        if said:
            self._test_from = said[-1].index
        finished = any(m.source == "vehicle" and m.text == "finished motor test" for m in said)
        self._test_armed = self._test_armed or state.armed
        if finished or (self._test_armed and not state.armed) or now > self._test_until:
            self._test_until = 0.0
            self._set(motor_test_running=False)
            return [self._radio_request(RADIO_RATE_HZ)]
        return []

    def service(self, now: float, state) -> list:
        out = self._follow_motor_test(now, state) if state.setup.motor_test_running else []
        if now - self._traffic_at >= TRAFFIC_REFRESH:
            self._traffic_at = now
            traffic = self._traffic.snapshot(now, state)
            fresh = [c for c in traffic.alerts if c.icao not in self._alerted]
            self._alerted = {c.icao: self._alerted.get(c.icao) or c.threat for c in traffic.alerts}
            traffic = traffic.said(self._alerted)           # the banner says what Messages says, word for word
            if traffic.contacts or state.traffic.contacts:
                self._store.set(traffic=traffic)
            for c in fresh:
                self._store.add_message_locked(Severity.WARNING, self._alerted[c.icao])
        return out


def motor_test_bound(seconds: float, count: int, firmware: str) -> float:
    """How long the vehicle runs a test: each motor its seconds, then half as long at rest before the next
    (ArduCopter/motor_test.cpp); the Solo's 3.3 runs one motor, at most 30 s, whatever the count."""
    have = version(firmware)
    if have is not None and have < (3, 4):
        return min(seconds, MOTOR_TEST_MAX_SECONDS_33)
    seconds = min(seconds, MOTOR_TEST_MAX_SECONDS)
    return seconds * count + 0.5 * seconds * (count - 1)


def _motor_test_problem(motor, throttle_pct, pwm, seconds, count, propellers_removed) -> str:
    if not propellers_removed:
        return "take the propellers off first (propellers_removed=True)"
    if not isinstance(motor, int) or not 1 <= motor <= 12:
        return "motor is 1 to 12, in test order"
    if (throttle_pct is None) == (pwm is None):
        return "give either a throttle in percent or a PWM"
    if throttle_pct is not None and not (math.isfinite(throttle_pct) and 0.0 <= throttle_pct <= 100.0):
        return "throttle must be 0 to 100 %"
    if pwm is not None and not (math.isfinite(pwm) and PWM_RANGE[0] <= pwm <= PWM_RANGE[1]):
        return f"PWM must be {PWM_RANGE[0]} to {PWM_RANGE[1]} µs"
    if not (math.isfinite(seconds) and 0.0 < seconds <= MOTOR_TEST_MAX_SECONDS):
        return f"seconds must be above 0 and at most {MOTOR_TEST_MAX_SECONDS:g}"
    if not isinstance(count, int) or not 1 <= count <= 12:
        return "count is 1 to 12 motors"
    return ""
