"""The link's protection in the pilot's words: MAVLink 2 signing and the UDP link pinned to the vehicle.

Read from the snapshot (``VehicleState.signing``, ``LinkHealth.foreign_packets`` and ``pinned_to``); the
window, the telemetry panel and Preferences all word it the same way from here.
"""
from __future__ import annotations

from driver.vehicle.api import Drone
from driver.vehicle.state import LinkHealth, Signing, SigningStatus

__all__ = ["SIGNING_WARNINGS", "signing_warning", "signed_frames", "foreign_text", "foreign_tooltip",
           "signing_unavailable"]

#: Signing states the pilot must act on: the vehicle ignores us, or we ignore it.
SIGNING_WARNINGS = frozenset({SigningStatus.REQUIRED, SigningStatus.MISMATCH, SigningStatus.UNAVAILABLE})

_BANNER = {
    SigningStatus.REQUIRED: "The vehicle requires signing: it ignores our commands — give its key in "
                            "Settings › Preferences › Link security",
    SigningStatus.MISMATCH: "Signing key mismatch: the vehicle's frames do not verify with our key",
    SigningStatus.UNAVAILABLE: "MAVLink 1: this link cannot be signed — the vehicle's frames are dropped",
}


def signing_warning(signing: Signing) -> str:
    """A line for the link banner when signing stands between the pilot and the vehicle, else ""."""
    return _BANNER.get(signing.status, "")


def signed_frames(signing: Signing) -> str:
    """The counts in a few words for a narrow column: "1200 verified · 3 dropped · 5 let in" ("" if none)."""
    dropped = signing.bad_signature + signing.unsigned_rejected
    parts = [f"{n} {what}" for n, what in ((signing.signed_accepted, "verified"), (dropped, "dropped"),
                                            (signing.unsigned_accepted, "let in")) if n]
    return " · ".join(parts)


def foreign_text(link: LinkHealth) -> str:
    n = link.foreign_packets
    return "0" if n == 0 else f"{n} ignored"


def foreign_tooltip(link: LinkHealth) -> str:
    if link.pinned_to:
        return (f"Datagrams from other addresses, ignored: the link is pinned to the vehicle at {link.pinned_to} "
                f"and sends to nobody else ({link.foreign_packets} so far)")
    return "Datagrams from other addresses are ignored once a UDP link is pinned to its vehicle"


def signing_unavailable(drone: Drone) -> str:
    """Why this drone cannot be signed from here ("" when it can): a remote (Ice) drone is signed on its server."""
    return drone.signing_unavailable
