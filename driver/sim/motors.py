"""The motor test and the radio as ArduCopter 4.6.3 shows them (tests/data/recordings/arducopter-4.6-sitl-setup).

Motor test (MAV_CMD_DO_MOTOR_TEST: p1 motor in test order, p2 0 percent / 1 PWM, p3 value, p4 seconds, p5 count):
ACCEPTED with "starting motor test", the motors armed for the test (the HEARTBEAT says armed), the tested
output at the value (20 % = 1200 between MOT_PWM_MIN and MOT_PWM_MAX), the others at 1000 (1100, armed idle,
when the vehicle was armed already); "finished motor test" and a disarm at the end. With a count each motor runs
its seconds, then rests half as long at the minimum output, then the next one (ArduCopter/motor_test.cpp
motor_test_output: ``timeout*1.5``). Test order 1..4 is outputs 3, 1, 4, 2 on a + quad
(FRAME_TYPE 0, recorded) and 1, 4, 2, 3 on an X quad (ArduPilot's AP_MotorsMatrix). Refused "Motor Test:
vehicle not landed" in the air (ArduCopter motor_test.cpp). A test with timeout 0 ends the running one at the
next loop; sent while none runs it starts one that ends at once (arming, then disarming the vehicle: it goes
through mavlink_motor_test_start like any other).

The radio: RC_CHANNELS from a simulated transmitter, 8 channels at the recording's SITL values (sticks centred,
throttle down, CH5 1800 and CH8 1800), as RC_CHANNELS_RAW on the Solo's 3.3; a test moves them with
:meth:`MotorTest.move_stick`.
The Solo's 3.3 (ardupilot-solo ArduCopter/motor_test.pde) runs one motor only: it ignores the count (param5 is
not passed), caps the timeout at 30 s (MOTOR_TEST_TIMEOUT_MS_MAX) and says neither "starting" nor "finished
motor test".
"""
from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink

__all__ = ["MotorTest", "TEST_ORDER", "RC_DEFAULT", "FRAME_CLASSES", "FRAME_TYPES"]

# FRAME_TYPE → outputs in test order (AP_MotorsMatrix: QUAD_PLUS motors 1 right, 2 left, 3 front, 4 back with
# test order 2, 4, 1, 3; QUAD_X 1 front right, 2 back left, 3 front left, 4 back right with 1, 3, 4, 2).
TEST_ORDER = {0: (3, 1, 4, 2), 1: (1, 4, 2, 3)}
# AP_Motors' _frame_class_string / _frame_type_string, which the banner's "Frame: QUAD/X" line joins
FRAME_CLASSES = {1: "QUAD", 2: "HEXA", 3: "OCTA", 4: "OCTAQUAD", 5: "Y6", 7: "TRI", 12: "DODECAHEXA", 14: "DECA"}
FRAME_TYPES = {0: "PLUS", 1: "X", 2: "V", 3: "H", 4: "VTAIL", 5: "ATAIL", 6: "PLUSREV", 10: "Y6B", 11: "Y6F",
               12: "BF_X", 13: "DJI_X", 14: "CW_X", 15: "I", 18: "X_REV", 19: "Y4"}
RC_DEFAULT = (1500, 1500, 1000, 1500, 1800, 1000, 1000, 1800)
ARMED_IDLE = 1100
REST_SHARE = 0.5                    # of each motor's seconds at rest before the next (motor_test.cpp)
TIMEOUT_MAX = 600.0                 # s (MOTOR_TEST_TIMEOUT_SEC)
TIMEOUT_MAX_33 = 30.0               # s, the Solo's 3.3 (MOTOR_TEST_TIMEOUT_MS_MAX)


