"""Flight rules every front end shows but only the driver decides: altitude and distance limits, and which
modes a pilot without an RC transmitter should not pick in flight. The viewer and the console only word
them."""
from __future__ import annotations

import math

from pymavlink import mavutil

from ..core import frames

__all__ = ["COPTER_MODES", "MIN_TAKEOFF_ALTITUDE", "MAX_TAKEOFF_ALTITUDE", "TAKEOFF_ALTITUDE_RANGE", "MAX_ALTITUDE",
           "MIN_GOTO_ALTITUDE", "THROTTLE_MODES", "takeoff_altitude_problem", "go_to_problem", "mode_warning",
           "mode_refusal",
           "arming_consequence", "DISARM_DELAY", "unattended", "GCS_FAILSAFE_ACTIONS", "NOT_ARMABLE_MODES",
           "ARM_IN", "arming_refusal", "gcs_failsafe_setting"]

#: ArduCopter custom_mode numbers by name, from pymavlink's own table.
COPTER_MODES: dict[str, int] = {name: number for number, name in mavutil.mode_mapping_acm.items()}

MIN_TAKEOFF_ALTITUDE = 1.0         # m above home: lower is no takeoff (ground effect, a prop wash in the grass)
MAX_TAKEOFF_ALTITUDE = 50.0        # m above home: a takeoff climbs straight up; higher is a go-to's job
MAX_ALTITUDE = 120.0               # m above home: no go-to target above it (EU open category)
#: The one takeoff altitude range: window (Preferences, --takeoff-altitude), driver CLI, console and Ice.
TAKEOFF_ALTITUDE_RANGE = (MIN_TAKEOFF_ALTITUDE, MAX_TAKEOFF_ALTITUDE)
MIN_GOTO_ALTITUDE = 1.0            # m above home

#: Modes in which ArduCopter takes the throttle from the RC transmitter's stick: the flight rules never command
#: the first ones while the vehicle may be airborne (driver.vehicle.safety: has_manual_throttle() in mode.h; with no
#: transmitter the throttle is zero and it falls); the others hold their altitude without one
#: (get_pilot_desired_climb_rate is zero when no RC was ever seen) but not their position, and ask first.
THROTTLE_MODES = {
    "STABILIZE": "throttle comes straight from the RC transmitter: without one the motors go to idle and it falls",
    "ACRO": "throttle comes straight from the RC transmitter: without one the motors go to idle and it falls",
    "SYSTEMID": "throttle comes straight from the RC transmitter: without one the motors go to idle and it falls",
    "TURTLE": "throttle comes straight from the RC transmitter: without one the motors go to idle and it falls",
    "DRIFT": "climb and descent come from the RC transmitter's throttle stick and steering from its sticks: without "
             "one it holds its altitude but drifts with the wind",
    "ALT_HOLD": "climb and descent come from the RC transmitter's throttle stick: without one it holds its altitude "
                "but not its position, and drifts with the wind",
    "SPORT": "climb and descent come from the RC transmitter's throttle stick: without one it holds its altitude "
             "but not its position, and drifts with the wind",
}


def takeoff_altitude_problem(altitude: float, ceiling: float = MAX_ALTITUDE) -> str | None:
    """Why ``altitude`` cannot be a takeoff target, or None: one rule for the window, the driver, its CLI,
    console and Ice (``ceiling``: a lower configured maximum altitude)."""
    top = min(MAX_TAKEOFF_ALTITUDE, ceiling)
    if frames.finite(altitude) and MIN_TAKEOFF_ALTITUDE <= altitude <= top:
        return None
    return f"altitude must be {MIN_TAKEOFF_ALTITUDE:g} to {top:g} m"


def go_to_problem(north: float, east: float, altitude: float, max_altitude: float, max_distance: float) -> str | None:
    """Why a go-to target (metres from home) is outside the configured limits, or None."""
    if not frames.finite(north, east, altitude):
        return "coordinates are not finite numbers"
    if not MIN_GOTO_ALTITUDE <= altitude <= max_altitude or math.hypot(north, east) > max_distance:
        return (f"outside the limits: {MIN_GOTO_ALTITUDE:g} to {max_altitude:g} m above home, at most "
                f"{max_distance:g} m from it")
    return None


DISARM_DELAY = 10.0                # s: ArduCopter's default DISARM_DELAY, armed on the ground without a takeoff


#: Modes ArduCopter refuses to arm in ("Arm: Mode not armable": their Mode::allows_arming is false; AUTO only with
#: AUTO_OPTIONS' allow-arming bit, off by default). The simulator refuses the same ones (driver/sim/common.py).
NOT_ARMABLE_MODES = frozenset({"AUTO", "RTL", "CIRCLE", "LAND", "AVOID_ADSB", "SMART_RTL", "FOLLOW"})
#: The modes a pilot on a laptop arms in: GUIDED (Take off, the sticks) or LOITER (holds with no RC).
ARM_IN = ("GUIDED", "LOITER")


