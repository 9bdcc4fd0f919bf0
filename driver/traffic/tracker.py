"""The contacts heard in ADSB_VEHICLE, kept per ICAO address, projected against our own track.

Only the autopilot's ADSB_VEHICLE are taken (ArduPilot forwards its receiver's); a message with impossible values
(NaN is impossible in integers, but a latitude past 90°, an unknown heading marker) keeps only what is sane.
A contact not heard for ``fade_after`` s is shown faded and never alerts; after ``drop_after`` s it is gone. Its
age counts from when the receiver last heard it: the message's ``tslc`` (time since last communication, s) plus
the time since the message came.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..core import frames
from .approach import AlertLimits, closest_approach
from .model import Contact, Traffic

__all__ = ["TrafficTracker", "FADE_AFTER", "DROP_AFTER"]

FADE_AFTER = 5.0          # s: ArduPilot repeats each aircraft about once a second
DROP_AFTER = 20.0
FLAG_COORDS, FLAG_ALT, FLAG_HEADING, FLAG_VELOCITY, FLAG_CALLSIGN = 1, 2, 4, 8, 16
FLAG_VERTICAL_VELOCITY = 128


@dataclass
class _Heard:
    msg: object
    at: float                 # monotonic


class TrafficTracker:
    def __init__(self, limits: AlertLimits = AlertLimits(), fade_after: float = FADE_AFTER,
                 drop_after: float = DROP_AFTER) -> None:
        self.limits = limits
        self.fade_after = fade_after
        self.drop_after = drop_after
        self._heard: dict[int, _Heard] = {}

    def on_adsb_vehicle(self, m, now: float) -> bool:
        """Keep the newest report of this aircraft; False when it cannot be placed."""
        if not m.flags & FLAG_COORDS or not (-90 <= m.lat * 1e-7 <= 90 and -180 <= m.lon * 1e-7 <= 180):
            return False
        self._heard[m.ICAO_address] = _Heard(m, now)
        return True

    def snapshot(self, now: float, own) -> Traffic:
        """The contacts at ``now`` against ``own`` (a VehicleState: position, velocity)."""
        for icao in [i for i, h in self._heard.items() if _age(h, now) > self.drop_after]:
            del self._heard[icao]
        contacts = [self._contact(h, now, own) for h in self._heard.values()]
        contacts.sort(key=lambda c: (c.distance is None, c.distance or 0.0))
        return Traffic(tuple(contacts))

    def _contact(self, h: _Heard, now: float, own) -> Contact:
        m = h.msg
        lat, lon = m.lat * 1e-7, m.lon * 1e-7
        alt = m.altitude / 1000.0 if m.flags & FLAG_ALT else None
        heading = (m.heading / 100.0) % 360.0 if m.flags & FLAG_HEADING and m.heading < 36000 else None
        speed = m.hor_velocity / 100.0 if m.flags & FLAG_VELOCITY else None
        climb = m.ver_velocity / 100.0 if m.flags & FLAG_VERTICAL_VELOCITY else None
        callsign = m.callsign if isinstance(m.callsign, str) else bytes(m.callsign).decode("ascii", "replace")
        callsign = callsign.rstrip("\x00").strip() if m.flags & FLAG_CALLSIGN else ""
        age = _age(h, now)
        stale = age > self.fade_after
        relative_alt = distance = bearing = approach = None
        position = own.position
        if position is not None:
            north, east = frames.offset_ned(position.lat, position.lon, lat, lon)
            distance = math.hypot(north, east)
            bearing = math.degrees(math.atan2(east, north)) % 360.0
            if alt is not None:
                relative_alt = alt - position.alt
            cvn = cve = 0.0
            if heading is not None and speed is not None:
                cvn, cve = speed * math.cos(math.radians(heading)), speed * math.sin(math.radians(heading))
            # the contact's position now: dead-reckoned over its age
            north, east = north + cvn * age, east + cve * age
            up = (relative_alt if relative_alt is not None else 0.0) + (climb or 0.0) * age
            v = own.velocity
            rel_vel = (cvn - v.north, cve - v.east, (climb or 0.0) + v.down)
            approach = closest_approach((north, east, up), rel_vel, self.limits) if relative_alt is not None \
                else None
        return Contact(m.ICAO_address, callsign, lat, lon, alt, heading, speed, climb, m.emitter_type, m.squawk,
                       age, stale, relative_alt, distance, bearing, approach)


def _age(h: _Heard, now: float) -> float:
    """Seconds since the receiver last heard the aircraft: its tslc when the autopilot sent it, and since."""
    return max(0.0, now - h.at) + float(getattr(h.msg, "tslc", 0) or 0)
