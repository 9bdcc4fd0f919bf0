"""How instant the window stays while flying: UI event-loop lateness and the cost of each redraw.

    .venv/bin/python bench/bench_viewer.py [--seconds 30] [--no-camera] [--gamepad] [--dock map|plots] [--tiles]

Runs the real window (offscreen unless a display is set) on the embedded driver and the simulated vehicle,
takes off, and holds both sticks as a pilot would, with the simulated camera playing (unless --no-camera).
A 10 ms timer measures how late the UI thread answers: any lateness is input lag the pilot feels. It also
times one telemetry update of every instrument (30 Hz, the map included), one map update and one plot redraw
(10 Hz), against the 33 ms of a 30 fps frame. ``--dock`` chooses which of the tabbed Map and Plots docks is
in view (the map by default, as the window opens); ``--tiles`` shows map tiles from a local tile server
(tests/tile_server.py) instead of the offline grid. With --gamepad, an SDL virtual gamepad flies instead:
another thread sweeps both its sticks at 100 Hz, as a pilot's thumbs would, and the SDL reader thread feeds
the window.
"""
from __future__ import annotations

import argparse
import os
import math
import sys
import tempfile
import threading
import time
from dataclasses import replace

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

import numpy as np  # noqa: E402
from PyQt5.QtCore import QSettings, QTimer  # noqa: E402
from PyQt5.QtWidgets import QApplication  # noqa: E402

from driver.sim import SimConfig, SimVehicle  # noqa: E402
from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402
from uavviewer.main_window import MainWindow, load_style  # noqa: E402

FRAME_MS = 1000.0 / 30.0


def timed(samples: list[float], fn):
    def wrapper(*args):
        t = time.perf_counter()
        fn(*args)
        samples.append((time.perf_counter() - t) * 1e3)
    return wrapper


def describe(name: str, ms: list[float]) -> None:
    a = np.asarray(ms)
    print(f"{name:34} n={a.size:5d}  median {np.median(a):6.2f} ms  p99 {np.percentile(a, 99):6.2f} ms  "
          f"max {a.max():6.2f} ms  (p99 = {np.percentile(a, 99) / FRAME_MS:.2f} of a 30 fps frame)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--no-camera", action="store_true", help="leave the simulated camera off")
    ap.add_argument("--gamepad", action="store_true", help="fly with an SDL virtual gamepad, sticks sweeping")
    ap.add_argument("--dock", choices=("map", "plots"), default="map", help="the tabbed dock in view")
    ap.add_argument("--tiles", action="store_true", help="map tiles from a local tile server, not the grid")
    args = ap.parse_args()

    app = QApplication(sys.argv[:1])
    app.setStyleSheet(load_style())
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=1.0, ready_after=1.0))
    sim.start()
    drone = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{sim.tcp_port}", takeoff_altitude=3.0)).start()
    settings = QSettings(os.path.join(tempfile.mkdtemp(), "bench.ini"), QSettings.IniFormat)
    w = MainWindow(drone, qsettings=settings, takeoff_altitude=3.0,
                   default_cameras=[] if args.no_camera else ["sim"])
    w.resize(1600, 1000)
    w.show()
    w.activateWindow()
    (w.mapDock if args.dock == "map" else w.plotsDock).raise_()
    tile_server = None
    if args.tiles:
        sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "tests"))
        from tile_server import TileServer
        tile_server = TileServer().start()
        w.tile_cache_dir = tempfile.mkdtemp()
        w.set_settings(replace(w.settings, tile_url=tile_server.url, tile_attribution="local tiles"))
        w.mapPanel.layerCombo.setCurrentIndex(1)

    instruments: list[float] = []
    redraws: list[float] = []
    map_updates: list[float] = []
    map_paints: list[float] = []
    w.map.show_state = timed(map_updates, w.map.show_state)
    w.mapPanel.mapView.paintEvent = timed(map_paints, w.mapPanel.mapView.paintEvent)
    w.adapter.stateChanged.disconnect()
    w.adapter.stateChanged.connect(timed(instruments, w.show_state))
    w.plots._timer.timeout.disconnect()
    w.plots._timer.timeout.connect(timed(redraws, w.plots.redraw))

    lateness: list[float] = []
    last = [time.perf_counter()]
    measuring = [False]

    def tick() -> None:
        now = time.perf_counter()
        if measuring[0]:
            lateness.append(max(0.0, (now - last[0]) * 1e3 - 10.0))
        last[0] = now

    probe = QTimer()
    probe.setTimerType(0)                           # Qt.PreciseTimer
    probe.timeout.connect(tick)
    probe.start(10)

    pad = None
    sweeping, stopping = threading.Event(), threading.Event()
    if args.gamepad:
        from uavviewer.gamepad import VirtualPad
        pad = VirtualPad("Bench gamepad")

        def thumbs() -> None:                       # both sticks sweep, 100 updates a second
            t0 = time.monotonic()
            while not stopping.is_set():
                if not sweeping.wait(0.5):
                    continue
                t = time.monotonic() - t0
                pad.set_axis("righty", 0.5 + 0.3 * math.sin(t))
                pad.set_axis("rightx", 0.3 * math.sin(1.7 * t))
                pad.set_axis("leftx", 0.4 * math.sin(0.7 * t))
                time.sleep(0.01)
        threading.Thread(target=thumbs, daemon=True).start()

    started = [False]
    camera: dict = {}
    flying_since: list[float] = []

    def pilot() -> None:
        s = w.adapter.state
        if s.readiness.ready_to_arm and not started[0]:
            started[0] = True
            w.adapter.command("takeoff", 3.0)
        if s.can_fly_velocity:
            if not flying_since:
                flying_since.append(time.monotonic())
                measuring[0] = True
            if pad is None:
                w.rightStick.hold(0.3, 0.8)
                w.leftStick.hold(0.4, 0.1)
            elif w.gamepad.status == "":
                sweeping.set()
            if time.monotonic() - flying_since[0] > args.seconds:
                camera.update(w.camera.stats())
                app.quit()

    driver = QTimer()
    driver.timeout.connect(pilot)
    driver.start(200)
    QTimer.singleShot(int((args.seconds + 90) * 1000), app.quit)     # never hang
    app.exec_()
    try:
        if not lateness:
            print("the vehicle never flew: nothing measured")
            return
        if pad is not None:
            stopping.set()
            pad.detach()
        seen = "off" if args.no_camera else (f"{camera['fps']:.0f} fps painted at {camera['resolution']}, "
                                              f"{camera['frames']} frames")
        flown = f"the gamepad ({w.gamepad.pad.name if w.gamepad.pad else 'gone'}) sweeping" if pad is not None \
            else "both sticks held"
        print(f"flying {args.seconds:.0f} s with {flown}; camera {seen}; "
              f"{w.adapter.sent_setpoints} stick updates sent")
        describe("UI event-loop lateness (10 ms timer)", lateness)
        describe("instruments update (per snapshot)", instruments)
        describe(f"  of which the map ({'tiles' if args.tiles else 'grid'})", map_updates)
        if map_paints:
            describe("map paint", map_paints)
        describe("plots redraw (4 plots, 60 s)", redraws)
        late = np.asarray(lateness)
        print(f"UI answered within one 30 fps frame {100.0 * (late <= FRAME_MS).mean():.2f} % of the time; "
              f"{int((late > 50).sum())} stalls over 50 ms")
    finally:
        w.close()
        drone.close()
        sim.stop()
        if tile_server is not None:
            tile_server.stop()


if __name__ == "__main__":
    main()
