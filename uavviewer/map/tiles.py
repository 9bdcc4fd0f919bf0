"""Map tiles from a ``{z}/{x}/{y}`` server, fetched without ever blocking the UI thread.

QNetworkAccessManager does the fetching (asynchronous, on Qt's own threads) and QNetworkDiskCache keeps
what came in the per-user cache folder, within a size limit, honouring the server's caching headers, as
OpenStreetMap's tile usage policy asks; every request names the application in its User-Agent. Offline,
only the cache answers. A few requests run at a time, nearest the view centre first; tiles that
scrolled away are dropped from the queue before they are asked for. A tile that failed is not asked
for again until the source is reset (the pilot changes the server or goes online again).
"""
from __future__ import annotations

import collections
import logging
from pathlib import Path

from PyQt5.QtCore import QObject, QStandardPaths, QUrl, pyqtSignal
from PyQt5.QtGui import QImage
from PyQt5.QtNetwork import QNetworkAccessManager, QNetworkDiskCache, QNetworkReply, QNetworkRequest

from driver.version import __version__
from .geometry import TileKey, tile_url

__all__ = ["TileSource", "USER_AGENT", "default_cache_dir", "MAX_AREA_TILES", "IN_FLIGHT"]

log = logging.getLogger(__name__)

USER_AGENT = f"UavViewerPy/{__version__} (ground station; +https://github.com/JdeRobot)".encode()
IN_FLIGHT = 4                 # requests at once (OSM's policy: a couple of connections, no more)
MEMORY_TILES = 512            # decoded tiles kept in memory (~32 MB at 256x256 RGBA)
MAX_AREA_TILES = 1500         # "download this area" never asks for more (OSM forbids bulk downloads)


def default_cache_dir() -> str:
    """The per-user cache folder (~/.cache/UavViewerPy/tiles on Linux)."""
    base = QStandardPaths.writableLocation(QStandardPaths.CacheLocation) or str(Path.home() / ".cache" / "UavViewerPy")
    return str(Path(base) / "tiles")


