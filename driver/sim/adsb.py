"""Simulated ADS-B traffic, as ArduCopter 4.6.3 SITL forwards it (tests/data/recordings/arducopter-4.6-sitl-adsb).

``SimConfig.adsb`` aircraft (SIM_ADSB_COUNT) within SIM_ADSB_RADIUS (1500 m) of home at SIM_ADSB_ALT (300 m)
and above; the autopilot itself (its own system and component) sends one ADSB_VEHICLE per aircraft about once
a second from about 9 s after boot: ICAO a random number below 10000, callsign "SIM" + that number, altitude_type
0 (QNH) in mm, heading in centidegrees, speeds in cm/s, emitter type random 0-19 (19, a point obstacle, stands
still), tslc 1, flags 511, squawk 1200. An aircraft that leaves the radius comes back under a new ICAO address.

Only when asked, as ArduPilot: ADSB_VEHICLE is in no MAV_DATA_STREAM (its stream is SRn_ADSB, 0 by default), so
a ground station gets traffic only after SET_MESSAGE_INTERVAL (checked against 4.6.3 SITL: nothing in 40 s
unasked; 60 in 12 s after asking 5 Hz). Each time the interval comes round the next aircraft of the list is sent,
and a new round of the list starts at most once a second (AP_ADSB::send_adsb_vehicle).
A test adds its own track with :meth:`Traffic.add_aircraft`. ArduCopter 3.3 (the Solo) has no ADS-B: nothing.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["AdsbTraffic", "Aircraft"]

RADIUS = 1500.0                 # m (SIM_ADSB_RADIUS)
BASE_ALT = 300.0                # m above sea level (SIM_ADSB_ALT)
FIRST_AFTER = 9.0               # s after boot (recording: 9.2 s)
LIST_INTERVAL = 1.0             # s: a new round of the list starts at most this often (AP_ADSB::send_adsb_vehicle)
FLAGS = 511
FLAG_HEADING = 4                # ADSB_FLAGS_VALID_HEADING


@dataclass
class Aircraft:
    icao: int
    north: float                # m from home
    east: float
    alt: float                  # m above sea level
    heading: float | None       # degrees; None: the receiver heard no heading (flag 4 clear, standing still)
    speed: float                # m/s
    climb: float                # m/s, up
    emitter: int
    fixed: bool = False         # a test's track: never respawned


class AdsbTraffic:
    """The aircraft around the simulated vehicle; stepped by the Autopilot."""

    def _adsb_init(self) -> None:
        self.aircraft: list[Aircraft] = []
        self._adsb_index, self._adsb_round = 0, -LIST_INTERVAL     # the list's next aircraft; when its round began
        count = int(getattr(self.config, "adsb", 0) or 0)
        if self.profile.mavlink2:                     # 4.x only: 3.3 had no AP_ADSB
            self.aircraft = [self._spawn() for _ in range(count)]

    def _spawn(self) -> Aircraft:
        rng = self.rng
        emitter = rng.randrange(20)
        still = emitter == 19
        r, bearing = RADIUS * math.sqrt(rng.random()), rng.uniform(0, 2 * math.pi)
        return Aircraft(icao=rng.randrange(1, 10000), north=r * math.cos(bearing), east=r * math.sin(bearing),
                        alt=BASE_ALT + rng.uniform(0, 200), heading=0.0 if still else rng.uniform(0, 360),
                        speed=0.0 if still else rng.uniform(10, 150), climb=0.0 if still else rng.uniform(0, 9),
                        emitter=emitter)

    def add_aircraft(self, icao: int, north: float, east: float, alt: float, heading: float | None, speed: float,
                     climb: float = 0.0) -> Aircraft:
        """A test's own aircraft (m from home, m above sea level, degrees, m/s): flown straight, never replaced;
        heading None: sent without a heading (and it stands still)."""
        aircraft = Aircraft(icao, north, east, alt, heading, speed, climb, emitter=1, fixed=True)
        self.aircraft.append(aircraft)
        return aircraft

    def _adsb_step(self, dt: float) -> None:
        for i, a in enumerate(self.aircraft):
            if a.heading is None:
                continue
            rad = math.radians(a.heading)
            a.north += a.speed * math.cos(rad) * dt
            a.east += a.speed * math.sin(rad) * dt
            a.alt += a.climb * dt
            if not a.fixed and math.hypot(a.north, a.east) > RADIUS:
                self.aircraft[i] = self._spawn()

    def _msg_adsb_vehicle(self):
        """The next aircraft of the list, each time the asked interval comes round (None: nothing to send now)."""
        if self.boot_seconds < FIRST_AFTER or not self.aircraft:
            return None
        if self._adsb_index >= len(self.aircraft):
            if self.t - self._adsb_round < LIST_INTERVAL:
                return None                             # too soon to start a new round
            self._adsb_index = 0
        if self._adsb_index == 0:
            self._adsb_round = self.t
        a = self.aircraft[self._adsb_index]
        self._adsb_index += 1
        lat = self.home_lat + a.north / 111319.49079327357
        lon = self.home_lon + a.east / self.m_per_deg_lon
        callsign = f"SIM{a.icao}".encode()[:9]
        return self.factory.adsb_vehicle_encode(
            a.icao, int(lat * 1e7), int(lon * 1e7), 0, int(a.alt * 1000), int((a.heading or 0.0) * 100) % 36000,
            int(a.speed * 100), int(a.climb * 100), callsign, a.emitter, 1,
            FLAGS if a.heading is not None else FLAGS & ~FLAG_HEADING, 1200)
