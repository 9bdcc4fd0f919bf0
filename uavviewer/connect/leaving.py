"""What the pilot is told before the window lets go of a vehicle in the air (connect elsewhere, disconnect). No Qt."""
from __future__ import annotations

from driver.vehicle.rules import gcs_failsafe_setting, unattended
from driver.vehicle.state import VehicleState

__all__ = ["leaving_words"]


def leaving_words(s: VehicleState, disconnecting: bool = False) -> str:
    """Where it is, in which mode, what it does unattended, and its own GCS failsafe by the parameter's value:
    "airborne at 12 m in GUIDED; ... it will act on its own GCS failsafe: FS_GCS_ENABLE = 0, none". The last
    sentence says what happens next: a new connection is tried beside this one, while a disconnect lets go now."""
    mode = s.mode or "an unknown mode"
    then = ("Disconnect lets go of it now, and no other vehicle is connected: File › Connect finds it again."
            if disconnecting else
            "The new connection is tried beside this one: this vehicle stays flown until the new one answers.")
    return (f"The vehicle is airborne at {s.altitude:.0f} m in {mode}. Once this window lets go of it, it is sent "
            f"zero velocity and nobody commands it: {unattended(s.mode, s.gcs_failsafe)}.\n\n"
            f"It will act on its own GCS failsafe: {gcs_failsafe_setting(s.gcs_failsafe)}.\n\n{then}")
