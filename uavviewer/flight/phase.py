"""What the vehicle is doing, in the pilot's words, read from the snapshot (never a local flag)."""
from __future__ import annotations

import enum

from driver.vehicle.rules import arming_refusal
from driver.vehicle.state import LandedState, LinkStatus, VehicleState

#: The one wording, everywhere in the window, for "nothing heard from a vehicle yet".
NO_VEHICLE = "No vehicle yet"
#: ... and for "no vehicle at all": after File › Disconnect (the link closed, no vehicle ever heard on it).
NOT_CONNECTED = "Not connected"

__all__ = ["NO_VEHICLE", "NOT_CONNECTED", "no_vehicle_words", "no_link_flag", "link_gone_text", "FlightPhase",
           "flight_phase", "takeoff_progress", "takeoff_cancellable", "stick_hint",
           "readiness_text"]


class FlightPhase(enum.Enum):
    NO_VEHICLE = "no vehicle"
    ON_GROUND = "on ground"
    TAKING_OFF = "taking off"
    FLYING = "flying"
    LANDING = "landing"

    @property
    def airborne(self) -> bool:
        return self in (FlightPhase.TAKING_OFF, FlightPhase.FLYING, FlightPhase.LANDING)


def flight_phase(s: VehicleState) -> FlightPhase:
    if s.link.status is LinkStatus.WAITING or (not s.mode and s.link.status is not LinkStatus.OK):
        return FlightPhase.NO_VEHICLE
    if s.takeoff.active:
        return FlightPhase.TAKING_OFF
    if not s.flying:
        return FlightPhase.ON_GROUND
    if s.landed_state is LandedState.LANDING or s.mode == "LAND":
        return FlightPhase.LANDING
    if s.landed_state is LandedState.TAKEOFF:
        return FlightPhase.TAKING_OFF
    return FlightPhase.FLYING


def takeoff_cancellable(s: VehicleState) -> bool:
    """A takeoff under way that has not asked the vehicle to leave the ground yet: Cancel gives it back."""
    from driver.vehicle.state import SequencePhase
    return s.takeoff.phase in (SequencePhase.WAITING_READY, SequencePhase.SETTING_GUIDED, SequencePhase.ARMING)


def takeoff_progress(s: VehicleState) -> float:
    """0..1 of the takeoff sequence: arming counts a little, the climb the rest."""
    from driver.vehicle.state import SequencePhase
    phase = s.takeoff.phase
    early = {SequencePhase.WAITING_READY: 0.02, SequencePhase.SETTING_GUIDED: 0.05,
             SequencePhase.ARMING: 0.1}
    if phase in early:
        return early[phase]
    if phase is SequencePhase.DONE:
        return 1.0
    target = s.takeoff.target_altitude
    if target <= 0:
        return 0.1
    return max(0.1, min(1.0, 0.1 + 0.9 * s.altitude / target))


_STICK_HINTS = {"no link": "No link", "on the ground": "Take off to fly", "taking off": "Taking off…",
                "landing": "Landing…"}


def no_vehicle_words(s: VehicleState) -> str:
    """"Not connected" once the window holds no link (File › Disconnect), else "No vehicle yet": one wording
    each, on every widget that says there is no vehicle."""
    return NOT_CONNECTED if s.link.status is LinkStatus.CLOSED and not s.mode else NO_VEHICLE


def no_link_flag(s: VehicleState) -> str:
    """The attitude indicator's flag once the link is gone: REPLAY ENDED, NOT CONNECTED or NO LINK."""
    return (s.link.ended_words or ("" if s.mode else no_vehicle_words(s))).upper() or "NO LINK"


def link_gone_text(s: VehicleState, last: str) -> str:
    """The phase line once the link is gone; ``last``: what the vehicle was last heard doing."""
    if s.link.replay_ended:
        return f"{s.link.ended_words} · its last moment: {last}"
    age = s.link.heartbeat_age
    return f"Link lost{f' {age:.0f} s ago' if age is not None else ''} · last heard {last}"


def stick_hint(s: VehicleState) -> str:
    """Why the sticks are inert, or "" when they fly the vehicle."""
    why = s.velocity_blocker
    if why == "no link" and (s.link.status is LinkStatus.WAITING or not s.mode):
        return no_vehicle_words(s)
    if why == "not GUIDED":
        return f"Sticks fly in GUIDED\n(mode is {s.mode or '?'})"
    return _STICK_HINTS.get(why, why)


def readiness_text(s: VehicleState) -> str:
    """On the ground: why the vehicle says it will not arm (its own pre-arm reasons, until it says they pass),
    what the autopilot still waits for before it can arm, the mode to switch to when this one cannot be armed
    (RTL, LAND, ...), or "ready to arm"."""
    reasons = s.readiness.reasons
    if reasons:                             # the first in the phase line's two lines; all of them in Preflight
        return "not ready to arm: " + reasons[0] + (f" (+{len(reasons) - 1} more)" if len(reasons) > 1 else "")
    missing = s.readiness.missing
    if missing:
        return "waiting for " + ", ".join(missing)
    return arming_refusal(s.mode) or "ready to arm"
