"""Calibrations as ArduCopter 4.6.3 answers them (tests/data/recordings/arducopter-4.6-sitl-setup/-calib).

Mixed into :class:`~driver.sim.autopilot.Autopilot` (through :class:`~driver.sim.setup.Setup`). Recorded:

* gyro (PREFLIGHT_CALIBRATION p1=1): "Initialising ArduPilot", ACCEPTED 0.5 s later;
* baro (p3=1): IN_PROGRESS with "Updating barometer calibration" / "Barometer calibration complete", then
  ACCEPTED 1 s later (two ACKs for one command);
* level (p5=2): "Initialising ArduPilot", ACCEPTED 1 s later, then "Trim OK: roll=.. pitch=.. yaw=..";
* accel (p5=1): ACCEPTED after 0.5 s, then COMMAND_LONG ACCELCAL_VEHICLE_POS (target 0/0) asking position 1..6,
  only the first with "Place vehicle level and press any key."; the GCS answers with the same command and
  position (ACCEPTED), the next prompt follows 0.65 s later, the verdict (16777215 success / 16777216 failure)
  is repeated about once a second. An airframe that is not turned fails at position 2. The airframe is
  turned only by ``SimConfig.calibration_model`` (SITL's ``calibration`` model: it takes each asked pose);
* compass (DO_START_MAG_CAL): MAG_CAL_PROGRESS per compass 0..2 at about 4 Hz each; unmoved it stays 0 %
  (status 2); tumbled by the calibration model it reaches 25/33/50/75 % and after 38.5 s each compass says
  "Mag(n) good orientation" and sends MAG_CAL_REPORT (status 4, fitness 0.037, offsets 5, 13, -18) until
  accepted (COMPASS_OFS* written) or cancelled; a cancel leaves "Compass calibrated requires reboot"; an accept
  while a compass still runs stops them all and is FAILED (AP_Compass_Calibration.cpp _accept_calibration_mask);
* armed: gyro/accel/baro/level FAILED "Disarm to allow calibration", DO_START_MAG_CAL FAILED "Disarm to allow
  compass calibration"; FIXED_MAG_CAL_YAW is ACCEPTED even armed.

The Solo's 3.3 (3drobotics/ardupilot-solo ArduCopter/GCS_Mavlink.pde, compass_cal.pde): gyro and baro ACCEPTED
at once (no IN_PROGRESS), level (p5=2) is not handled there (FAILED), the compass is driven as above; a refusal
while armed is a bare FAILED (its compass library prints to the console only); FIXED_MAG_CAL_YAW does not exist
(UNSUPPORTED: it came with 4.0). Its six-position accelerometer calibration is the older one (its
libraries/AP_AccelCal/AP_AccelCal.cpp): PREFLIGHT_CALIBRATION p5=1 starts it but is answered FAILED (the handler
never sets its result); each position is asked only by STATUSTEXT "Place vehicle <level / on its LEFT side /
on its RIGHT side / nose DOWN / nose UP / on its BACK> and press any key." and the ground station confirms with
any COMMAND_ACK (``accelcal.collect_sample()``); ACCELCAL_VEHICLE_POS is never sent and is UNSUPPORTED; the
verdict is only its text, not repeated, and "Calibration successful" reboots the vehicle a second later.
"""
from __future__ import annotations

import logging

from pymavlink.dialects.v20 import ardupilotmega as mavlink

log = logging.getLogger("driver.sim.autopilot")

__all__ = ["Calibration", "ACCEL_SUCCESS", "ACCEL_FAILED", "POSITION_NAMES", "MAG_OFFSETS", "MAG_CAL_DURATION"]

ACCEL_SUCCESS = 16777215          # ACCELCAL_VEHICLE_POS_SUCCESS
ACCEL_FAILED = 16777216           # ACCELCAL_VEHICLE_POS_FAILED
POSITION_NAMES = {1: "level", 2: "on its left side", 3: "on its right side", 4: "nose down", 5: "nose up",
                  6: "on its back"}
