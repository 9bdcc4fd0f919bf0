"""Survey: a polygon covered by a lawnmower of camera passes (no Qt).

The camera's footprint at the survey altitude gives the spacing of the passes (side overlap) and the distance
between photos along them (front overlap); ArduPilot takes the photos itself with DO_SET_CAM_TRIGG_DIST, switched
on at the start of each pass and off at its end, so no photos are wasted in the turns. The ground sample distance
(GSD) is the ground a pixel covers, the worse of the image's two axes.

Passes run along ``angle`` (degrees clockwise from north), one every spacing across the polygon, from entry to
exit alternately; a concave polygon is flown across its gaps (each pass spans the polygon's first to last edge
on that line), as QGroundControl does.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.core.frames import offset_latlon, offset_ned
from driver.mission.plan import MissionItem

__all__ = ["Camera", "CAMERAS", "GOPRO_HERO4_BLACK", "SurveySpec", "Survey", "survey", "camera_named",
           "polygon_area"]


@dataclass(frozen=True)
class Camera:
    """A camera as photogrammetry needs it: sensor size (mm), image size (pixels), focal length (mm)."""
    name: str
    sensor_width: float
    sensor_height: float
    image_width: int
    image_height: int
    focal_length: float
    landscape: bool = True             # the image's long side across the direction of flight

    def footprint(self, altitude: float) -> tuple[float, float]:
        """Ground metres one photo covers at ``altitude``: (across the passes, along them)."""
        width = altitude * self.sensor_width / self.focal_length
        height = altitude * self.sensor_height / self.focal_length
        return (width, height) if self.landscape else (height, width)

    def gsd(self, altitude: float) -> float:
        """Ground sample distance, centimetres a pixel, at ``altitude`` (the worse of the two axes)."""
        return 100.0 * altitude * max(self.sensor_width / self.image_width,
                                      self.sensor_height / self.image_height) / self.focal_length


#: The 3DR Solo's camera: 1/2.3" sensor (6.17 x 4.55 mm), 12 MP stills (4000 x 3000), 2.98 mm lens.
GOPRO_HERO4_BLACK = Camera("GoPro HERO4 Black (3DR Solo)", 6.17, 4.55, 4000, 3000, 2.98)

#: The cameras offered, the Solo's first (sensor data as QGroundControl's camera list gives it).
CAMERAS: tuple[Camera, ...] = (
    GOPRO_HERO4_BLACK,
    Camera("Canon S100 PowerShot", 7.6, 5.7, 4000, 3000, 5.2),
    Camera("Canon SX260 HS PowerShot", 6.17, 4.55, 4000, 3000, 4.5),
    Camera("Canon G9 X PowerShot", 13.2, 8.8, 5488, 3680, 10.2),
    Camera("Parrot Sequoia RGB", 6.17, 4.63, 4608, 3456, 4.9),
    Camera("Ricoh GR II", 23.7, 15.7, 4928, 3264, 18.3),
    Camera("Sony a6000 16 mm", 23.5, 15.6, 6000, 4000, 16.0),
)


def camera_named(name: str) -> Camera:
    return next((c for c in CAMERAS if c.name == name), GOPRO_HERO4_BLACK)


@dataclass(frozen=True)
class SurveySpec:
    """What the pilot chose: the area (latitude, longitude vertices), altitude above home, camera, overlaps
    (0..0.95) and the direction of the passes."""
    polygon: tuple[tuple[float, float], ...]
    altitude: float = 30.0
    camera: Camera = GOPRO_HERO4_BLACK
    front_overlap: float = 0.70
    side_overlap: float = 0.60
    angle: float = 0.0                 # degrees clockwise from north

    def valid(self) -> bool:
        return (len(self.polygon) >= 3 and self.altitude > 0
                and 0.0 <= self.front_overlap <= 0.95 and 0.0 <= self.side_overlap <= 0.95
                and all(math.isfinite(v) for p in self.polygon for v in p)
                and math.isfinite(self.altitude) and math.isfinite(self.angle))


@dataclass(frozen=True)
class Survey:
    """What a spec gives: the items to fly and the figures the pilot judges it by."""
    items: tuple[MissionItem, ...]
    passes: tuple[tuple[tuple[float, float], tuple[float, float]], ...]   # (entry, exit) latitude/longitude
    spacing: float                     # m between passes
    trigger_distance: float            # m between photos
    gsd: float                         # cm a pixel
    photos: int
    area: float                        # m² of the polygon
    length: float                      # m flown along the passes


def polygon_area(points: list[tuple[float, float]]) -> float:
    """Area of a simple polygon in plane metres (shoelace)."""
    return abs(sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in zip(points, points[1:] + points[:1]))) / 2.0


def survey(spec: SurveySpec) -> Survey:
    """The lawnmower over ``spec.polygon``: for each pass, its entry waypoint, camera on, its exit waypoint,
    camera off."""
    cam = spec.camera
    across, along = cam.footprint(spec.altitude)
    spacing = max(0.5, across * (1.0 - spec.side_overlap))
    trigger = max(0.1, along * (1.0 - spec.front_overlap))
    gsd = cam.gsd(spec.altitude)
    if not spec.valid():
        return Survey((), (), spacing, trigger, gsd, 0, 0.0, 0.0)
    lat0, lon0 = spec.polygon[0]
    local = [offset_ned(lat0, lon0, lat, lon) for lat, lon in spec.polygon]      # (north, east)
    a = math.radians(spec.angle)
    ua, va = (math.cos(a), math.sin(a)), (-math.sin(a), math.cos(a))              # along, across: (north, east)
    uv = [(n * ua[0] + e * ua[1], n * va[0] + e * va[1]) for n, e in local]
    area = polygon_area([(e, n) for n, e in local])
    vmin, vmax = min(v for _, v in uv), max(v for _, v in uv)
    count = max(1, math.ceil((vmax - vmin) / spacing - 1e-9))
    first = (vmin + vmax) / 2.0 - (count - 1) * spacing / 2.0                     # centred across the area
    passes, items, length, photos = [], [], 0.0, 0
    for k in range(count):
        v = first + k * spacing
        cuts = sorted(_crossings(uv, v))
        if len(cuts) < 2:
            continue
        u0, u1 = cuts[0], cuts[-1]
        if len(passes) % 2:
            u0, u1 = u1, u0
        ends = []
        for u in (u0, u1):
            north, east = u * ua[0] + v * va[0], u * ua[1] + v * va[1]
            ends.append(offset_latlon(lat0, lon0, north, east))
        passes.append((ends[0], ends[1]))
        length += abs(u1 - u0)
        photos += int(abs(u1 - u0) // trigger) + 1
        items += [_waypoint(*ends[0], spec.altitude), _trigger(trigger),
                  _waypoint(*ends[1], spec.altitude), _trigger(0.0)]
    return Survey(tuple(items), tuple(passes), spacing, trigger, gsd, photos, area, length)


def _crossings(uv: list[tuple[float, float]], v: float) -> list[float]:
    out = []
    for (u0, v0), (u1, v1) in zip(uv, uv[1:] + uv[:1]):
        if (v0 <= v < v1) or (v1 <= v < v0):
            out.append(u0 + (v - v0) * (u1 - u0) / (v1 - v0))
    return out


def _waypoint(lat: float, lon: float, alt: float) -> MissionItem:
    return MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, lat=lat, lon=lon, alt=alt)


def _trigger(distance: float) -> MissionItem:
    """DO_SET_CAM_TRIGG_DIST: a photo every ``distance`` m (0: stop), the first at once."""
    return MissionItem(mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST, frame=mavlink.MAV_FRAME_MISSION,
                       param1=distance, param3=1.0 if distance > 0 else 0.0)
