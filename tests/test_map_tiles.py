"""Map tiles from a real HTTP server on 127.0.0.1 (generated PNGs): cache, failures, a slow server, offline."""
from __future__ import annotations

import threading

import pytest
from PyQt5.QtCore import QEvent, QPointF, Qt
from PyQt5.QtGui import QMouseEvent
from PyQt5.QtWidgets import QApplication

from uavviewer.map.geometry import MapFrame, tiles_covering
from uavviewer.map.tiles import MAX_AREA_TILES, TileSource
from uavviewer.map.map_view import MapView

from tile_server import TileServer

HOME = (-35.363261, 149.165230)


@pytest.fixture
def tile_server():
    servers = []

    def make(**kw) -> TileServer:
        server = TileServer(**kw).start()
        servers.append(server)
        return server
    yield make
    for server in servers:
        server.stop()


@pytest.fixture
def map_view(qtbot):
    """The map canvas on its own, 400x300, home at Canberra, tiles at level 17."""
    def make(source: TileSource | None) -> MapView:
        view = MapView()
        qtbot.addWidget(view)
        view.frame = MapFrame(*HOME)
        view.mpp = 0.9                             # ~level 17 at this latitude
        view.set_vehicle((0.0, 0.0, 0.0))
        view.resize(400, 300)
        view.set_tiles(source, "© test tiles")
        view.show()
        qtbot.waitExposed(view)
        return view
    return make


def source_for(server: TileServer, tmp_path, **kw) -> TileSource:
    return TileSource(server.url, str(tmp_path / "tiles"), **kw)


def test_tiles_come_in_and_the_second_time_from_the_disk_cache(qtbot, tile_server, map_view, tmp_path):
    server = tile_server()
    first = source_for(server, tmp_path)
    view = map_view(first)
    wanted = len(view.visible_tiles())
    assert wanted >= 4
    qtbot.waitUntil(lambda: view.drawn_tiles == wanted, timeout=10000)
    assert server.tile_hits == wanted and set(server.hits.values()) == {1}   # each tile asked for once
    assert all(agent.startswith("UavViewerPy/") for agent in server.agents)  # the policy: name the app
    view.update()
    qtbot.waitUntil(lambda: view.paints > 2)
    assert server.tile_hits == wanted                                          # in memory: not asked again

    second = source_for(server, tmp_path)                                      # a new run: memory empty
    again = map_view(second)
    qtbot.waitUntil(lambda: again.drawn_tiles == wanted, timeout=10000)
    assert server.tile_hits == wanted and second.requests == wanted           # all from the disk cache
    assert second.cache_bytes > 0


def test_offline_mode_shows_only_cached_tiles_and_never_asks_the_server(qtbot, tile_server, map_view, tmp_path):
    server = tile_server()
    online = map_view(source_for(server, tmp_path))
    cached = {key for key, _ in online.visible_tiles()}
    qtbot.waitUntil(lambda: online.drawn_tiles == len(cached), timeout=10000)
    hits = server.tile_hits

    offline = source_for(server, tmp_path, offline=True)
    view = map_view(offline)
    qtbot.waitUntil(lambda: view.drawn_tiles == len(cached), timeout=10000)
    view.centre = (2000.0, 0.0)                   # 2 km east: nothing of it in the cache
    view.set_follow(False)
    view.update()
    away = {key for key, _ in view.visible_tiles()}
    qtbot.waitUntil(lambda: set(offline.failures) == away, timeout=10000)
    assert set(offline.failures.values()) == {"not in the offline cache"}
    assert view.drawn_tiles == 0 and server.tile_hits == hits                # the grid, and no network at all

    offline.set_offline(False)                                               # online again: they load
    view.update()
    qtbot.waitUntil(lambda: view.drawn_tiles == len(away), timeout=10000)
    assert server.tile_hits == hits + len(away)


def test_a_failing_server_leaves_the_grid_and_is_not_hammered(qtbot, tile_server, map_view, tmp_path):
    server = tile_server(status=500)
    source = source_for(server, tmp_path)
    view = map_view(source)
    wanted = {key for key, _ in view.visible_tiles()}
    qtbot.waitUntil(lambda: set(source.failures) == wanted, timeout=10000)
    assert set(source.failures.values()) == {"HTTP 500"}
    hits = server.tile_hits
    for _ in range(3):
        view.update()
        paints = view.paints
        qtbot.waitUntil(lambda: view.paints > paints)
    assert view.drawn_tiles == 0 and server.tile_hits == hits == len(wanted)   # asked once, then left alone


def test_a_slow_server_never_stalls_the_window(qtbot, tile_server, map_view, tmp_path):
    """While every tile request hangs on the server, the map still pans and paints: the UI thread waits for
    nothing. Then the server answers and the tiles appear."""
    hold = threading.Event()
    server = tile_server(hold=hold)
    source = source_for(server, tmp_path)
    view = map_view(source)
    qtbot.waitUntil(lambda: server.waiting >= 1 and source.in_flight >= 1, timeout=10000)

    start, paints = view.centre, view.paints
    # the pilot drags the map while the tiles hang: events posted to the event loop, as the mouse's are
    post = QApplication.postEvent
    post(view, QMouseEvent(QEvent.MouseButtonPress, QPointF(200, 150), Qt.LeftButton, Qt.LeftButton, Qt.NoModifier))
    for x in range(205, 305, 5):
        post(view, QMouseEvent(QEvent.MouseMove, QPointF(x, 150), Qt.NoButton, Qt.LeftButton, Qt.NoModifier))
    post(view, QMouseEvent(QEvent.MouseButtonRelease, QPointF(300, 150), Qt.LeftButton, Qt.NoButton, Qt.NoModifier))
    qtbot.waitUntil(lambda: view.centre[0] == pytest.approx(start[0] - 100 * view.mpp) and view.paints > paints)
    assert not view.follow
    assert view.drawn_tiles == 0 and server.waiting >= 1                       # and the server still holds

    hold.set()
    qtbot.waitUntil(lambda: view.drawn_tiles == len(view.visible_tiles()), timeout=10000)


def test_download_area_is_bounded_and_fills_the_cache(qtbot, tile_server, tmp_path):
    server = tile_server()
    source = source_for(server, tmp_path)
    frame = MapFrame(*HOME)
    huge = [k for z in range(14, 18) for k, _ in tiles_covering(frame, -5000, 5000, 5000, -5000, z, limit=10 ** 6)]
    assert len(huge) > MAX_AREA_TILES and source.download_area(huge) == 0 and server.tile_hits == 0
    small = [k for z in (16, 17) for k, _ in tiles_covering(frame, -300, 300, 300, -300, z)]
    with qtbot.waitSignal(source.areaProgress, timeout=15000,
                          check_params_cb=lambda done, failed, total: done + failed == total):
        assert source.download_area(small) == len(small)
    assert server.tile_hits == len(small) and not source.failures

    offline = source_for(server, tmp_path, offline=True)          # then in the field, with no network
    offline.want(small)
    qtbot.waitUntil(lambda: all(offline.image(k) is not None for k in small), timeout=10000)
    assert server.tile_hits == len(small)
