"""The map's geometry (uavviewer.map.geometry) and trail (uavviewer.map.trail): numbers, no Qt."""
from __future__ import annotations

import math

import pytest

from driver.core import frames
from uavviewer.map.geometry import (MapFrame, TileKey, ground_resolution, inverse_mercator, mercator, nice_scale, tile_at,
                           tile_url, tile_zoom_for, tiles_covering)
from uavviewer.map.trail import TRAIL_SECONDS, Trail

CANBERRA = (-35.363261, 149.165230)          # the recordings' home
SVALBARD = (78.2232, 15.6267)                # high latitude: a Mercator metre is a fifth of a ground metre
FIJI_EDGE = (-16.5, 179.9995)                # 50 m west of the antimeridian
CHUKOTKA_EDGE = (66.0, -179.9996)            # just east of it, far north


@pytest.mark.parametrize("home", [CANBERRA, SVALBARD, FIJI_EDGE, CHUKOTKA_EDGE])
@pytest.mark.parametrize("north, east", [(0.0, 0.0), (120.0, -45.0), (-80.0, 200.0), (5.0, -300.0)])
def test_view_metres_are_ground_metres_from_home(home, north, east):
    """A point the driver puts N/E metres from home lands N/E view metres from home, both ways, at any latitude
    and across the antimeridian (where a longitude jumps from +180 to -180)."""
    frame = MapFrame(*home)
    lat, lon = frames.offset_latlon(*home, north, east)
    assert -180.0 <= lon < 180.0
    e, n = frame.to_view(lat, lon)
    assert (e, n) == pytest.approx((east, north), abs=0.02 + 2e-4 * math.hypot(north, east))
    back = frame.to_latlon(e, n)
    assert back[0] == pytest.approx(lat, abs=1e-9)
    assert frames.wrap_lon(back[1] - lon) == pytest.approx(0.0, abs=1e-9)
    assert frames.offset_ned(*home, lat, lon) == pytest.approx((north, east), abs=1e-6)


def test_mercator_round_trip_and_the_edges_of_the_map():
    for lat, lon in (CANBERRA, SVALBARD, (0.0, -180.0), (-85.0, 179.999999)):
        back_lat, back_lon = inverse_mercator(*mercator(lat, lon))
        assert back_lat == pytest.approx(lat, abs=1e-9) and -180.0 <= back_lon <= 180.0
        assert frames.wrap_lon(back_lon - lon) == pytest.approx(0.0, abs=1e-9)
    assert mercator(89.9, 0.0) == mercator(85.05112877980659, 0.0)      # clamped to the square world
    assert mercator(0.0, 180.0)[0] == pytest.approx(20037508.342789244)


def test_tiles_by_the_slippy_map_scheme():
    assert tile_at(51.5074, -0.1278, 10) == TileKey(10, 511, 340)      # London, by OSM's formula
    assert tile_at(0.0, 0.0, 1) == TileKey(1, 1, 1)
    assert tile_at(-85.1, -180.0, 3) == TileKey(3, 0, 7)               # clamped to the last row
    assert tile_at(*FIJI_EDGE, 17).x == 2 ** 17 - 1
    assert tile_at(*CHUKOTKA_EDGE, 17).x == 0
    assert tile_url("http://h/{z}/{x}/{y}.png", TileKey(3, 4, 5)) == "http://h/3/4/5.png"


def test_tiles_covering_the_antimeridian_are_placed_side_by_side():
    frame = MapFrame(*FIJI_EDGE)
    n = 2 ** 17
    tiles = tiles_covering(frame, -300.0, 300.0, 300.0, -300.0, 17)
    xs = {key.x for key, _ in tiles}
    assert {n - 1, 0} <= xs and all(0 <= x < n for x in xs)
    assert frame.tile_rect(tiles[0][0], tiles[0][1])[0] <= 0.0 <= frame.tile_rect(tiles[0][0], tiles[0][1])[2]
    for key, near in tiles:
        west, north, east, south = frame.tile_rect(key, near)
        assert east - west == pytest.approx(ground_resolution(FIJI_EDGE[0], 17) * 256, rel=1e-6)
        assert (west < 0) == (key.x == n - 1 or key.x > n // 2)         # x = 0 is drawn east of home, not 40000 km away
        assert -1000 < west < 1000
    assert tiles_covering(frame, -5e6, 5e6, 5e6, -5e6, 17) == []          # too many: none rather than thousands


def test_tile_zoom_follows_the_screen_at_any_latitude():
    assert tile_zoom_for(ground_resolution(CANBERRA[0], 17), CANBERRA[0]) == 17
    assert tile_zoom_for(ground_resolution(SVALBARD[0], 15), SVALBARD[0]) == 15
    # high up a tile pixel of a level covers less ground: the same screen scale takes a lower level
    assert tile_zoom_for(0.3, SVALBARD[0]) == tile_zoom_for(0.3, 0.0) - 2
    assert tile_zoom_for(1e-6, 0.0) == 19 and tile_zoom_for(float("nan"), 0.0) == 0


def test_scale_bar_lengths():
    assert nice_scale(1.0, 150) == 100 and nice_scale(0.5, 150) == 50 and nice_scale(3.0, 150) == 200
    assert nice_scale(0.0, 150) == 0.0


def test_trail_keeps_ten_minutes_and_fades_by_age():
    trail = Trail()
    for i in range(1300):                              # 0.5 s and 1 m a point: 650 s of flight
        trail.add(i * 0.5, float(i), 0.0)
    assert len(trail) == int(TRAIL_SECONDS / 0.5) + 1 and trail.span == TRAIL_SECONDS
    bands = trail.bands(8, 649.5, None)
    assert [len(b) > 0 for b in bands] == [True] * 8
    assert bands[0][0] == (99.0, 0.0) and bands[-1][-1] == (1299.0, 0.0)   # oldest faint, newest bright
    assert sum(len(b) for b in bands) == len(trail) + 7                    # bands join at one shared point
    assert not trail.add(650.0, 1299.2, 0.0)                               # 0.2 m and 0.5 s: nothing new
    assert trail.add(652.0, 1299.2, 0.0)                                   # hovering: a point every 2 s


def test_replay_track_keeps_everything_and_uses_lat_lon():
    trail = Trail(seconds=None)
    frame = MapFrame(*CANBERRA)
    for t in range(2000):
        lat, lon = frames.offset_latlon(*CANBERRA, t * 0.1, 0.0)
        trail.add(float(t), 0.0, 0.0, (lat, lon), force=True)
    bands = trail.bands(4, 0.0, frame.to_view)
    assert len(trail) == 2000
    assert bands[0][0] == pytest.approx((0.0, 0.0), abs=1e-6)
    assert bands[-1][-1] == pytest.approx((0.0, 199.9), abs=0.05)
