"""The flight rules the driver cannot break, enforced in one place that every message to the vehicle passes.

Whatever part asks (the pilot's buttons, a takeoff or mission sequence, setup, the logs, a smart shot, the
console, an Ice client), everything the driver sends goes out through the ticker, and the ticker hands every
message to :meth:`FlightRules.screen` before the write. Commands are also checked when they are asked
(:meth:`FlightRules.command_problem`, the same rules), so the pilot hears the reason at once; the screen at the
wire is what makes the rules hold even for a part that forgets to ask.

The rules:

* **May be airborne** (:class:`AirborneLatch`) starts with the first message that can lift the vehicle
  (NAV_TAKEOFF, MISSION_START, AUTO while armed, arming in AUTO) or with the vehicle's own word that it is not
  on the ground (an unknown landed state counts as airborne), and once started by such a message it ends only
  when the vehicle reports itself landed *and* disarmed, in a report sent after that message could have reached
  it.
* While the vehicle may be airborne, no mode that takes its throttle from the pilot's stick is commanded: the
  modes whose ``has_manual_throttle()`` is true in ArduCopter 4.6's mode.h (STABILIZE, ACRO, SYSTEMID, TURTLE).
  Without an RC transmitter their throttle is zero and the vehicle falls.
* While the vehicle may be airborne, no disarm goes out but the emergency motor stop the pilot confirmed
  (:meth:`FlightRules.allow_emergency_stop`).
* No motor test, calibration, reboot, log download or log erase starts while the vehicle is armed or may be
  airborne.
* Land, Stop (GUIDED with zero velocity, BRAKE), RTL and the pause of a mission (BRAKE) always pass.
"""
from __future__ import annotations

import logging
import math
import struct

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .state import VehicleState

log = logging.getLogger("driver.vehicle")

__all__ = ["FlightRules", "AirborneLatch", "MANUAL_THROTTLE_MODES", "ARM_FORCE_MAGIC"]

#: ArduCopter's modes whose has_manual_throttle() is true (ArduCopter/mode.h, 4.6.3): their throttle is the RC
#: transmitter's stick, zero without one. Never commanded while the vehicle may be airborne.
MANUAL_THROTTLE_MODES = {"STABILIZE": 0, "ACRO": 1, "SYSTEMID": 25, "TURTLE": 28}
_MANUAL_THROTTLE_NUMBERS = frozenset(MANUAL_THROTTLE_MODES.values())
AUTO = 3
ARM_FORCE_MAGIC = 21196               # param2 of COMPONENT_ARM_DISARM: skip the checks (a disarm stops the motors)
#: How long after the last message that can lift the vehicle a "landed and disarmed" heartbeat still may have
#: left the vehicle before that message reached it (a 2 s latency each way is the worst link the driver is
#: tried on; a heartbeat a second on top).
LIFT_SETTLE = 5.0
#: s the pilot's confirmed emergency stop may take to go out (its retries included).
EMERGENCY_WINDOW = 15.0
#: s beyond its own run a motor test may keep the vehicle armed: the request on its way, a loop to end it.
MOTOR_TEST_MARGIN = 2.0

#: Commands that only make sense disarmed on the ground: motor test, calibrations, reboot, log erase.
GROUND_ONLY_COMMANDS = {
    mavlink.MAV_CMD_DO_MOTOR_TEST: "motor test",
    mavlink.MAV_CMD_PREFLIGHT_CALIBRATION: "calibration",
    mavlink.MAV_CMD_DO_START_MAG_CAL: "compass calibration",
    mavlink.MAV_CMD_FIXED_MAG_CAL_YAW: "compass calibration",
    mavlink.MAV_CMD_ACCELCAL_VEHICLE_POS: "accelerometer calibration",
    mavlink.MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN: "reboot",
}
#: ...and messages of the same kind: a log's data asked, or the logs erased.
GROUND_ONLY_MESSAGES = {"LOG_REQUEST_DATA": "log download", "LOG_ERASE": "log erase"}
FTP_OPEN_FILE_RO = 4
FTP_LOG_FOLDERS = (b"/APM/LOGS", b"logs", b"@SYS/logs")
_FTP_HEADER = struct.Struct("<HBBBBBBI")


