"""The console's setup verbs, in MAVProxy's words (mixed into :class:`driver.console.Console`):
accelcal, accelcalsimple, level, gyrocal, calpress, magcal, motortest, rc, adsb.

``accelcal`` starts the six-position calibration; each position the vehicle asks for is printed, and an empty
line (Enter, as in MAVProxy) tells the vehicle it is in place. ``motortest`` takes MAVProxy's arguments followed
by the word ``props-off``: the pilot's explicit word that the propellers are off (a motortest recalled from
MAVProxy's history, or typed out of habit, does not spin a propeller); the driver still refuses it armed or in
the air.
"""
from __future__ import annotations

import threading
import time

from ..setup.model import AccelStep
from .words import number
from ..traffic.model import Traffic

__all__ = ["SetupCommands", "traffic_lines", "rc_line"]

MAGCAL_USAGE = "magcal start|accept|cancel|status | magcal yaw DEG"
PROPS_OFF = "props-off"
MOTORTEST_USAGE = (f"motortest MOTOR TYPE VALUE SECONDS [COUNT] {PROPS_OFF} (TYPE 0 percent, 1 PWM) | "
                   "motortest stop")
RC_WAIT = 3.0                  # s 'rc' waits for the first RC_CHANNELS it asked for
WATCH_TIMEOUT = 120.0          # s an accel calibration waits for the vehicle's next word


def rc_line(state) -> str:
    rc, out = state.setup.rc, state.setup.outputs
    if not rc.values and not out.values:
        return "rc: nothing from the vehicle yet (RC_CHANNELS asked for)"
    inputs = " ".join(f"{i}:{v}" for i, v in enumerate(rc.values, 1) if v) or "none"
    outputs = " ".join(f"{i}:{v}" for i, v in enumerate(out.values, 1) if v) or "none"
    rssi = f", RSSI {rc.rssi}" if rc.rssi is not None else ""
    return f"rc in  {inputs}{rssi}\nservo out {outputs}"


def traffic_lines(traffic: Traffic) -> list[str]:
    if not traffic.contacts:
        return ["adsb: no traffic"]
    lines = []
    for c in traffic.contacts:
        where = f"{c.distance:.0f} m at {c.bearing_deg:03.0f}°" if c.distance is not None else "position unknown"
        rel = f"{c.relative_alt:+.0f} m" if c.relative_alt is not None else "alt ?"
        heading = f"hdg {c.heading_deg:03.0f}°" if c.heading_deg is not None else "hdg ?"
        speed = f"{c.speed:.0f} m/s" if c.speed is not None else "? m/s"
        flags = (" STALE" if c.stale else "") + (" ALERT" if c.alert else "")
        lines.append(f"{c.label:<9} {where}, {rel}, {heading}, {speed}, {c.age:.0f} s ago{flags}")
    return lines