PROMPTS_33 = {1: "level", 2: "on its LEFT side", 3: "on its RIGHT side", 4: "nose DOWN", 5: "nose UP",
              6: "on its BACK"}                  # 3.3's AP_AccelCal::update() words
SEVERITY_HIGH_33 = 3                             # 3.3's SEVERITY_HIGH, as its STATUSTEXT carries it
COMPASSES = (0, 1, 2)
MAG_OFFSETS = (4.998, 12.998, -17.999)            # the calibration model's (recording: 5, 13, -18)
MAG_FITNESS = 0.037
MAG_CAL_DURATION = 38.4                          # s from start to the first report, tumbled (recording: 38.5)
MAG_STEPS = ((9.2, 25, 2), (12.2, 33, 3), (17.0, 50, 3), (25.5, 75, 3))   # s, percent, status (recording)
MAG_INTERVAL = 0.25                              # s between rounds of MAG_CAL_PROGRESS (about 4 Hz each)
VERDICT_REPEAT = 1.0                             # s between repeats of the accel verdict


class Calibration:
    """Calibration state and handlers; timers run on the sim's own clock (``self.t``)."""

    def _calibration_init(self) -> None:
        self.timers: list = []                   # (due, callable): delayed ACKs, prompts, verdicts
        self.accel_step: int | None = None       # position asked now (1..6), None when not calibrating
        self.accel_verdict: int | None = None    # ACCEL_SUCCESS / ACCEL_FAILED once ended
        self.accel_needed = False                # "3D Accel calibration needed" after a failure
        self.accel_reboot = False                # "Accels calibrated requires reboot" after a success
        self.airframe_pose = 1                   # the side the airframe rests on (1 level .. 6 back)
        self.mag_started: float | None = None    # sim time of DO_START_MAG_CAL while running
        self.mag_done = False                    # reports sent, waiting for accept / cancel
        self.mag_reboot = False                  # "Compass calibrated requires reboot"
        self.mag_next = 0.0
        self.prearm_failing_since: float | None = None   # the calibration's pre-arm failures, reported as 4.x does
        self.prearm_reported: float | None = None
        self.prearm_check = 0.0

    @property
    def turned(self) -> bool:
        """The airframe moves as asked (SITL's calibration model) or stays level on the bench."""
        return bool(getattr(self.config, "calibration_model", False))

    def after(self, delay: float, action) -> None:
        self.timers.append((self.t + delay, action))

    def _calibration_step(self) -> None:
        due = [entry for entry in self.timers if entry[0] <= self.t]
        if due:
            self.timers = [entry for entry in self.timers if entry[0] > self.t]
            for _, action in sorted(due, key=lambda e: e[0]):
                action()
        if self.mag_started is not None and self.t >= self.mag_next:
            self.mag_next = self.t + MAG_INTERVAL
            self._mag_round()
        if self.t >= self.prearm_check:
            self.prearm_check = self.t + 1.0
            self._report_prearm()

    def _report_prearm(self) -> None:
        """AP_Arming's pre-arm check at 1 Hz: a failure is told a second or more after it began, then every 30 s
        (recording: 1.0 s after DO_START_MAG_CAL, 1.8 s after the accel success, again 30-31 s later)."""
        reasons = self.calibration_arm_reasons()
        if not reasons:
            self.prearm_failing_since = self.prearm_reported = None
            return
        if self.armed or not self.profile.calibration_text:
            return
        if self.prearm_failing_since is None:
            self.prearm_failing_since = self.t
        due = (self.prearm_reported is None and self.t - self.prearm_failing_since >= 1.0) or (
            self.prearm_reported is not None and self.t - self.prearm_reported > 30.0)
        if due:
            self.prearm_reported = self.t
            for reason in reasons:
                self._text(mavlink.MAV_SEVERITY_CRITICAL, "PreArm: " + reason.removeprefix("Arm: "))

    def failing_prearm(self) -> list[str]:
        """The checks that fail now and clear SYS_STATUS's pre-arm health bit (GCS::update_sensor_status_flags:
        healthy while armed or while AP_Notify's pre_arm_check holds, which each 1 Hz run of the checks sets):
        a calibration that failed or wants a reboot, the safety switch. Recording (-setup): the bit cleared with
        "Compass calibration running" and stayed clear through "Arm: 3D Accel calibration needed"."""
        return self.calibration_arm_reasons() + (["Hardware safety switch"] if self.safety_on else [])

    def calibration_arm_reasons(self) -> list[str]:
        """Why arming is refused after a calibration (recording: "Arm: 3D Accel calibration needed")."""
        reasons = []
        if self.accel_needed:
            reasons.append("Arm: 3D Accel calibration needed")
        elif self.accel_reboot:
            reasons.append("Arm: Accels calibrated requires reboot")
        if self.mag_started is not None:
            reasons.append("Arm: Compass calibration running")
        elif self.mag_reboot:
            reasons.append("Arm: Compass calibrated requires reboot")
        return reasons

    def _ack_later(self, command: int, result: int, delay: float, then=None) -> None:
        sender = self._sender_ids

        def ack():
            self.emit(self.factory.command_ack_encode(command, result, 0, 0, *sender))
            if then is not None:
                then()
        self.after(delay, ack)

    def _disarm_first(self, compass: bool = False) -> tuple:
        if self.profile.calibration_text:
            self._text(mavlink.MAV_SEVERITY_NOTICE,
                       "Disarm to allow compass calibration" if compass else "Disarm to allow calibration")
        return mavlink.MAV_RESULT_FAILED, None

    # -- PREFLIGHT_CALIBRATION -----------------------------------------------------------------------
    def _cmd_preflight_calibration(self, p1, p2, p3, p4, p5, *_):
        if self.armed:
            return self._disarm_first()
        modern = self.profile.calibration_text
        cmd = mavlink.MAV_CMD_PREFLIGHT_CALIBRATION
        if int(p1) == 1:                                        # gyro
            if not modern:
                return mavlink.MAV_RESULT_ACCEPTED, None
            self._text(mavlink.MAV_SEVERITY_INFO, "Initialising ArduPilot")
            return None, lambda: self._ack_later(cmd, mavlink.MAV_RESULT_ACCEPTED, 0.5)
        if int(p3) == 1:                                        # baro
            if not modern:
                return mavlink.MAV_RESULT_ACCEPTED, None
            self._text(mavlink.MAV_SEVERITY_INFO, "Updating barometer calibration")
            self._text(mavlink.MAV_SEVERITY_INFO, "Barometer calibration complete")
            return mavlink.MAV_RESULT_IN_PROGRESS, lambda: self._ack_later(cmd, mavlink.MAV_RESULT_ACCEPTED, 0.96)
        if int(p5) == 2:                                        # level (board trim)
            if not modern:
                return mavlink.MAV_RESULT_FAILED, None
            self._text(mavlink.MAV_SEVERITY_INFO, "Initialising ArduPilot")
            return None, lambda: self._ack_later(cmd, mavlink.MAV_RESULT_ACCEPTED, 1.05, self._trim_ok)
        if int(p5) == 4:                                        # simple accel (level only): as level
            if not modern:
                return mavlink.MAV_RESULT_FAILED, None          # not handled by 3.3
            return None, lambda: self._ack_later(cmd, mavlink.MAV_RESULT_ACCEPTED, 1.0)
        if int(p5) == 1:                                        # 3D accel, six positions
            if self.accel_step is not None:
                return mavlink.MAV_RESULT_TEMPORARILY_REJECTED, None
            self.accel_verdict = None
            self.accel_step = 1
            self.airframe_pose = 1
            if not modern:                                      # 3.3 starts it, yet answers FAILED
                return mavlink.MAV_RESULT_FAILED, lambda: self.after(0.02, lambda: self._ask_position(1))
            self._text(mavlink.MAV_SEVERITY_INFO, "Initialising ArduPilot")
            return None, lambda: self._ack_later(cmd, mavlink.MAV_RESULT_ACCEPTED, 0.5, lambda: self.after(
                0.02, lambda: self._ask_position(1)))
        return mavlink.MAV_RESULT_UNSUPPORTED if int(p4) == 1 else mavlink.MAV_RESULT_FAILED, None

    def _trim_ok(self) -> None:
        self._text(mavlink.MAV_SEVERITY_INFO, f"Trim OK: roll={self.roll:.2f} pitch={self.pitch:.2f} yaw=0.00")

    def _accel_command(self, position: float) -> None:
        self.emit(self.factory.command_long_encode(0, 0, mavlink.MAV_CMD_ACCELCAL_VEHICLE_POS, 0, float(position),
                                                   0, 0, 0, 0, 0, 0))

    def _ask_position(self, position: int) -> None:
        if self.accel_step != position:
            return
        if self.turned:
            self.airframe_pose = position        # the calibration model takes the pose before the answer
        if not self.profile.calibration_text:    # 3.3: its words only
            self._text(SEVERITY_HIGH_33, f"Place vehicle {PROMPTS_33[position]} and press any key.")
            return
        self._accel_command(position)
        if position == 1:
            self._text(mavlink.MAV_SEVERITY_CRITICAL, "Place vehicle level and press any key.")

    def _cmd_accelcal_vehicle_pos(self, p1, *_):
        """The GCS says the vehicle is in the asked position (AP_AccelCal::gcs_vehicle_position)."""
        if not self.profile.calibration_text:
            return mavlink.MAV_RESULT_UNSUPPORTED, None      # 3.3's command switch has no such command
        if self.accel_step is None or int(p1) != self.accel_step:
            return mavlink.MAV_RESULT_FAILED, None
        return mavlink.MAV_RESULT_ACCEPTED, self._accel_sample()

    def _on_command_ack(self, msg) -> None:
        """3.3: any COMMAND_ACK from a ground station while a position is asked takes the sample
        (GCS_Mavlink.pde: ``accelcal.collect_sample()``); 4.x's snoop wants MAVProxy's own ACK, not used here."""
        if not self.profile.calibration_text and self.accel_step is not None:
            then = self._accel_sample()
            if then is not None:
                then()

    def _accel_sample(self):
        """The asked position's sample: the fit fails on a wrong pose, else the next position or the verdict."""
        position = self.accel_step
        if self.airframe_pose != position:      # the samples do not fit: the fit fails
            self.accel_step = None
            self.after(0.65, self._accel_failed)
            return None
        if position == 6:
            self.accel_step = None
            if self.profile.calibration_text:
                self.after(0.68, self._trim_ok)
            self.after(0.78, self._accel_succeeded)
            return None
        self.accel_step = position + 1
        return lambda: self.after(0.65, lambda: self._ask_position(position + 1))

    def _accel_failed(self) -> None:
        self._text(self._accel_severity(), "Calibration FAILED")
        self.accel_needed = True
        self._accel_end(ACCEL_FAILED)

    def _accel_succeeded(self) -> None:
        self._text(self._accel_severity(), "Calibration successful")
        self.accel_needed = False
        self.accel_reboot = True
        self._accel_end(ACCEL_SUCCESS)

    def _accel_severity(self) -> int:
        return mavlink.MAV_SEVERITY_CRITICAL if self.profile.calibration_text else SEVERITY_HIGH_33

    def _accel_end(self, verdict: int) -> None:
        self.accel_verdict = verdict
        if not self.profile.calibration_text:    # 3.3: told once; a success reboots (AP_AccelCal::success)
            if verdict == ACCEL_SUCCESS:
                self.after(1.0, self.reboot)
            return
        self.after(0.1, lambda: self._repeat_verdict(verdict))

    def _repeat_verdict(self, verdict: int) -> None:
        if self.accel_verdict != verdict or self.accel_step is not None:
            return                               # a new calibration started
        if self.armed:                           # AP_AccelCal is not updated while armed (recording: no repeat
            self.after(0.02, lambda: self._repeat_verdict(verdict))   # during a motor test, one right after it)
            return
        self._accel_command(verdict)
        self.after(VERDICT_REPEAT, lambda: self._repeat_verdict(verdict))

    # -- compass ---------------------------------------------------------------------------------------
    def _cmd_do_start_mag_cal(self, p1, *_):
        if self.armed:
            return self._disarm_first(compass=True)
        if not 0 <= p1 <= 255:
            return mavlink.MAV_RESULT_FAILED, None
        self.mag_started = self.t
        self.mag_done = False
        self.mag_next = self.t + 0.2
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_do_accept_mag_cal(self, *_):
        if self.mag_started is not None and not self.mag_done:
            self.mag_started = None                         # every calibrator stops (_accept_calibration_mask),
            self.mag_reboot = True                          # FAILED as one was not done; started: reboot needed
            return mavlink.MAV_RESULT_FAILED, None
        if self.mag_done:
            for axis, value in zip("XYZ", MAG_OFFSETS):
                for prefix in ("COMPASS_OFS_", "COMPASS_OFS2_", "COMPASS_OFS3_"):
                    if prefix + axis in self.params:
                        self.params[prefix + axis] = value
            self.mag_started = None
            self.mag_done = False
            self.mag_reboot = True
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_do_cancel_mag_cal(self, *_):
        if self.mag_started is not None:
            self.mag_started = None
            self.mag_done = False
            self.mag_reboot = True
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _cmd_fixed_mag_cal_yaw(self, p1, *_):
        if not self.profile.calibration_text:
            return mavlink.MAV_RESULT_UNSUPPORTED, None       # 4.0 and later only
        if not 0.0 <= p1 <= 360.0 or not self.stage.gps_fix:
            return mavlink.MAV_RESULT_FAILED, None
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _mag_progress(self) -> tuple[int, int]:
        """(percent, status) now: 0 % RUNNING_STEP_ONE unmoved; the recording's steps when tumbled."""
        if not self.turned:
            return 0, mavlink.MAG_CAL_RUNNING_STEP_ONE
        elapsed = self.t - self.mag_started
        pct, status = 0, mavlink.MAG_CAL_RUNNING_STEP_ONE
        for at, step_pct, step_status in MAG_STEPS:
            if elapsed >= at:
                pct, status = step_pct, step_status
        return pct, status

    def _mag_round(self) -> None:
        if self.mag_done:
            for compass in COMPASSES:
                self._mag_report(compass)
            return
        if self.turned and self.t - self.mag_started >= MAG_CAL_DURATION:
            self.mag_done = True
            self._mag_good(0)                    # the recording's order: each compass ends on its own
            self._mag_report(0)
            self._mag_good(2)
            self._mag_good(1)
            self._mag_report(1)
            self._mag_report(2)
            return
        pct, status = self._mag_progress()
        mask = [0, 0, 0, 0, 2, 0, 0, 0, 0, 0] if pct == 0 else [219, 136, 253, 123, 219, 218, 244, 250, 178, 218]
        for compass in (1, 2, 0):               # the recording's order
            self.emit(self.factory.mag_cal_progress_encode(compass, 7, status, 1, pct, mask, 0.0, 0.0, 0.0))

    def _mag_good(self, compass: int) -> None:
        self._text(mavlink.MAV_SEVERITY_INFO, f"Mag({compass}) good orientation: 0 4.0")

    def _mag_report(self, compass: int) -> None:
        self.emit(self.factory.mag_cal_report_encode(compass, 7, mavlink.MAG_CAL_SUCCESS, 0, MAG_FITNESS,
                                                     *MAG_OFFSETS, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 3.98, 0, 0, 1.0))
