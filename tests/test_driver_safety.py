"""The command core's flight rules and reply matching, on the driver's own clock (nothing real waited).

The vehicle is not started: what the autopilot says is fed with ``ingest``, ``step`` runs one pass of the ticker and
returns exactly what would go out on the wire, after the flight rules (driver.vehicle.safety).
"""
from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.vehicle import Vehicle
from driver.vehicle.state import CommandStatus

from test_driver_clock import at, clock, vehicle  # noqa: F401  (the driver on its own clock, not started)

GUIDED, AUTO, STABILIZE, LAND = 4, 3, 0, 9
ARM = mavlink.MAV_CMD_COMPONENT_ARM_DISARM
_enc = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)


def frame(msg) -> bytes:
    """``msg`` as the autopilot sends it, each frame with the next sequence number."""
    data = msg.pack(_enc)
    _enc.seq = (_enc.seq + 1) % 256
    return data


def heartbeat(armed: bool, mode: int = GUIDED, status: int = mavlink.MAV_STATE_ACTIVE) -> bytes:
    base = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (mavlink.MAV_MODE_FLAG_SAFETY_ARMED if armed else 0)
    return frame(_enc.heartbeat_encode(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, base, mode,
                                       status))


def landed(state: int) -> bytes:
    return frame(_enc.extended_sys_state_encode(0, state))


def ack(command: int, result: int = mavlink.MAV_RESULT_ACCEPTED) -> bytes:
    return frame(_enc.command_ack_encode(command, result, 0, 0, 255, 190))


def commands(sent: list, command: int) -> list:
    return [m for m in sent if m.get_type() == "COMMAND_LONG" and m.command == command]


def modes(sent: list) -> list[int]:
    return [int(m.param2) for m in sent if m.get_type() == "COMMAND_LONG" and m.command == mavlink.MAV_CMD_DO_SET_MODE] \
        + [m.custom_mode for m in sent if m.get_type() == "SET_MODE"]


def flying(vehicle: Vehicle, mode: int = GUIDED) -> None:
    vehicle.ingest(publish=True, data=heartbeat(True, mode))
    vehicle.ingest(publish=True, data=landed(mavlink.MAV_LANDED_STATE_IN_AIR))


def on_the_ground(vehicle: Vehicle, armed: bool = False, mode: int = GUIDED) -> None:
    vehicle.ingest(publish=True, data=heartbeat(armed, mode, mavlink.MAV_STATE_STANDBY))
    vehicle.ingest(publish=True, data=landed(mavlink.MAV_LANDED_STATE_ON_GROUND))


# -- the rules ------------------------------------------------------------------------------------------------------
def test_no_throttle_mode_and_no_disarm_while_flying(clock, vehicle):
    flying(vehicle)
    at(clock, vehicle, 0.0)
    assert vehicle.state().may_be_airborne
    for mode in ("STABILIZE", "ACRO"):
        result = vehicle.set_mode(mode).result(timeout=5)
        assert result.status is CommandStatus.REJECTED and "throttle" in result.reason, result
    result = vehicle.disarm().result(timeout=5)
    assert result.status is CommandStatus.REJECTED and "airborne" in result.reason, result
    sent = at(clock, vehicle, 0.1)
    assert not commands(sent, ARM) and STABILIZE not in modes(sent)


def test_unknown_landed_state_counts_as_airborne(clock, vehicle):
    """No EXTENDED_SYS_STATE and a heartbeat in a failsafe (CRITICAL) say nothing of the ground: airborne."""
    vehicle.ingest(publish=True, data=heartbeat(True, GUIDED, mavlink.MAV_STATE_CRITICAL))
    at(clock, vehicle, 0.0)
    assert vehicle.state().in_air is None and vehicle.state().may_be_airborne
    assert vehicle.set_mode("STABILIZE").result(timeout=5).status is CommandStatus.REJECTED
    motor = vehicle.setup.motor_test(1, throttle_pct=5, seconds=1, propellers_removed=True).result(timeout=5)
    assert motor.status is CommandStatus.REJECTED, motor
    assert not commands(at(clock, vehicle, 0.1), mavlink.MAV_CMD_DO_MOTOR_TEST)