class SetupCommands:
    """``self.vehicle`` is a :class:`~driver.vehicle.Vehicle`; ``self._report(future)`` prints its result."""

    _accel = None

    def setup_enter(self) -> bool:
        """An empty line: during an accel calibration, the vehicle is in the asked position."""
        cal = self._accel
        if cal is not None and cal.state.step is AccelStep.WAITING:
            self._report(cal.confirm_position())
        return False

    def do_accelcal(self, arg: str) -> None:
        """accelcal: six-position accelerometer calibration; press Enter when the vehicle is in each position"""
        cal = self._accel = self.vehicle.setup.accel_calibration()
        self._report(cal.started)
        threading.Thread(target=self._follow_accel, args=(cal,), name="console-accelcal", daemon=True).start()

    def _follow_accel(self, cal) -> None:
        told = None
        while not cal.verdict.done():
            state = self.vehicle.wait_for(lambda s: cal.verdict.done() or (
                s.setup.accel.step is AccelStep.WAITING and s.setup.accel.position != told), WATCH_TIMEOUT)
            if state is None or cal.verdict.done():
                break
            told = state.setup.accel.position
            self.say(f"Place vehicle {state.setup.accel.position_name} and press Enter")
        if cal.verdict.done():
            self._report(cal.verdict)

    def do_accelcalsimple(self, arg: str) -> None:
        """accelcalsimple: level-only accelerometer calibration"""
        self._report(self.vehicle.setup.calibrate_accel_simple())

    def do_level(self, arg: str) -> None:
        """level: board level (trim) calibration, the vehicle standing level"""
        self._report(self.vehicle.setup.calibrate_level())

    def do_gyrocal(self, arg: str) -> None:
        """gyrocal: gyro calibration, the vehicle still"""
        self._report(self.vehicle.setup.calibrate_gyro())

    def do_calpress(self, arg: str) -> None:
        """calpress: barometer (pressure) calibration"""
        self._report(self.vehicle.setup.calibrate_baro())

    def do_magcal(self, arg: str) -> None:
        """magcal start|accept|cancel|status: onboard compass calibration; magcal yaw DEG: from a known heading"""
        words = arg.split()
        setup = self.vehicle.setup
        if words == ["start"]:
            cal = setup.compass_calibration()
            self._report(cal.started)
            cal.finished.add_done_callback(lambda f: self._report(f))
        elif words == ["accept"]:
            self._report(setup.accept_compass())
        elif words == ["cancel"]:
            self._report(setup.cancel_compass())
        elif words == ["status"]:
            state = self.vehicle.state().setup.compass
            lines = [f"compass {p.compass}: {p.percent} % (status {p.status}, attempt {p.attempt})"
                     for p in state.progress]
            lines += [f"compass {r.compass}: {'done' if r.ok else 'FAILED'} (status {r.status}), fitness "
                      f"{r.fitness:.3f}, offsets {r.offsets[0]:.1f} {r.offsets[1]:.1f} {r.offsets[2]:.1f}"
                      for r in state.reports]
            self.say("\n".join(lines) if lines else "magcal: not running")
        elif len(words) == 2 and words[0] == "yaw":
            self._report(setup.fixed_mag_yaw(number(words[1], "DEG")))
        else:
            raise ValueError(f"usage: {MAGCAL_USAGE}")

    def do_motortest(self, arg: str) -> None:
        """motortest MOTOR TYPE VALUE SECONDS [COUNT] props-off: spin a motor (test order) at VALUE percent (TYPE 0)
        or PWM (TYPE 1) for SECONDS, COUNT motors in turn; props-off says the propellers are OFF; motortest stop
        ends it"""
        words = arg.split()
        if words == ["stop"]:
            self._report(self.vehicle.setup.stop_motor_test())
            return
        props_off = bool(words) and words[-1] == PROPS_OFF
        words = words[:-1] if props_off else words
        if len(words) not in (4, 5) or words[1] not in ("0", "1"):
            raise ValueError(f"usage: {MOTORTEST_USAGE}")
        if not props_off:
            raise ValueError(f"the motors spin: take the propellers off, then end the line with '{PROPS_OFF}' "
                             f"(motortest {' '.join(words)} {PROPS_OFF})")
        motor = int(number(words[0], "MOTOR", integer=True))
        value = number(words[2], "VALUE")
        seconds = number(words[3], "SECONDS")
        count = int(number(words[4], "COUNT", integer=True)) if len(words) == 5 else 1
        pct, pwm = (value, None) if words[1] == "0" else (None, value)
        self._report(self.vehicle.setup.motor_test(motor, throttle_pct=pct, pwm=pwm, seconds=seconds, count=count,
                                                   propellers_removed=props_off))

    def do_rc(self, arg: str) -> None:
        """rc: the transmitter's channels (RC_CHANNELS) and the outputs (SERVO_OUTPUT_RAW) as the vehicle sees them"""
        # RC_CHANNELS is in no stream a ground station asks for at connect: ask, wait for a fresh one (4.6.3 SITL
        # sent it about a second later) rather than say "nothing" or show an old one, then ask the stream off
        # again (10 Hz of RC_CHANNELS and SERVO_OUTPUT_RAW is about 18 % of a 57.6 kbaud radio)
        asked = time.time()
        self.vehicle.setup.watch_radio()
        try:
            state = self.vehicle.wait_for(lambda s: s.setup.rc.updated >= asked, RC_WAIT) or self.vehicle.state()
        finally:
            if not self.vehicle.setup.motor_test_running:
                self.vehicle.setup.unwatch_radio()
        self.say(rc_line(state))

    def do_adsb(self, arg: str) -> None:
        """adsb: the ADS-B traffic the vehicle forwards, nearest first, with alerts"""
        self.say("\n".join(traffic_lines(self.vehicle.state().traffic)))