class MotorTest:
    """Motor test state and the outputs/inputs messages; the Autopilot owns the rest."""

    def _motors_init(self) -> None:
        self.motor_test = None           # (output 1..4, pwm, until) while one motor spins
        self.motor_queue: list = []      # the next motors of a sequence: (start, output, pwm, seconds)
        self.test_armed_before = False
        self.rc = list(RC_DEFAULT)

    def move_stick(self, channel: int, pwm: int) -> None:
        """The pilot moves a transmitter channel (1-based)."""
        self.rc[channel - 1] = int(pwm)

    def test_order(self) -> tuple[int, ...]:
        return TEST_ORDER.get(int(self.params["FRAME_TYPE"]), TEST_ORDER[1])

    def _cmd_do_motor_test(self, p1, p2, p3, p4, p5=0.0, *_):
        if not self.landed:
            self._text(mavlink.MAV_SEVERITY_CRITICAL, "Motor Test: vehicle not landed")
            return mavlink.MAV_RESULT_FAILED, None
        order = self.test_order()
        seq, kind = int(p1), int(p2)
        if not 1 <= seq <= len(order) or kind not in (0, 1) or p4 < 0:
            return mavlink.MAV_RESULT_FAILED, None
        modern = self.profile.calibration_text
        low, high = int(self.params["MOT_PWM_MIN"]), int(self.params["MOT_PWM_MAX"])
        pwm = low + (high - low) * min(max(p3, 0.0), 100.0) / 100.0 if kind == 0 else min(max(p3, low), high)
        seconds = min(float(p4), TIMEOUT_MAX if modern else TIMEOUT_MAX_33)     # 0: ends at the next loop
        count = max(1, int(p5)) if modern else 1
        starting = self.motor_test is None and not self.motor_queue
        if starting:
            self.test_armed_before = self.armed
        self.motor_queue = [(self.t + i * seconds * (1.0 + REST_SHARE), order[(seq - 1 + i) % len(order)], int(pwm),
                             seconds) for i in range(count)]
        self.motor_test = None
        if starting and modern:
            self._text(mavlink.MAV_SEVERITY_INFO, "starting motor test")
        if not self.armed:
            self.armed = True                         # the test arms the motors (recording: HEARTBEAT armed)
            self.armed_at = self.t - self.profile.arming_delay
            self.landed = True
            self.touchdown_at = self.t
        return mavlink.MAV_RESULT_ACCEPTED, None

    def _motors_step(self) -> None:
        if self.motor_queue and self.t >= self.motor_queue[0][0]:
            start, output, pwm, seconds = self.motor_queue.pop(0)
            self.motor_test = (output, pwm, self.t + seconds)     # out for one loop at least, even at 0 s
        elif self.motor_test is not None and self.t >= self.motor_test[2]:
            self.motor_test = None
            if not self.motor_queue:
                self._motor_test_end()
        if (self.motor_test is not None or self.motor_queue) and self.armed:
            self.touchdown_at = self.t                # no auto-disarm while the test runs

    def _motor_test_end(self) -> None:
        self.motor_test = None
        self.motor_queue = []
        if self.profile.calibration_text:
            self._text(mavlink.MAV_SEVERITY_INFO, "finished motor test")
        self._disarm()                                # the motor test disarms at its end

    @property
    def motor_testing(self) -> bool:
        return self.motor_test is not None or bool(self.motor_queue)

    def _msg_servo_output_raw(self):
        if not self.motor_testing:
            return super()._msg_servo_output_raw()
        rest = ARMED_IDLE if self.test_armed_before else 1000
        pwm = [rest] * 4
        if self.motor_test is not None:
            pwm[self.motor_test[0] - 1] = self.motor_test[1]
        return self.factory.servo_output_raw_encode(int(self.t * 1e6) & 0xFFFFFFFF, 0, *pwm, 0, 0, 0, 0)

    def _msg_rc_channels(self):
        if not self.profile.mavlink2:         # 3.3's RC stream: "SERVO_OUTPUT_RAW and RC_CHANNELS_RAW" (GCS_Mavlink.pde)
            return self.factory.rc_channels_raw_encode(self.time_boot_ms(), 0, *self.rc[:8], 255)
        channels = list(self.rc) + [0] * (18 - len(self.rc))
        return self.factory.rc_channels_encode(self.time_boot_ms(), len(self.rc), *channels[:18], 255)
