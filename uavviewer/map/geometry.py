"""Map geometry without Qt: Web-Mercator tiles and a local frame in metres around home.

The map draws in *view metres*: east/north metres from a reference point (home), measured on Web-Mercator
scaled by cos(reference latitude), so slippy-map tiles (EPSG:3857, the ``{z}/{x}/{y}`` scheme) are exact
rectangles in it and distances near the reference are true ground metres. Longitudes are unwrapped
around the reference, so a flight across the antimeridian stays one piece.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

from driver.core.frames import EARTH_RADIUS

__all__ = ["TILE_SIZE", "MAX_LAT", "MAX_ZOOM", "MapFrame", "TileKey", "mercator", "inverse_mercator",
           "tile_at", "tiles_covering", "tile_zoom_for", "nice_scale", "tile_url", "ground_resolution"]

TILE_SIZE = 256                        # pixels of a slippy-map tile
MAX_LAT = 85.05112877980659            # Web-Mercator's edge: atan(sinh(pi))
MAX_ZOOM = 19                          # OpenStreetMap's deepest level
WORLD = 2.0 * math.pi * EARTH_RADIUS   # m of Mercator x around the equator


def mercator(lat: float, lon: float) -> tuple[float, float]:
    """Web-Mercator (EPSG:3857) metres of a latitude/longitude; latitude clamped to the map's edge."""
    lat = max(-MAX_LAT, min(MAX_LAT, lat))
    x = EARTH_RADIUS * math.radians(lon)
    y = EARTH_RADIUS * math.log(math.tan(math.pi / 4.0 + math.radians(lat) / 2.0))
    return x, y


def inverse_mercator(x: float, y: float) -> tuple[float, float]:
    """(lat, lon) of Web-Mercator metres; longitude wrapped into [-180, 180)."""
    lat = math.degrees(2.0 * math.atan(math.exp(y / EARTH_RADIUS)) - math.pi / 2.0)
    lon = (math.degrees(x / EARTH_RADIUS) + 180.0) % 360.0 - 180.0
    return lat, lon


def ground_resolution(lat: float, zoom: int) -> float:
    """Ground metres a tile pixel covers at ``lat`` and ``zoom``."""
    return math.cos(math.radians(lat)) * WORLD / (TILE_SIZE * 2 ** zoom)


@dataclass(frozen=True)
class MapFrame:
    """View metres (east, north) around a reference latitude/longitude."""
    lat: float
    lon: float

    @cached_property
    def scale(self) -> float:
        """Ground metres per Mercator metre at the reference."""
        return math.cos(math.radians(max(-MAX_LAT, min(MAX_LAT, self.lat))))

    @cached_property
    def origin(self) -> tuple[float, float]:
        """The reference in Web-Mercator metres."""
        return mercator(self.lat, self.lon)

    def to_view(self, lat: float, lon: float) -> tuple[float, float]:
        return self.mercator_to_view(*mercator(lat, lon))

    def to_latlon(self, east: float, north: float) -> tuple[float, float]:
        x0, y0 = self.origin
        return inverse_mercator(x0 + east / self.scale, y0 + north / self.scale)

    def mercator_to_view(self, x: float, y: float) -> tuple[float, float]:
        """View metres of Web-Mercator metres, the short way round (across the antimeridian)."""
        x0, y0 = self.origin
        dx = (x - x0 + WORLD / 2.0) % WORLD - WORLD / 2.0
        return dx * self.scale, (y - y0) * self.scale

    def tile_rect(self, key: "TileKey", unwrap_near: float = 0.0) -> tuple[float, float, float, float]:
        """(west, north, east, south) of a tile in view metres; ``unwrap_near``: the view east metre the tile
        should be drawn near (a tile at x=0 drawn east of the antimeridian)."""
        size = WORLD / 2 ** key.z
        west_m = -WORLD / 2.0 + key.x * size
        north_m = WORLD / 2.0 - key.y * size
        w, n = self.mercator_to_view(west_m, north_m)
        span = WORLD * self.scale
        w += round((unwrap_near - w) / span) * span
        return w, n, w + size * self.scale, n - size * self.scale


@dataclass(frozen=True, order=True)
class TileKey:
    z: int
    x: int
    y: int


def tile_at(lat: float, lon: float, zoom: int) -> TileKey:
    """The tile holding a point (x wrapped round the world, y clamped to the map)."""
    n = 2 ** zoom
    x, y = mercator(lat, lon)
    tx = math.floor((x + WORLD / 2.0) / WORLD * n) % n
    ty = min(n - 1, max(0, math.floor((WORLD / 2.0 - y) / WORLD * n)))
    return TileKey(zoom, tx, ty)


def tiles_covering(frame: MapFrame, west: float, north: float, east: float, south: float, zoom: int,
                   limit: int = 4096) -> list[tuple[TileKey, float]]:
    """The tiles (and the view east metre each is drawn near) covering a view rectangle, centre first.

    At most ``limit``: a request that would take more returns an empty list (the caller zoomed too far out
    for tiles). Across the antimeridian the x index wraps and the tile is placed on the side being shown.
    """
    n = 2 ** zoom
    size = WORLD / n * frame.scale                   # view metres a tile spans
    x0, y0 = frame.origin
    fx0 = (x0 + WORLD / 2.0) / WORLD * n             # the reference in fractional tile units
    fy0 = (WORLD / 2.0 - y0) / WORLD * n
    cols = range(math.floor(fx0 + west / size), math.floor(fx0 + east / size) + 1)
    rows = range(max(0, math.floor(fy0 - north / size)), min(n - 1, math.floor(fy0 - south / size)) + 1)
    if len(cols) * len(rows) > limit or not rows:
        return []
    cx, cy = fx0 + (west + east) / 2.0 / size, fy0 - (north + south) / 2.0 / size
    cells = sorted(((col, row) for row in rows for col in cols),
                   key=lambda c: (c[0] + 0.5 - cx) ** 2 + (c[1] + 0.5 - cy) ** 2)
    return [(TileKey(zoom, col % n, row), (col - fx0) * size) for col, row in cells]


def tile_zoom_for(metres_per_pixel: float, lat: float, max_zoom: int = MAX_ZOOM) -> int:
    """The tile level whose pixels are closest to the screen's (tiles drawn between 0.7x and 1.4x)."""
    if not (metres_per_pixel > 0 and math.isfinite(metres_per_pixel)):
        return 0
    z = math.log2(math.cos(math.radians(max(-MAX_LAT, min(MAX_LAT, lat)))) * WORLD / (TILE_SIZE * metres_per_pixel))
    return max(0, min(max_zoom, round(z)))


def nice_scale(metres_per_pixel: float, max_pixels: float) -> float:
    """The longest 1, 2 or 5 x 10^n metres that fits in ``max_pixels``: the scale bar's length."""
    if not (metres_per_pixel > 0 and max_pixels > 0):
        return 0.0
    longest = metres_per_pixel * max_pixels
    base = 10 ** math.floor(math.log10(longest))
    for step in (5, 2, 1):
        if step * base <= longest:
            return step * base
    return base


def tile_url(template: str, key: TileKey) -> str:
    """``https://tile.openstreetmap.org/{z}/{x}/{y}.png`` with the tile's numbers."""
    return template.replace("{z}", str(key.z)).replace("{x}", str(key.x)).replace("{y}", str(key.y))
