"""A real {z}/{x}/{y} tile server on 127.0.0.1 serving generated PNGs (numpy + OpenCV): for the map's tests,
its benchmark and its screenshot, so none of them touches the internet.

    .venv/bin/python tests/tile_server.py --port 8765      # serves http://127.0.0.1:8765/{z}/{x}/{y}.png

Each tile is drawn from its place in the world (streets on a fixed world-pixel grid, a river, a park), so
neighbouring tiles join up and every tile differs. ``status`` makes it fail (e.g. 500), ``hold`` (an Event)
makes every answer wait until it is set: a slow server.
"""
from __future__ import annotations

import argparse
import collections
import http.server
import re
import threading

import cv2
import numpy as np

__all__ = ["TileServer", "tile_png"]

_PATH = re.compile(r"^/(\d+)/(\d+)/(\d+)\.png$")


def tile_png(z: int, x: int, y: int) -> bytes:
    """A 256x256 map-like PNG of tile z/x/y."""
    img = np.full((256, 256, 3), (222, 236, 242), np.uint8)          # BGR: a light land colour
    gx, gy = np.meshgrid(np.arange(256) + x * 256, np.arange(256) + y * 256)
    street = max(32, 2 ** (z - 10))                                   # world pixels between streets
    img[(gx % street) < 3] = (255, 255, 255)
    img[(gy % street) < 3] = (255, 255, 255)
    river = np.abs(gy - (y * 256 + 128) - 60 * np.sin(gx / 230.0)) < 14 + (gx % 7 == 0)
    img[river & ((gy // 4096) % 2 == 0)] = (230, 200, 170)
    park = ((gx // (street * 3)) % 5 == 1) & ((gy // (street * 3)) % 4 == 2)
    img[park & ~river] = (190, 225, 195)
    cv2.putText(img, f"{z}/{x}/{y}", (8, 248), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (150, 150, 150), 1, cv2.LINE_AA)
    ok, png = cv2.imencode(".png", img)
    assert ok
    return png.tobytes()


class TileServer:
    """The server on a thread; ``hits`` counts requests by path, ``agents`` keeps the User-Agents seen."""

    def __init__(self, port: int = 0, status: int = 200, hold: threading.Event | None = None) -> None:
        self.status = status
        self.hold = hold
        self.hits: collections.Counter[str] = collections.Counter()
        self.agents: set[str] = set()
        self.waiting = 0                    # requests held back right now (a slow server)
        server = self

        class Handler(http.server.BaseHTTPRequestHandler):
            protocol_version = "HTTP/1.1"

            def do_GET(self) -> None:  # noqa: N802
                server.hits[self.path] += 1
                server.agents.add(self.headers.get("User-Agent", ""))
                if server.hold is not None and not server.hold.is_set():
                    server.waiting += 1
                    server.hold.wait(30)
                    server.waiting -= 1
                m = _PATH.match(self.path)
                if server.status != 200 or m is None:
                    body = b"tile server says no"
                    self.send_response(server.status if m else 404)
                    self.send_header("Content-Type", "text/plain")
                else:
                    body = tile_png(*(int(g) for g in m.groups()))
                    self.send_response(200)
                    self.send_header("Content-Type", "image/png")
                    self.send_header("Cache-Control", "max-age=604800")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)

            def log_message(self, *args) -> None:
                pass

        self._httpd = http.server.ThreadingHTTPServer(("127.0.0.1", port), Handler)
        self._httpd.daemon_threads = True
        self._thread = threading.Thread(target=self._httpd.serve_forever, name="tile-server", daemon=True)

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self._httpd.server_address[1]}/{{z}}/{{x}}/{{y}}.png"

    @property
    def tile_hits(self) -> int:
        return sum(self.hits.values())

    def start(self) -> "TileServer":
        self._thread.start()
        return self

    def stop(self) -> None:
        if self.hold is not None:
            self.hold.set()
        self._httpd.shutdown()
        self._httpd.server_close()


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--port", type=int, default=8765)
    srv = TileServer(ap.parse_args().port)
    print(srv.url, flush=True)
    srv.start()
    try:
        srv._thread.join()
    except KeyboardInterrupt:
        srv.stop()