def arming_refusal(mode: str) -> str | None:
    """Why arming in ``mode`` will be refused, said before anyone asks the vehicle; None when it may arm."""
    if mode.upper() not in NOT_ARMABLE_MODES:
        return None
    return f"switch to {' or '.join(ARM_IN)} to arm"


def arming_consequence(mode: str) -> str:
    """What arming on the ground in ``mode`` does, in a pilot's words (one wording for every front end)."""
    why = THROTTLE_MODES.get(mode.upper())
    if why is not None:
        return (f"The motors start and idle. {mode.upper()} takes its throttle from an RC transmitter: without one "
                f"nothing lifts off, and ArduCopter disarms again after about {DISARM_DELAY:.0f} s (DISARM_DELAY). "
                "To fly from here, use Take off instead: it arms in GUIDED and climbs.")
    return (f"The motors start and idle. Without a takeoff within about {DISARM_DELAY:.0f} s ArduCopter disarms "
            "again (DISARM_DELAY). Take off arms by itself: you rarely need Arm.")


#: FS_GCS_ENABLE: what ArduCopter does once the ground station's heartbeats stop (GCS failsafe, after
#: FS_GCS_TIMEOUT, 5 s by default), from its parameter documentation.
GCS_FAILSAFE_ACTIONS = {1: "returns home (RTL)", 2: "continues its mission in AUTO, else returns home (RTL)",
                        3: "returns along its path (SmartRTL), else RTL", 4: "returns along its path (SmartRTL), "
                        "else lands", 5: "lands", 6: "jumps to its mission's landing (DO_LAND_START), else RTL"}
_UNATTENDED = {
    "GUIDED": "holds position in GUIDED", "LOITER": "holds position in LOITER", "POSHOLD": "holds position in "
    "POSHOLD", "BRAKE": "holds position in BRAKE", "RTL": "goes on returning home and lands there (RTL)",
    "SMART_RTL": "goes on returning along its path and lands (SmartRTL)", "LAND": "goes on landing where it is",
    "AUTO": "flies on with its mission (AUTO)", "CIRCLE": "goes on circling (CIRCLE)",
}


def gcs_failsafe_setting(gcs_failsafe: int | None) -> str:
    """The vehicle's GCS failsafe as the pilot reads it: "FS_GCS_ENABLE = 0, none"."""
    if gcs_failsafe is None:
        return "FS_GCS_ENABLE not read yet"
    if gcs_failsafe == 0:
        return "FS_GCS_ENABLE = 0, none"
    return f"FS_GCS_ENABLE = {gcs_failsafe}, {GCS_FAILSAFE_ACTIONS.get(gcs_failsafe, 'see its documentation')}"


def unattended(mode: str, gcs_failsafe: int | None) -> str:
    """What the vehicle does in ``mode`` once nobody commands it from here, in a pilot's words: the mode's own
    behaviour, then what its GCS failsafe (FS_GCS_ENABLE, None: not read yet) makes of it."""
    mode = mode.upper()
    now = _UNATTENDED.get(mode)
    if now is None:
        why = THROTTLE_MODES.get(mode)
        now = f"stays in {mode or 'its mode'}" + (f", where its {why}" if why else "")
    if gcs_failsafe is None:
        then = "until its own failsafes act (its GCS failsafe setting is not known yet)"
    elif gcs_failsafe == 0:
        then = "until its battery failsafe acts: its GCS failsafe is off (FS_GCS_ENABLE 0)"
    else:
        action = GCS_FAILSAFE_ACTIONS.get(gcs_failsafe, f"acts as FS_GCS_ENABLE {gcs_failsafe} says")
        then = f"until its GCS failsafe notices the silence (FS_GCS_TIMEOUT, 5 s by default) and {action}"
    return f"it {now} {then}"


def mode_refusal(mode: str, may_be_airborne: bool) -> str | None:
    """Why the driver will not command ``mode`` now (its flight rules, driver.vehicle.safety), or None: said
    before anyone asks, so a front end can grey the mode out."""
    from .safety import MANUAL_THROTTLE_MODES
    if not may_be_airborne or mode.upper() not in MANUAL_THROTTLE_MODES:
        return None
    return (f"{mode.upper()} takes its throttle from an RC transmitter: not commanded while the vehicle may be "
            "airborne (switch on the transmitter itself)")


def mode_warning(mode: str, flying: bool) -> str | None:
    """Why switching to ``mode`` now needs the pilot's confirmation, or None when it does not (the modes the
    flight rules refuse outright: :func:`mode_refusal`)."""
    why = THROTTLE_MODES.get(mode.upper())
    if not flying or why is None:
        return None
    return f"{mode.upper()} in flight: its {why}. Only with an RC transmitter in hand."
