"""ArduPilot's parameter metadata: the shipped copy, a user's file, and the once-fetched per-user cache."""
from __future__ import annotations

import gzip
import http.server
import threading

import pytest

from driver.params import metadata as md
from driver.params.metadata import ParamMetadata, bounds_problem, load_metadata


def test_the_shipped_copy_documents_arducopter():
    meta = load_metadata()
    assert meta is not None and meta.source == md.SHIPPED and meta.generated.startswith("Copter-4.5.3")
    rtl = meta.get("RTL_ALT")
    assert (rtl.display_name, rtl.units, rtl.min, rtl.max, rtl.increment) == ("RTL Altitude", "cm", 200, 300000, 1)
    assert "climb" in rtl.description and not rtl.reboot_required
    assert meta.get("BATT_MONITOR").reboot_required and meta.get("FORMAT_VERSION").read_only
    fs = meta.get("FS_GCS_ENABLE")
    assert fs.values[1] == "RTL" and fs.value_text(1) == "RTL"
    mask = meta.get("GCS_PID_MASK")
    assert mask.bitmask[0] == "Roll" and mask.value_text(4) == "Yaw" and mask.value_text(5) == "Roll, Yaw"
    assert mask.value_text(3) == "Roll, Pitch"
    assert meta.get("NO_SUCH_PARAM") is None


def test_bounds():
    meta = load_metadata()
    assert bounds_problem(meta.get("RTL_ALT"), 1e9) == "RTL_ALT = 1e+09 is outside 200 to 300000 cm"
    assert bounds_problem(meta.get("RTL_ALT"), 1500) == ""
    assert "none of its values" in bounds_problem(meta.get("FS_GCS_ENABLE"), 8)
    assert "bits that mean nothing" in bounds_problem(meta.get("GCS_PID_MASK"), 16)
    assert bounds_problem(meta.get("GCS_PID_MASK"), 15) == ""
    assert "read-only" in bounds_problem(meta.get("FORMAT_VERSION"), 1)
    assert bounds_problem(None, 1e30) == ""                                   # nothing known: nothing to say


def test_a_users_file_must_be_metadata(tmp_path):
    bad = tmp_path / "x.xml"
    bad.write_text("<paramfile/>")
    with pytest.raises(ValueError):
        load_metadata(str(bad))
    with pytest.raises(OSError):
        load_metadata(str(tmp_path / "missing.xml"))


def test_fetched_once_into_the_per_user_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    body = gzip.decompress(open(md.SHIPPED, "rb").read())

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self):
            self.send_response(200)
            self.end_headers()
            self.wfile.write(body if self.path == "/apm.pdef.xml" else b"<html>not found</html>")

        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        base = f"http://127.0.0.1:{server.server_address[1]}"
        with pytest.raises(ValueError):
            md.fetch_metadata(base + "/other")                                  # not metadata: nothing cached
        assert load_metadata().source == md.SHIPPED
        fetched = md.fetch_metadata(base + "/apm.pdef.xml")
    finally:
        server.shutdown()
    assert isinstance(fetched, ParamMetadata) and fetched.source == md.cache_path()
    assert load_metadata().source == md.cache_path() and load_metadata().get("RTL_ALT").units == "cm"
