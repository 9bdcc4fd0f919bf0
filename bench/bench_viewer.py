"""How instant the window stays while flying, and what the viewer costs: UI lateness, redraws, CPU.

    .venv/bin/python bench/bench_viewer.py [--seconds 30] [--no-camera] [--gamepad] [--dock map|plots] [--tiles]
                                           [--write-docs]
    xvfb-run -s "-screen 0 1600x1000x24" .venv/bin/python bench/bench_viewer.py --cpu [--seconds 30] [--write-docs]

Runs the real window (offscreen unless a display is set) on the embedded driver and the simulated vehicle,
takes off, and holds both sticks as a pilot would, with the simulated camera playing (unless --no-camera).
A 10 ms timer measures how late the UI thread answers: any lateness is input lag the pilot feels. It also
times following one snapshot (buttons, sticks, messages, the map's data), one update of the attitude indicator
(30 Hz), of the readouts (5 Hz), one map paint and one plot redraw (5 Hz), against the 33 ms of a 30 fps frame.
``--dock`` chooses which of the tabbed Map and Plots docks is in view (the map by default, as the window opens);
``--tiles`` shows map tiles from a local tile server (tests/tile_server.py) instead of the offline grid. With
--gamepad, an SDL virtual gamepad flies instead: another thread sweeps both its sticks at 100 Hz, as a pilot's
thumbs would, and the SDL reader thread feeds the window.

``--cpu``: the viewer process's CPU (all its threads, % of one core) while flying both sticks with the plots
showing, the simulated vehicle in another process (``python -m driver.sim``), in three cases, each in a
fresh viewer process: no camera; a 640×480 30 fps H.264 stream over RTP (SDP) from ffmpeg on 127.0.0.1
(installed with apt-get when missing); the same with the window minimised. It runs under Xvfb (a real X
server: offscreen Qt has no window to minimise); without a display it starts itself under ``xvfb-run``,
installing Debian's xvfb when missing.
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
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))             # bench_video_latency's sender
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

import numpy as np  # noqa: E402
from PyQt5.QtCore import QSettings, QTimer  # noqa: E402
from PyQt5.QtWidgets import QApplication  # noqa: E402

from driver.sim import SimConfig, SimVehicle  # noqa: E402
from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402
from uavviewer.main_window import MainWindow, load_style  # noqa: E402
import tables  # noqa: E402  (bench/tables.py: this script runs from bench/)

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


CASES = ("no camera", "640x480 30 fps stream", "minimised, with the stream")


def free_port() -> int:
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def cpu_main(seconds: float, dock: str) -> None:
    """Each case in its own viewer process, against its own simulated vehicle process; ``dock`` in view."""
    import json
    import subprocess

    import bench_video_latency as video
    here = os.path.abspath(__file__)
    root = os.path.dirname(os.path.dirname(here))
    if not os.environ.get("DISPLAY"):
        video.ensure_tools(["xvfb-run"])
        env = {k: v for k, v in os.environ.items() if k != "QT_QPA_PLATFORM"}
        sys.exit(subprocess.call(["xvfb-run", "-a", "-s", "-screen 0 1600x1000x24", sys.executable, here, "--cpu",
                                  "--seconds", str(seconds), "--dock", dock], env=env))
    video.ensure_tools(["ffmpeg"])
    print(f"viewer process CPU, % of one core, flying both sticks for {seconds:.0f} s, the {dock} dock in view "
          f"({os.environ.get('QT_QPA_PLATFORM') or 'display ' + os.environ.get('DISPLAY', '?')})", flush=True)
    for case in CASES:
        port = free_port()
        sim = subprocess.Popen([sys.executable, "-m", "driver.sim", "--tcp", f"127.0.0.1:{port}",
                                "--ready-after", "1"], cwd=root, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
        sender = None
        with tempfile.TemporaryDirectory() as tmp:
            try:
                video.wait_for_port(port)
                uri = ""
                if case != "no camera":
                    sender = video.Sender("rtp", tmp, size=(640, 480))
                    uri = sender.uri
                run = subprocess.run([sys.executable, here, "--cpu-case", case, "--port", str(port),
                                      "--seconds", str(seconds), "--uri", uri, "--dock", dock], cwd=root,
                                     capture_output=True,
                                     text=True, timeout=seconds + 150)
            finally:
                if sender is not None:
                    sender.close()
                sim.terminate()
                sim.wait(10)
        try:
            r = json.loads(run.stdout.strip().splitlines()[-1])
        except (IndexError, ValueError):
            print(f"  {case}: failed: {run.stderr[-1500:]}", flush=True)
            continue
        print(f"  {case:28} {r['cpu']:5.1f} %   (UI thread {r['ui']:4.1f} %; {r['painted']} video frames painted, "
              f"{r['shown']} snapshots "
              f"shown, minimised {r['minimised']})", flush=True)


def cpu_case(case: str, port: int, seconds: float, uri: str, dock: str) -> None:
    """One viewer: take off, hold both sticks, then measure this process's CPU over ``seconds``."""
    import json
    import resource

    app = QApplication(sys.argv[:1])
    app.setStyleSheet(load_style())
    drone = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{port}", takeoff_altitude=3.0)).start()
    settings = QSettings(os.path.join(tempfile.mkdtemp(), "bench.ini"), QSettings.IniFormat)
    w = MainWindow(drone, qsettings=settings, takeoff_altitude=3.0, cameras=[uri] if uri else None,
                   default_cameras=[])
    w.resize(1600, 1000)
    w.show()
    w.activateWindow()
    (w.mapDock if dock == "map" else w.plotsDock).raise_()
    painted, shown = [0], [0]
    w.camera_view.framePainted.connect(lambda *_: painted.__setitem__(0, painted[0] + 1))
    w.adapter.stateChanged.connect(lambda *_: shown.__setitem__(0, shown[0] + 1))
    result: dict = {}
    phase = ["takeoff"]

    def pilot() -> None:
        s = drone.state()
        if phase[0] == "takeoff" and s.readiness.ready_to_arm:
            phase[0] = "climbing"
            w.adapter.send(w.adapter.drone.takeoff, 3.0)
        if s.can_fly_velocity:
            w.rightStick.hold(0.3, 0.8)
            w.leftStick.hold(0.4, 0.1)
            if phase[0] == "climbing":
                phase[0] = "settling"
                if case.startswith("minimised"):
                    w.showMinimized()
                QTimer.singleShot(3000, start)

    def start() -> None:
        r = resource.getrusage(resource.RUSAGE_SELF)
        result.update(cpu0=r.ru_utime + r.ru_stime, t0=time.monotonic(), painted0=painted[0], shown0=shown[0],
                      ui0=time.thread_time())
        QTimer.singleShot(int(seconds * 1000), stop)

    def stop() -> None:
        r = resource.getrusage(resource.RUSAGE_SELF)
        wall = time.monotonic() - result["t0"]
        result.update(cpu=100.0 * (r.ru_utime + r.ru_stime - result["cpu0"]) / wall,
                      ui=100.0 * (time.thread_time() - result["ui0"]) / wall,
                      painted=painted[0] - result["painted0"], shown=shown[0] - result["shown0"],
                      minimised=w.isMinimized())
        app.quit()

    driver = QTimer()
    driver.timeout.connect(pilot)
    driver.start(200)
    QTimer.singleShot(int((seconds + 120) * 1000), app.quit)     # never hang
    app.exec_()
    w.sticks.centre()
    w.close()
    drone.close()
    print(json.dumps({k: v for k, v in result.items() if k in ("cpu", "ui", "painted", "shown", "minimised")}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--no-camera", action="store_true", help="leave the simulated camera off")
    ap.add_argument("--gamepad", action="store_true", help="fly with an SDL virtual gamepad, sticks sweeping")
    ap.add_argument("--dock", choices=("map", "plots"), default="map", help="the tabbed dock in view")
    ap.add_argument("--tiles", action="store_true", help="map tiles from a local tile server, not the grid")
    ap.add_argument("--cpu", action="store_true", help="the viewer's CPU: no camera, a stream, minimised")
    ap.add_argument("--cpu-case", choices=CASES, help=argparse.SUPPRESS)
    ap.add_argument("--port", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--uri", default="", help=argparse.SUPPRESS)
    tables.add_write_docs(ap)
    args = ap.parse_args()
    if args.cpu:
        return cpu_main(args.seconds, args.dock)
    if args.cpu_case:
        return cpu_case(args.cpu_case, args.port, args.seconds, args.uri, args.dock)

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
        w.preferences.set_settings(replace(w.settings, tile_url=tile_server.url, tile_attribution="local tiles"))
        w.mapPanel.layerCombo.setCurrentIndex(1)

    follow: list[float] = []
    instruments: list[float] = []
    readouts: list[float] = []
    redraws: list[float] = []
    map_updates: list[float] = []
    map_paints: list[float] = []
    w.map.show_state = timed(map_updates, w.map.show_state)
    w.mapPanel.mapView.paintEvent = timed(map_paints, w.mapPanel.mapView.paintEvent)
    w.adapter.stateChanged.disconnect()
    w.adapter.stateChanged.connect(timed(follow, w.show_state))
    # the views' refresh channels (uavviewer/refresh.py)
    w.readouts.instruments_channel._callback = timed(instruments, w.readouts.show_instruments)
    w.readouts.text_channel._callback = timed(readouts, w.readouts.show_text)
    w.readouts.plots_channel._callback = timed(redraws, w.plots.redraw)

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
        from uavviewer.input.gamepad import VirtualPad
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
            w.adapter.send(w.adapter.drone.takeoff, 3.0)
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
        describe("following a snapshot (show_state)", follow)
        describe(f"  of which the map ({'tiles' if args.tiles else 'grid'})", map_updates)
        if map_paints:
            describe("map paint", map_paints)
        describe("attitude indicator update (30 Hz)", instruments)
        describe("readouts update (5 Hz)", readouts)
        describe("plots redraw (4 plots, 60 s, 5 Hz)", redraws)
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
    with tables.publishing(tables.variant("viewer", "--cpu", "--gamepad", "--tiles", "--dock", "--no-camera")):
        main()
