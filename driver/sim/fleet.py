"""Several simulated vehicles at once, for a lab demo or a test: distinct system ids and homes.

Vehicle ``i`` (from 0) has system id ``i + 1`` and its home ``spacing`` metres east of the previous one's,
facing the same way, so on a map they stand in a row and never start inside each other.
"""
from __future__ import annotations

import math
from dataclasses import replace

from .vehicle import SimConfig

SPACING_M = 10.0
EARTH_RADIUS_M = 6378137.0


def fleet_configs(count: int, base: SimConfig | None = None, spacing: float = SPACING_M) -> list[SimConfig]:
    """``count`` configurations like ``base``; TCP ports from ``base.tcp_port`` up (0 stays 0: any free port)."""
    base = base if base is not None else SimConfig()
    if not 1 <= count <= 250:
        raise ValueError("a fleet is 1 to 250 simulated vehicles (MAVLink system ids 1 to 250)")
    lat, lon, alt, heading = base.home
    configs = []
    for i in range(count):
        east = i * spacing
        dlon = math.degrees(east / (EARTH_RADIUS_M * math.cos(math.radians(lat))))
        port = base.tcp_port + i if base.tcp_port else base.tcp_port
        configs.append(replace(base, system_id=base.system_id + i, home=(lat, lon + dlon, alt, heading), tcp_port=port,
                               seed=None if base.seed is None else base.seed + i))
    return configs
