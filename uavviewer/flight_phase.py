"""What the vehicle is doing, in the pilot's words, read from the snapshot (never a local flag)."""
from __future__ import annotations

import enum

from driver.rules import arming_refusal
from driver.state import LandedState, LinkStatus, VehicleState

#: The one wording, everywhere in the window, for "nothing heard from a vehicle yet".
NO_VEHICLE = "No vehicle yet"

__all__ = ["NO_VEHICLE", "FlightPhase", "flight_phase", "takeoff_progress", "takeoff_cancellable", "stick_hint",
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
    from driver.state import SequencePhase
    return s.takeoff.phase in (SequencePhase.WAITING_READY, SequencePhase.SETTING_GUIDED, SequencePhase.ARMING)


def takeoff_progress(s: VehicleState) -> float:
    """0..1 of the takeoff sequence: arming counts a little, the climb the rest."""
    from driver.state import SequencePhase
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


def stick_hint(s: VehicleState) -> str:
    """Why the sticks are inert, or "" when they fly the vehicle."""
    why = s.velocity_blocker
    if why == "no link" and s.link.status is LinkStatus.WAITING:
        return NO_VEHICLE
    if why == "not GUIDED":
        return f"Sticks fly in GUIDED\n(mode is {s.mode or '?'})"
    return _STICK_HINTS.get(why, why)


def readiness_text(s: VehicleState) -> str:
    """On the ground: what the autopilot still waits for before it can arm, the mode to switch to when this one
    cannot be armed (RTL, LAND, ...), or "ready to arm"."""
    missing = s.readiness.missing
    if missing:
        return "waiting for " + ", ".join(missing)
    return arming_refusal(s.mode) or "ready to arm"