class TileSource(QObject):
    """Tiles by key: :meth:`image` answers at once from memory, :meth:`want` queues the fetch."""

    tileReady = pyqtSignal(object)              # TileKey: its image is in memory now
    tileFailed = pyqtSignal(object, str)        # TileKey, why (offline and not cached, HTTP 404, ...)
    areaProgress = pyqtSignal(int, int, int)    # downloaded, failed, total of a "download this area"

    def __init__(self, template: str, cache_dir: str | None = None, cache_mb: int = 200,
                 offline: bool = False, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.template = template
        self.offline = offline
        self._net = QNetworkAccessManager(self)
        self._cache = QNetworkDiskCache(self)
        self._cache.setCacheDirectory(cache_dir or default_cache_dir())
        self._cache.setMaximumCacheSize(max(1, int(cache_mb)) * 1024 * 1024)
        self._net.setCache(self._cache)
        self._images: collections.OrderedDict[TileKey, QImage] = collections.OrderedDict()
        self._failed: dict[TileKey, str] = {}
        self._queue: list[TileKey] = []             # wanted, nearest first
        self._pending: dict[QNetworkReply, TileKey] = {}
        self._area: dict[TileKey, None] = {}        # "download this area": the keys still to fetch
        self._area_flying: set[TileKey] = set()     # ... and those on their way
        self._area_counts = [0, 0, 0]
        self.requests = 0                           # sent to the network stack (cache hits included)

    # -- settings --------------------------------------------------------------------------------
    def set_offline(self, offline: bool) -> None:
        """Offline: answered from the cache only. Going online forgets the failures (they may load now)."""
        if offline != self.offline:
            self.offline = offline
            self._failed.clear()

    def set_cache_mb(self, mb: int) -> None:
        self._cache.setMaximumCacheSize(max(1, int(mb)) * 1024 * 1024)

    @property
    def cache_bytes(self) -> int:
        return int(self._cache.cacheSize())

    @property
    def cache_dir(self) -> str:
        return self._cache.cacheDirectory()

    def close(self) -> None:
        self._queue.clear()
        self._area.clear()
        self._area_flying.clear()
        for reply in list(self._pending):
            reply.abort()

    # -- tiles -----------------------------------------------------------------------------------
    def image(self, key: TileKey) -> QImage | None:
        img = self._images.get(key)
        if img is not None:
            self._images.move_to_end(key)
        return img

    def failure(self, key: TileKey) -> str | None:
        return self._failed.get(key)

    @property
    def failures(self) -> dict[TileKey, str]:
        return dict(self._failed)

    @property
    def in_flight(self) -> int:
        return len(self._pending)

    def want(self, keys: list[TileKey]) -> None:
        """The tiles the view shows now, nearest first: queued unless in memory, failed or on their way."""
        on_way = set(self._pending.values())
        self._queue = [k for k in keys if k not in self._images and k not in self._failed and k not in on_way]
        self._pump()

    def download_area(self, keys: list[TileKey]) -> int:
        """Fetch ``keys`` into the disk cache for offline use; refused (returns 0) above MAX_AREA_TILES."""
        if len(keys) > MAX_AREA_TILES or self.offline:
            return 0
        self._area = dict.fromkeys(keys)
        self._area_counts = [0, 0, len(keys)]
        self._pump()
        return len(keys)

    def _pump(self) -> None:
        on_way = set(self._pending.values())
        while len(self._pending) < IN_FLIGHT and (self._queue or self._area):
            if self._queue:
                key = self._queue.pop(0)
            else:
                key = next(iter(self._area))
                del self._area[key]
                self._area_flying.add(key)
            if key not in on_way:
                self._request(key)
                on_way.add(key)

    def _request(self, key: TileKey) -> None:
        request = QNetworkRequest(QUrl(tile_url(self.template, key)))
        request.setRawHeader(b"User-Agent", USER_AGENT)
        request.setAttribute(QNetworkRequest.CacheLoadControlAttribute,
                             QNetworkRequest.AlwaysCache if self.offline else QNetworkRequest.PreferNetwork)
        request.setAttribute(QNetworkRequest.CacheSaveControlAttribute, True)
        request.setAttribute(QNetworkRequest.RedirectPolicyAttribute, QNetworkRequest.NoLessSafeRedirectPolicy)
        reply = self._net.get(request)
        self.requests += 1
        self._pending[reply] = key
        reply.finished.connect(lambda r=reply: self._finished(r))

    def _finished(self, reply: QNetworkReply) -> None:
        key = self._pending.pop(reply, None)
        reply.deleteLater()
        if key is None:
            return
        in_area = key in self._area_flying
        self._area_flying.discard(key)
        image = QImage()
        error = reply.error()
        if error == QNetworkReply.NoError:
            data = bytes(reply.readAll())
            if not image.loadFromData(data):
                error = -1
        if error == QNetworkReply.NoError:
            self._images[key] = image
            while len(self._images) > MEMORY_TILES:
                self._images.popitem(last=False)
            self._area_step(in_area, ok=True)
            self.tileReady.emit(key)
        elif error != QNetworkReply.OperationCanceledError:
            status = reply.attribute(QNetworkRequest.HttpStatusCodeAttribute)
            why = ("not in the offline cache" if self.offline else
                   f"HTTP {status}" if status else "not an image" if error == -1 else reply.errorString())
            self._failed[key] = why
            self._area_step(in_area, ok=False)
            self.tileFailed.emit(key, why)
        self._pump()

    def _area_step(self, in_area: bool, ok: bool) -> None:
        done, failed, total = self._area_counts
        if not in_area:
            return
        self._area_counts = [done + ok, failed + (not ok), total]
        self.areaProgress.emit(*self._area_counts)
