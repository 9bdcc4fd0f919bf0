"""The simulator's setup answers that the recordings do not show, from ArduPilot's sources: the motor test refused
in the air, the fixed-yaw compass calibration without a position, a position confirmed that was not asked."""
from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.sim import SimConfig
from driver.sim.autopilot import Autopilot

STEP = 0.02


class Bench:
    def __init__(self, **config) -> None:
        self.out: list = []
        self.ap = Autopilot(SimConfig(**{"ready_after": 1.0, "seed": 1, **config}), emit=self.out.append)
        self.factory = mavlink.MAVLink(None, 255, 190)

    def run(self, seconds: float) -> None:
        for _ in range(int(seconds / STEP)):
            self.ap.step(STEP)

    def command(self, command: int, *params: float, wait: float = 0.1) -> tuple[list[int], list[str]]:
        self.out.clear()
        p = list(params) + [0.0] * (7 - len(params))
        self.ap.handle(self.factory.command_long_encode(1, 1, command, 0, *p), 2)
        self.run(wait)
        acks = [m.result for m in self.out if m.get_type() == "COMMAND_ACK" and m.command == command]
        return acks, [m.text for m in self.out if m.get_type() == "STATUSTEXT"]


def test_a_motor_test_in_the_air_is_refused_with_the_vehicles_reason():
    b = Bench()
    b.run(3.0)
    b.ap.armed, b.ap.landed, b.ap.d = True, False, -5.0
    acks, texts = b.command(mavlink.MAV_CMD_DO_MOTOR_TEST, 1, 0, 20, 2)
    assert acks == [mavlink.MAV_RESULT_FAILED] and "Motor Test: vehicle not landed" in texts
    assert not b.ap.motor_testing


def test_a_motor_test_with_timeout_zero_ends_the_running_one():
    b = Bench()
    b.run(3.0)
    assert b.command(mavlink.MAV_CMD_DO_MOTOR_TEST, 1, 1, 1300, 30)[0] == [mavlink.MAV_RESULT_ACCEPTED]
    assert b.ap.motor_testing and b.ap.armed
    acks, texts = b.command(mavlink.MAV_CMD_DO_MOTOR_TEST, 1, 0, 0, 0)
    assert acks == [mavlink.MAV_RESULT_ACCEPTED] and "finished motor test" in texts
    assert not b.ap.motor_testing and not b.ap.armed


def test_fixed_yaw_needs_a_position_and_a_valid_yaw():
    b = Bench(ready_after=30.0)
    b.run(3.0)                                            # no GPS fix yet
    assert b.command(mavlink.MAV_CMD_FIXED_MAG_CAL_YAW, 353)[0] == [mavlink.MAV_RESULT_FAILED]
    b.run(30.0)
    assert b.command(mavlink.MAV_CMD_FIXED_MAG_CAL_YAW, 400)[0] == [mavlink.MAV_RESULT_FAILED]
    assert b.command(mavlink.MAV_CMD_FIXED_MAG_CAL_YAW, 353)[0] == [mavlink.MAV_RESULT_ACCEPTED]


def test_a_position_that_was_not_asked_is_failed_and_a_second_start_is_turned_away():
    b = Bench()
    b.run(3.0)
    assert b.command(mavlink.MAV_CMD_ACCELCAL_VEHICLE_POS, 1)[0] == [mavlink.MAV_RESULT_FAILED]   # none running
    assert b.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 1, wait=1.0)[0] == [
        mavlink.MAV_RESULT_ACCEPTED]
    assert b.command(mavlink.MAV_CMD_ACCELCAL_VEHICLE_POS, 3)[0] == [mavlink.MAV_RESULT_FAILED]   # 1 is asked
    assert b.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 1)[0] == [
        mavlink.MAV_RESULT_TEMPORARILY_REJECTED]


def test_each_page_can_say_what_the_solos_firmware_lacks(sim_factory, vehicle_factory):
    from driver.core.firmware import SETUP_ACTIONS, unavailable
    sim = sim_factory(profile="solo")
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    state = v.wait_for(lambda s: s.firmware, 30)
    assert state.firmware == "3.3.1"
    missing = {a for a in SETUP_ACTIONS if unavailable(a, state.firmware)}
    assert missing == {"level", "accel_simple", "accel", "fixed_yaw", "adsb"}
    assert "MAV_CMD_FIXED_MAG_CAL_YAW" in unavailable("fixed_yaw", state.firmware)
    assert not any(unavailable(a, "4.6.3") for a in SETUP_ACTIONS)
    assert not any(unavailable(a, "") for a in SETUP_ACTIONS)      # not known yet: the vehicle decides


def test_the_solos_33_asks_each_accel_position_by_text_and_takes_a_command_ack():
    """ardupilot-solo: PREFLIGHT_CALIBRATION p5=1 starts it but is answered FAILED; "Place vehicle ... and press
    any key." per position, any COMMAND_ACK takes the sample, no ACCELCAL_VEHICLE_POS; a success reboots."""
    b = Bench(profile="solo", calibration_model=True)
    b.run(3.0)
    acks, texts = b.command(mavlink.MAV_CMD_PREFLIGHT_CALIBRATION, 0, 0, 0, 0, 1, wait=0.5)
    assert acks == [mavlink.MAV_RESULT_FAILED] and texts == ["Place vehicle level and press any key."]
    asked = [texts[0]]
    for _ in range(6):
        b.out.clear()
        b.ap.handle(b.factory.command_ack_encode(0, 1), 1)
        b.run(1.0)
        asked += [m.text for m in b.out if m.get_type() == "STATUSTEXT"]
        assert not any(m.get_type() == "COMMAND_LONG" for m in b.out)          # never ACCELCAL_VEHICLE_POS
    assert asked == ["Place vehicle level and press any key.", "Place vehicle on its LEFT side and press any key.",
                     "Place vehicle on its RIGHT side and press any key.", "Place vehicle nose DOWN and press any key.",
                     "Place vehicle nose UP and press any key.", "Place vehicle on its BACK and press any key.",
                     "Calibration successful"]
    b.run(1.0)
    assert b.ap.rebooting_until is not None                                   # AP_AccelCal::success reboots
    assert b.command(mavlink.MAV_CMD_ACCELCAL_VEHICLE_POS, 1)[0] in ([], [mavlink.MAV_RESULT_UNSUPPORTED])


def test_the_solos_33_has_no_accelcal_vehicle_pos():
    b = Bench(profile="solo")
    b.run(3.0)
    assert b.command(mavlink.MAV_CMD_ACCELCAL_VEHICLE_POS, 1)[0] == [mavlink.MAV_RESULT_UNSUPPORTED]


def test_a_timeout_zero_motor_test_while_none_runs_arms_then_disarms_the_vehicle():
    """motor_test.cpp: a stop sent idle goes through mavlink_motor_test_start and ends at the next loop."""
    b = Bench()
    b.run(3.0)
    acks, texts = b.command(mavlink.MAV_CMD_DO_MOTOR_TEST, 1, 0, 0, 0, wait=0.2)
    assert acks == [mavlink.MAV_RESULT_ACCEPTED] and texts == ["starting motor test", "finished motor test"]
    assert not b.ap.motor_testing and not b.ap.armed