class AirborneLatch:
    """Whether the vehicle may be in the air: the cautious union of what we sent and what it says."""

    def __init__(self) -> None:
        self.lifted_at: float | None = None       # when the last message that can lift it went out

    @property
    def lifted(self) -> bool:
        return self.lifted_at is not None

    def may_be_airborne(self, s: VehicleState) -> bool:
        """Not known to be on the ground (the vehicle's own landed state, unknown counting as airborne), armed in
        AUTO (its mission lifts it at the first MISSION_START, from anyone), or lifted and not seen landed and
        disarmed since. Armed on the ground before anything lifted it is not airborne. (VehicleState's own
        ``may_be_airborne`` says the same from the published ``lifted``.)"""
        return self.lifted or s.in_air is not False or (s.armed and s.mode == "AUTO")

    def lift(self, now: float) -> None:
        """A message that can lift the vehicle goes out now."""
        self.lifted_at = now

    def observe(self, s: VehicleState, now: float) -> None:
        """The vehicle's report: landed and disarmed, long enough after the last lift, ends the latch."""
        if self.lifted_at is not None and not s.armed and s.in_air is False and now >= self.lifted_at + LIFT_SETTLE:
            self.lifted_at = None


class FlightRules:
    """The gate. Called with the vehicle's state lock held (the ticker's step, the command paths)."""

    def __init__(self, arming_in_doubt=lambda now, judged: False) -> None:
        self.airborne = AirborneLatch()
        self._emergency_until = -math.inf
        self._arming_in_doubt = arming_in_doubt    # (now, the command judged) -> another arm, disarm or motor test
                                                   # of ours may still change the armed bit (a motor test arms)
        self._motor_test_until = -math.inf         # a motor test that went out may run (armed) until then
        self.blocked = 0                           # messages held back at the wire (a part that did not ask)

    # -- what the pilot and the parts ask --------------------------------------------------------------
    def may_be_airborne(self, s: VehicleState) -> bool:
        return self.airborne.may_be_airborne(s)

    def allow_emergency_stop(self, now: float) -> None:
        """The pilot confirmed the emergency motor stop: a forced disarm may go out, even in the air."""
        self._emergency_until = now + EMERGENCY_WINDOW

    def mode_problem(self, mode: int, s: VehicleState) -> str | None:
        """Why switching to ``mode`` (custom_mode) is not sent now, or None."""
        if mode in _MANUAL_THROTTLE_NUMBERS and self.may_be_airborne(s):
            name = next(n for n, v in MANUAL_THROTTLE_MODES.items() if v == mode)
            return (f"{name} takes its throttle from an RC transmitter's stick and the vehicle may be airborne: "
                    "the ground station never commands it then")
        return None

    def command_problem(self, command: int, params, s: VehicleState, now: float) -> str | None:
        """Why the COMMAND_LONG ``command`` with ``params`` is not sent now, or None."""
        if command == mavlink.MAV_CMD_DO_SET_MODE:
            return self.mode_problem(int(params[1]), s)
        if command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM and params[0] < 0.5:
            return self.disarm_problem(int(round(params[1])) == ARM_FORCE_MAGIC, s, now)
        what = GROUND_ONLY_COMMANDS.get(command)
        if what is not None:
            if command == mavlink.MAV_CMD_DO_MOTOR_TEST and params[3] == 0 and self.motor_test_may_run(s, now):
                return None                        # the stop of a running test (timeout 0) ends it, never starts
            return self.ground_problem(what, s, now, command)
        return None

    def motor_test_may_run(self, s: VehicleState, now: float) -> bool:
        """The vehicle says a test of ours runs, or one went out that may be running (armed) still."""
        return s.setup.motor_test_running or now < self._motor_test_until

    def disarm_problem(self, forced: bool, s: VehicleState, now: float) -> str | None:
        if not self.may_be_airborne(s):
            return None
        if forced and now <= self._emergency_until:
            return None
        return ("the vehicle may be airborne: only the confirmed emergency motor stop disarms it there "
                "(Land brings it down and ArduCopter disarms by itself)")

    def ground_problem(self, what: str, s: VehicleState, now: float, command: int = 0) -> str | None:
        if s.armed:
            return f"no {what} while the vehicle is armed: disarm first"
        running = now < self._motor_test_until and command != mavlink.MAV_CMD_DO_MOTOR_TEST   # (its own retries)
        if s.setup.motor_test_running or running or self._arming_in_doubt(now, command):
            return f"no {what} while an arm, a disarm or a motor test is on its way: the vehicle may be armed"
        if self.may_be_airborne(s):
            return f"no {what} while the vehicle may be airborne (it has not reported itself landed and disarmed)"
        return None

    # -- the wire ------------------------------------------------------------------------------------------
    def screen(self, msgs: list, s: VehicleState, now: float) -> list:
        """What may go out of ``msgs``, in order; a message that lifts the vehicle starts the latch here, just
        before its write. What breaks a rule is held back and logged (no part should get that far)."""
        self.airborne.observe(s, now)
        out = []
        for msg in msgs:
            problem = self.message_problem(msg, s, now)
            if problem:
                self.blocked += 1
                log.error("held back %s: %s", msg.get_type() if not isinstance(msg, bytes) else "frame", problem)
                continue
            if self._lifts(msg, s):
                self.airborne.lift(now)
            self._note_motor_test(msg, now)
            out.append(msg)
        return out

    def message_problem(self, msg, s: VehicleState, now: float) -> str | None:
        if isinstance(msg, bytes):                 # a frame packed already (SETUP_SIGNING): no command
            return None
        kind = msg.get_type()
        if kind in ("COMMAND_LONG", "COMMAND_INT"):
            params = (msg.param1, msg.param2, msg.param3, msg.param4) + (
                (msg.param5, msg.param6, msg.param7) if kind == "COMMAND_LONG" else (msg.x, msg.y, msg.z))
            return self.command_problem(msg.command, params, s, now)
        if kind == "SET_MODE":
            return self.mode_problem(msg.custom_mode, s) if _sets_custom_mode(msg) else None
        what = GROUND_ONLY_MESSAGES.get(kind)
        if what is not None:
            return self.ground_problem(what, s, now)
        if kind == "FILE_TRANSFER_PROTOCOL" and _opens_a_log(msg.payload):
            return self.ground_problem("log download", s, now)
        return None

    def _note_motor_test(self, msg, now: float) -> None:
        """A motor test going out arms the vehicle for its whole run (motor_test.cpp: each motor ``timeout`` s,
        then half that at rest); one with timeout 0 ends it at the vehicle's next loop."""
        if isinstance(msg, bytes) or msg.get_type() != "COMMAND_LONG" or msg.command != mavlink.MAV_CMD_DO_MOTOR_TEST:
            return
        seconds, count = max(0.0, msg.param4), max(1, int(msg.param5))
        self._motor_test_until = now + (1.5 * seconds * count if seconds else 0.0) + MOTOR_TEST_MARGIN

    @staticmethod
    def _lifts(msg, s: VehicleState) -> bool:
        """NAV_TAKEOFF, MISSION_START, AUTO while armed, arming while in AUTO."""
        if isinstance(msg, bytes):
            return False
        kind = msg.get_type()
        if kind == "SET_MODE":
            return _sets_custom_mode(msg) and msg.custom_mode == AUTO and s.armed
        if kind not in ("COMMAND_LONG", "COMMAND_INT"):
            return False
        command = msg.command
        if command in (mavlink.MAV_CMD_NAV_TAKEOFF, mavlink.MAV_CMD_MISSION_START):
            return True
        if command == mavlink.MAV_CMD_DO_SET_MODE:
            return int(msg.param2) == AUTO and s.armed
        if command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
            return msg.param1 >= 0.5 and s.mode == "AUTO"
        return False


def _sets_custom_mode(msg) -> bool:
    """A SET_MODE that changes the flight mode (not the safety switch, which is SET_MODE too)."""
    return bool(msg.base_mode & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED)


def _opens_a_log(payload) -> bool:
    """An FTP OpenFileRO of a file in a log folder."""
    data = bytes(payload)
    if len(data) < _FTP_HEADER.size:
        return False
    _, _, opcode, size, *_ = _FTP_HEADER.unpack_from(data)
    if opcode != FTP_OPEN_FILE_RO:
        return False
    path = data[_FTP_HEADER.size:_FTP_HEADER.size + size].rstrip(b"\x00")
    return any(path.startswith(folder) for folder in FTP_LOG_FOLDERS)