def test_no_motor_test_calibration_or_log_download_while_armed(clock, vehicle):
    on_the_ground(vehicle, armed=True)
    at(clock, vehicle, 0.0)
    assert not vehicle.state().may_be_airborne                      # armed on the pad: not airborne
    motor = vehicle.setup.motor_test(1, throttle_pct=5, seconds=1, propellers_removed=True).result(timeout=5)
    assert motor.status is CommandStatus.REJECTED and "armed" in motor.reason, motor
    level = vehicle.calibrate_level().result(timeout=5)
    assert level.status is CommandStatus.REJECTED and "armed" in level.reason, level
    vehicle.logs.download(1, "/tmp/never-written.bin")
    sent = []
    for tenth in range(1, 20):
        sent += at(clock, vehicle, tenth / 10)
    assert not [m for m in sent if m.get_type() in ("LOG_REQUEST_DATA", "LOG_ERASE")]
    assert not commands(sent, mavlink.MAV_CMD_DO_MOTOR_TEST) and not commands(sent, mavlink.MAV_CMD_PREFLIGHT_CALIBRATION)


def test_land_stop_and_rtl_always_go_out(clock, vehicle):
    flying(vehicle, AUTO)
    at(clock, vehicle, 0.0)
    vehicle.land()
    assert LAND in modes(at(clock, vehicle, 0.1))
    vehicle.return_to_launch()
    assert 6 in modes(at(clock, vehicle, 0.2))
    vehicle.stop()
    assert GUIDED in modes(at(clock, vehicle, 0.3))


def test_the_emergency_stop_is_the_one_disarm_in_the_air(clock, vehicle):
    flying(vehicle)
    at(clock, vehicle, 0.0)
    vehicle.disarm(force=True, emergency=True)
    sent = commands(at(clock, vehicle, 0.1), ARM)
    assert len(sent) == 1 and sent[0].param1 == 0 and sent[0].param2 == 21196


def test_a_message_that_lifts_the_vehicle_starts_may_be_airborne_until_it_reports_landed_and_disarmed(clock, vehicle):
    """NAV_TAKEOFF went out while the vehicle still says it is on the pad: from then on it may be airborne, and
    a plain disarm never goes out, until a report sent after the takeoff shows it landed and disarmed."""
    on_the_ground(vehicle, armed=True)
    at(clock, vehicle, 0.0)
    vehicle.command_long(mavlink.MAV_CMD_NAV_TAKEOFF, (0, 0, 0, 0, 0, 0, 3.0))
    assert commands(at(clock, vehicle, 0.1), mavlink.MAV_CMD_NAV_TAKEOFF)
    vehicle.ingest(publish=True, data=ack(mavlink.MAV_CMD_NAV_TAKEOFF))
    on_the_ground(vehicle, armed=True)                             # an old report, sent before it got there
    at(clock, vehicle, 0.2)
    assert vehicle.state().may_be_airborne
    assert vehicle.disarm().result(timeout=5).status is CommandStatus.REJECTED
    on_the_ground(vehicle, armed=False)                            # disarmed by itself (DISARM_DELAY)
    at(clock, vehicle, 1.0)
    assert vehicle.state().may_be_airborne                         # too soon after the takeoff to be sure
    on_the_ground(vehicle, armed=False)
    at(clock, vehicle, 6.0)
    assert not vehicle.state().may_be_airborne


