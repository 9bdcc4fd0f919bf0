"""ADS-B contacts as immutable snapshots (VehicleState.traffic)."""
from __future__ import annotations

from dataclasses import dataclass, replace

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
    said: str = ""                # its threat as the driver said it in Messages when it began to alert

    @property
    def alert(self) -> bool:
        return not self.stale and self.approach is not None and self.approach.conflict

    @property
    def label(self) -> str:
        return self.callsign or f"{self.icao:06X}"

    @property
    def threat(self) -> str:
        """This aircraft's closest approach in one text, the only one: Messages, the banner and the voice all say
        it ("Traffic SIM42: 162 metres below, closest 120 metres away in 14 seconds"); the height is the one at
        that moment, as the distance is. Words, not units: the voice reads "m" as "em"."""
        a = self.approach
        if a is None:
            return ""
        height = f"{abs(a.vertical):.0f} metres {'above' if a.vertical >= 0 else 'below'}"
        return f"Traffic {self.label}: {height}, closest {a.horizontal:.0f} metres away in {a.time:.0f} seconds"


@dataclass(frozen=True)
class Traffic:
    contacts: tuple[Contact, ...] = ()

    @property
    def alerts(self) -> tuple[Contact, ...]:
        return tuple(c for c in self.contacts if c.alert)

    def contact(self, icao: int) -> Contact | None:
        return next((c for c in self.contacts if c.icao == icao), None)

    def said(self, texts: dict[int, str]) -> "Traffic":
        """These contacts with what was said of each (by ICAO address) when it began to alert."""
        return Traffic(tuple(replace(c, said=texts.get(c.icao, "")) for c in self.contacts))
