#!/usr/bin/env python3
"""Camera figures: 1280×720 at 30 frames/s from a file through the viewer, and Ice getImageData at 640×480.

    QT_QPA_PLATFORM=offscreen python bench/bench_camera.py [--seconds 10] [--write-docs]

Viewer: frames painted per second, decode-to-paint latency (median, 95th percentile)
and process CPU time per painted frame (capture + decode + colour conversion + paint,
all threads). Ice: synchronous getImageData("RGB8") round trips per second from a
client process to a server process serving the simulated camera.
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
import tables  # bench/tables.py: this script runs from bench/

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)


def make_clip(path: str, seconds: float, size=(1280, 720), fps: float = 30.0) -> str:
    """A moving picture (the simulated camera flying a circle) so the encoder has real work."""
    import math

    import cv2

    from driver.camera.sim import SimulatedCamera
    from driver.vehicle.state import Attitude, LocalPosition, VehicleState
    cam = SimulatedCamera(*size)
    writer = cv2.VideoWriter(path, cv2.CAP_FFMPEG, cv2.VideoWriter_fourcc(*"mp4v"), fps, size)
    for i in range(int(seconds * fps)):
        t = i / fps
        s = VehicleState(attitude=Attitude(roll=0.3 * math.sin(t), pitch=-0.1, yaw=t * 0.3),
                         local=LocalPosition(10 * math.cos(t * 0.3), 10 * math.sin(t * 0.3), -8))
        writer.write(cv2.cvtColor(cam.render(s), cv2.COLOR_RGB2BGR))
    writer.release()
    return path


def bench_viewer(seconds: float) -> None:
    from PyQt5.QtCore import QEventLoop, QTimer
    from PyQt5.QtWidgets import QApplication

    from uavviewer.camera.controller import CameraController
    from uavviewer.camera.panel import CameraPanel

    app = QApplication.instance() or QApplication([])
    with tempfile.TemporaryDirectory() as tmp:
        clip = make_clip(os.path.join(tmp, "720p.mp4"), seconds + 2)
        panel = CameraPanel()
        panel.resize(960, 600)
        panel.show()
        latencies: list[float] = []
        panel.view.framePainted.connect(lambda index, latency: latencies.append(latency))
        controller = CameraController(panel, [clip], folder=tmp)
        loop = QEventLoop()
        QTimer.singleShot(1000, loop.quit)                     # warm up: open, first frames
        loop.exec_()
        latencies.clear()
        frames0 = controller.source.status().frames
        cpu0, t0 = time.process_time(), time.monotonic()
        QTimer.singleShot(int(seconds * 1000), loop.quit)
        loop.exec_()
        cpu, wall = time.process_time() - cpu0, time.monotonic() - t0
        status = controller.source.status()
        painted = len(latencies)
        lat = sorted(latencies)
        print(f"viewer, 1280x720 30 fps mp4v file, view {panel.view.width()}x{panel.view.height()}:")
        print(f"  decoded {(status.frames - frames0) / wall:.1f} frames/s, painted {painted / wall:.1f} frames/s, "
              f"dropped {status.dropped} in total")
        if lat:
            print(f"  decode-to-paint latency: median {statistics.median(lat) * 1000:.1f} ms, "
                  f"p95 {lat[int(0.95 * (len(lat) - 1))] * 1000:.1f} ms")
            print(f"  CPU {cpu / painted * 1000:.1f} ms per painted frame ({cpu / wall * 100:.0f} % of one core)")
        controller.close()
        controller.source.close(wait=3)
        panel.close()
        app.processEvents()


def serve(width: int, height: int) -> None:
    """Child process: serve the simulated camera and print the proxy."""
    import Ice

    from driver.ice.camera import CameraI
    from driver.vehicle.state import VehicleState

    class Still:
        def state(self):
            return VehicleState()

    init = Ice.InitializationData()
    init.properties = Ice.createProperties()
    init.properties.setProperty("Ice.ThreadPool.Server.SizeMax", "4")
    com = Ice.initialize(init)
    adapter = com.createObjectAdapterWithEndpoints("Bench", "tcp -h 127.0.0.1 -p 0")
    servant = CameraI({"Uri": "sim", "Width": str(width), "Height": str(height)}, Still())
    print(com.proxyToString(adapter.add(servant, Ice.stringToIdentity("Camera"))), flush=True)
    adapter.activate()
    sys.stdin.read()                                           # until the parent closes our stdin
    servant.close()
    com.destroy()


def bench_ice(seconds: float, width: int = 640, height: int = 480) -> None:
    import Ice

    from driver.ice import load_slice
    jderobot, _ = load_slice()
    child = subprocess.Popen([sys.executable, __file__, "--serve", str(width), str(height)],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        proxy = child.stdout.readline().strip()
        init = Ice.InitializationData()
        init.properties = Ice.createProperties()
        init.properties.setProperty("Ice.MessageSizeMax", "65536")
        com = Ice.initialize(init)
        try:
            cam = jderobot.CameraPrx.checkedCast(com.stringToProxy(proxy))
            deadline = time.monotonic() + 5
            while time.monotonic() < deadline:
                try:
                    cam.getImageData("RGB8")
                    break
                except jderobot.DataNotExistException:
                    time.sleep(0.05)
            calls, size, stamps = 0, 0, set()
            t0 = time.monotonic()
            while time.monotonic() - t0 < seconds:
                data = cam.getImageData("RGB8")
                calls += 1
                size = len(data.pixelData)
                stamps.add((data.timeStamp.seconds, data.timeStamp.useconds))
            wall = time.monotonic() - t0
            print(f"Ice getImageData(RGB8) {width}x{height} over loopback TCP, one client, another process:")
            print(f"  {calls / wall:.0f} round trips/s, {calls * size / wall / 1e6:.0f} MB/s, "
                  f"{len(stamps) / wall:.1f} distinct frames/s (camera renders 30)")
        finally:
            com.destroy()
    finally:
        child.stdin.close()
        child.wait(10)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--seconds", type=float, default=10.0)
    p.add_argument("--serve", nargs=2, type=int, help=argparse.SUPPRESS)
    tables.add_write_docs(p)
    args = p.parse_args()
    if args.serve:
        serve(*args.serve)
        return
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    bench_viewer(args.seconds)
    bench_ice(min(args.seconds, 5.0))


if __name__ == "__main__":
    with tables.publishing("camera"):
        main()