# -- replies matched to their own request ---------------------------------------------------------------------------
def test_a_late_accepted_for_a_replaced_arm_settles_neither_the_disarm_nor_the_emergency_stop(clock, vehicle):
    on_the_ground(vehicle, armed=False)
    at(clock, vehicle, 0.0)
    vehicle.arm()
    assert commands(at(clock, vehicle, 0.1), ARM)                  # the arm went out, unanswered so far
    on_the_ground(vehicle, armed=False)
    stop = vehicle.disarm(force=True, emergency=True)              # replaced before its answer came
    assert commands(at(clock, vehicle, 0.2), ARM)
    vehicle.ingest(publish=True, data=ack(ARM))                                        # the arm's ACCEPTED, late
    at(clock, vehicle, 0.3)
    vehicle.ingest(publish=True, data=heartbeat(True, GUIDED, mavlink.MAV_STATE_STANDBY))   # it did arm
    at(clock, vehicle, 0.4)
    said = [r for r in vehicle.state().results if r.command == "emergency motor stop"]
    assert said == []                                              # neither answer is the emergency stop's
    for tenth in range(5, 40):
        at(clock, vehicle, tenth / 10)
    for tenth in range(40, 90):                                    # the stop's own effect, heartbeat after heartbeat
        if tenth % 10 == 0:
            on_the_ground(vehicle, armed=False)
        at(clock, vehicle, tenth / 10)
    result = stop.result(timeout=5)
    assert result.ok, result


def test_arming_is_confirmed_by_the_heartbeat_not_the_ack(clock, vehicle):
    on_the_ground(vehicle, armed=False)
    at(clock, vehicle, 0.0)
    future = vehicle.arm()
    at(clock, vehicle, 0.1)
    vehicle.ingest(publish=True, data=ack(ARM))
    at(clock, vehicle, 0.2)
    assert not future.done()
    vehicle.ingest(publish=True, data=heartbeat(True, GUIDED, mavlink.MAV_STATE_STANDBY))
    at(clock, vehicle, 0.3)
    assert future.result(timeout=5).ok


def test_commands_get_their_full_retries_once_the_link_is_back(clock, vehicle):
    on_the_ground(vehicle, armed=False)
    at(clock, vehicle, 0.0)
    future = vehicle.command_long(mavlink.MAV_CMD_DO_SET_SERVO, (9, 1500))
    sent_at = []
    for tenth in range(0, 70):                                     # lost at 3.5 s, attempts at 0, 3 and 6 s
        if commands(at(clock, vehicle, tenth / 10), mavlink.MAV_CMD_DO_SET_SERVO):
            sent_at.append(tenth / 10)
    vehicle.ingest(publish=True, data=heartbeat(False, GUIDED, mavlink.MAV_STATE_STANDBY))   # back at 7 s, before its last wait ends
    for tenth in range(70, 200):
        if commands(at(clock, vehicle, tenth / 10), mavlink.MAV_CMD_DO_SET_SERVO):
            sent_at.append(tenth / 10)
        if tenth % 10 == 0:
            vehicle.ingest(publish=True, data=heartbeat(False, GUIDED, mavlink.MAV_STATE_STANDBY))
    assert sent_at == [0.0, 3.0, 6.0, 7.0, 10.0, 13.0], sent_at      # three more once it is back
    assert future.result(timeout=5).status is CommandStatus.TIMED_OUT


# -- parameters -----------------------------------------------------------------------------------------------------
def test_an_int32_value_float32_cannot_carry_is_refused_before_anything_is_sent(clock, vehicle):
    on_the_ground(vehicle)
    vehicle.ingest(publish=True, data=frame(_enc.param_value_encode(b"LOG_BITMASK", 176126.0, mavlink.MAV_PARAM_TYPE_INT32, 900, 5)))
    at(clock, vehicle, 0.0)
    assert vehicle.parameter_metadata is not None                  # loaded: the same checks every run
    for value in (16_777_217, 2 ** 31 - 1):                        # even with the pilot's "set it anyway"
        result = vehicle.set_parameter("LOG_BITMASK", value, allow_out_of_bounds=True).result(timeout=5)
        assert result.status is CommandStatus.REJECTED and "32-bit float" in result.reason, result
    sent = at(clock, vehicle, 0.1)
    assert [m for m in sent if m.get_type() == "PARAM_SET"] == []
    vehicle.set_parameter("LOG_BITMASK", 16_777_216, allow_out_of_bounds=True)   # 2^24: float32 holds it
    sent = at(clock, vehicle, 0.2)
    assert [m.param_value for m in sent if m.get_type() == "PARAM_SET"] == [16_777_216.0]
