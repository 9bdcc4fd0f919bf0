"""ADS-B contacts as immutable snapshots (VehicleState.traffic)."""
from __future__ import annotations

from dataclasses import dataclass

from .approach import Approach

__all__ = ["Contact", "Traffic"]


@dataclass(frozen=True)
class Contact:
    icao: int
    callsign: str
    lat: float                    # degrees
    lon: float
    alt: float | None             # m above sea level (the contact's own, QNH or GNSS), None: not sent
    heading_deg: float | None
    speed: float | None           # m/s horizontal
    climb: float | None           # m/s up
    emitter: int
    squawk: int
    age: float                    # s since it was last heard, at the snapshot
    stale: bool                   # faded: not heard for a while, dropped later
    relative_alt: float | None    # m above (+) or below (-) us, None when either altitude is unknown
    distance: float | None        # m horizontally from us, None before we know our position
    bearing_deg: float | None     # from us, clockwise from north
    approach: Approach | None     # the projected closest approach, None without our position

    @property
    def alert(self) -> bool:
        return not self.stale and self.approach is not None and self.approach.conflict

    @property
    def label(self) -> str:
        return self.callsign or f"{self.icao:06X}"


@dataclass(frozen=True)
class Traffic:
    contacts: tuple[Contact, ...] = ()

    @property
    def alerts(self) -> tuple[Contact, ...]:
        return tuple(c for c in self.contacts if c.alert)

    def contact(self, icao: int) -> Contact | None:
        return next((c for c in self.contacts if c.icao == icao), None)
