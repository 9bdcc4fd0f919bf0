#!/usr/bin/env python3
"""Ice figures: Pose3D round trip beside an empty Ice call, and stick-to-wire latency through Ice, the
embedded driver, and the window (on-screen stick, gamepad).

    python bench/bench_ice.py [--calls 2000] [--sticks 200] [--no-ice]

The server runs as its own process (``python -m driver``), connected to a small
MAVLink probe here that plays a GUIDED, armed vehicle and timestamps every
SET_POSITION_TARGET_LOCAL_NED the driver writes on the TCP link.

1. Round trip: ``getPose3DData`` and ``ice_ping`` (the empty call) alternate on
   the same proxy connection; median and 95th percentile, and their ratio
   (the server's own work per Pose3D call, the 2017 server slept 50 ms here).
2. Stick to wire: ``IceDrone.set_velocity`` (what the viewer calls when a stick
   moves) → CMDVel → server → driver → MAVLink on the wire; beside the same for
   the embedded driver (``Vehicle.set_velocity``, no Ice).
3. Through the window (``MainWindow`` on the embedded driver, offscreen): an on-screen stick moved
   (``JoystickPad.hold`` on the UI thread → demand → driver → wire), and a gamepad's stick moved: an SDL virtual
   joystick's axis set from another thread (the event time) → SDL's next poll (1 ms) wakes the reader → queued frame
   → the UI thread's demand → driver → wire. ``--no-ice`` runs 2 and 3 only.
"""
from __future__ import annotations

import argparse
import os
import socket
import statistics
import subprocess
import sys
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from pymavlink.dialects.v20 import ardupilotmega as mavlink  # noqa: E402


class WireProbe:
    """A MAVLink peer on TCP that says it is an armed copter in GUIDED and notes when setpoints arrive."""

    def __init__(self) -> None:
        self.listener = socket.socket()
        self.listener.bind(("127.0.0.1", 0))
        self.listener.listen(1)
        self.port = self.listener.getsockname()[1]
        self._seen = threading.Condition()
        self._last: tuple[float, float] | None = None   # (perf_counter, vx)
        self._closing = threading.Event()
        threading.Thread(target=self._run, daemon=True).start()

    def _run(self) -> None:
        conn, _ = self.listener.accept()
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        out = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        parser = mavlink.MAVLink(None)
        parser.robust_parsing = True

        def beat() -> None:
            while not self._closing.wait(0.2):
                hb = out.heartbeat_encode(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                          mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
                                          | mavlink.MAV_MODE_FLAG_SAFETY_ARMED, 4, mavlink.MAV_STATE_ACTIVE)
                try:
                    conn.sendall(hb.pack(out))
                except OSError:
                    return
        threading.Thread(target=beat, daemon=True).start()
        while not self._closing.is_set():
            try:
                data = conn.recv(65536)
            except OSError:
                return
            if not data:
                return
            now = time.perf_counter()
            for msg in parser.parse_buffer(data) or ():
                if msg.get_type() == "SET_POSITION_TARGET_LOCAL_NED":
                    with self._seen:
                        self._last = (now, msg.vx)
                        self._seen.notify_all()

    def wait_for_change(self, vx: float, timeout: float = 2.0) -> tuple[float, float] | None:
        """(perf_counter, forward speed) of the first setpoint on the wire whose forward speed is not ``vx``."""
        deadline = time.perf_counter() + timeout
        with self._seen:
            while self._last is None or abs(self._last[1] - vx) <= 1e-4:
                left = deadline - time.perf_counter()
                if left <= 0:
                    return None
                self._seen.wait(left)
            return self._last

    def wait_for(self, vx: float, timeout: float = 2.0) -> float | None:
        """perf_counter when a setpoint with this forward speed reached the wire."""
        deadline = time.perf_counter() + timeout
        with self._seen:
            while self._last is None or abs(self._last[1] - vx) > 1e-4:
                left = deadline - time.perf_counter()
                if left <= 0:
                    return None
                self._seen.wait(left)
            return self._last[0]

    def close(self) -> None:
        self._closing.set()
        self.listener.close()


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def figures(name: str, samples: list[float]) -> float:
    samples = sorted(samples)
    median = statistics.median(samples)
    p95 = samples[int(0.95 * (len(samples) - 1))]
    print(f"  {name:34} median {median * 1e6:8.0f} µs   p95 {p95 * 1e6:8.0f} µs   (n={len(samples)})")
    return median


def stick_to_wire(set_velocity, probe: WireProbe, count: int) -> list[float]:
    latencies = []
    for i in range(count):
        vx = 0.3 + (i % 10) * 0.1                   # each command differs from the last
        t0 = time.perf_counter()
        set_velocity(vx, 0.0, 0.0, 0.0)
        t1 = probe.wait_for(vx)
        if t1 is not None:
            latencies.append(t1 - t0)
        time.sleep(0.05)                             # a 20 Hz stick
    return latencies


def through_the_window(probe: WireProbe, count: int) -> tuple[list[float], list[float]]:
    """(on-screen stick, gamepad) latencies to the wire through the real window on the embedded driver."""
    import tempfile
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    from PyQt5.QtCore import QSettings, QTimer
    from PyQt5.QtWidgets import QApplication

    from driver.vehicle import Vehicle, VehicleConfig
    from uavviewer.gamepad import VirtualPad
    from uavviewer.main_window import MainWindow

    app = QApplication.instance() or QApplication(sys.argv[:1])
    vehicle = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{probe.port}")).start()
    settings = QSettings(os.path.join(tempfile.mkdtemp(), "bench.ini"), QSettings.IniFormat)
    w = MainWindow(vehicle, qsettings=settings, default_cameras=[])
    w.show()
    w.activateWindow()
    pad = VirtualPad("Bench pad")
    screen: list[float] = []
    gamepad: list[float] = []
    done = threading.Event()

    def until(test, timeout: float = 20.0) -> None:
        deadline = time.monotonic() + timeout
        while not test():
            if time.monotonic() > deadline:
                raise RuntimeError("the window did not get ready")
            app.processEvents()
            time.sleep(0.005)

    def move_the_pad() -> None:            # another thread, as a device: the UI thread runs its event loop
        try:
            probe.wait_for(0.0)                                     # the on-screen stick's centre went out
            last = 0.0
            for i in range(count):
                t0 = time.perf_counter()
                pad.set_axis("righty", 0.3 + (i % 10) * 0.07)      # each differs from the last
                got = probe.wait_for_change(last)
                if got is not None:
                    gamepad.append(got[0] - t0)
                    last = got[1]
                time.sleep(0.05)                                    # a 20 Hz stick
            pad.centre()
        finally:
            done.set()

    try:
        until(lambda: w.leftStick.isEnabled())                     # the probe is flying in GUIDED
        for i in range(count):
            x = 0.3 + (i % 10) * 0.07
            t0 = time.perf_counter()
            w.rightStick.hold(0.0, x)
            t1 = probe.wait_for(w.adapter.setpoint.forward)
            if t1 is not None:
                screen.append(t1 - t0)
            until(lambda: True)
            time.sleep(0.05)
        w.rightStick.centre()
        until(lambda: w.gamepad.pad is not None and w.gamepad.status == "")
        threading.Thread(target=move_the_pad, daemon=True).start()
        check = QTimer()
        check.timeout.connect(lambda: done.is_set() and app.quit())
        check.start(50)
        app.exec_()
    finally:
        pad.detach()
        w.quit_without_asking()
        vehicle.close()
    return screen, gamepad


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--calls", type=int, default=2000)
    ap.add_argument("--sticks", type=int, default=200)
    ap.add_argument("--no-ice", action="store_true", help="only the embedded driver and the window")
    opts = ap.parse_args()
    if opts.no_ice:
        print(f"stick to wire, {opts.sticks} velocity changes at 20 Hz")
        embedded_and_window(opts.sticks)
        return 0

    import Ice

    from driver.ice import load_slice
    from driver.ice.client import IceDrone, viewer_properties
    from driver.vehicle import Vehicle, VehicleConfig
    jderobot, mavlinkserver = load_slice()

    probe = WireProbe()
    port = free_port()
    server = subprocess.Popen([sys.executable, "-m", "driver", "--master", f"tcp:127.0.0.1:{probe.port}",
                               "--daemon", "--no-log", "--one-port", str(port)], cwd=ROOT,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    com = Ice.initialize(["--Ice.Default.InvocationTimeout=5000"])
    drone = None
    try:
        pose = jderobot.Pose3DPrx.uncheckedCast(com.stringToProxy(f"Pose3D:tcp -h 127.0.0.1 -p {port}"))
        status = mavlinkserver.VehiclePrx.uncheckedCast(com.stringToProxy(f"Vehicle:tcp -h 127.0.0.1 -p {port}"))
        deadline = time.monotonic() + 20
        while True:
            try:
                if status.getStatus(-1, -1).mode == "GUIDED":
                    break
            except Ice.ConnectionRefusedException:
                pass
            if time.monotonic() > deadline:
                raise RuntimeError("server did not come up")
            time.sleep(0.1)

        print(f"Ice {Ice.stringVersion()}, server process, loopback, {opts.calls} calls each")
        empty, pose3d = [], []
        for _ in range(200):                         # warm up
            pose.ice_ping()
            pose.getPose3DData()
        for _ in range(opts.calls):
            t0 = time.perf_counter()
            pose.ice_ping()
            t1 = time.perf_counter()
            pose.getPose3DData()
            t2 = time.perf_counter()
            empty.append(t1 - t0)
            pose3d.append(t2 - t1)
        e = figures("ice_ping (empty call)", empty)
        p = figures("Pose3D.getPose3DData", pose3d)
        print(f"  ratio Pose3D / empty call: {p / e:.2f}")

        print(f"stick to wire, {opts.sticks} velocity changes at 20 Hz")
        props = viewer_properties(host=None)
        for name in ("Vehicle", "CMDVel"):
            props.setProperty(f"UAVViewer.{name}.Proxy", f"{name}:tcp -h 127.0.0.1 -p {port}")
        drone = IceDrone(props).start()
        if not drone.wait_for(lambda s: s.mode == "GUIDED", 10):
            raise RuntimeError("IceDrone did not see the vehicle")
        ice = figures("through Ice (IceDrone → wire)", stick_to_wire(drone.set_velocity, probe, opts.sticks))
    finally:
        if drone is not None:
            drone.close()
        com.destroy()
        server.terminate()
        server.wait(10)
        probe.close()

    local = embedded_and_window(opts.sticks)
    print(f"  Ice adds {(ice - local) * 1e3:.2f} ms to a stick movement (median)")
    return 0


def embedded_and_window(sticks: int) -> float:
    """The embedded driver's figure, then the window's (on-screen stick, gamepad); the first's median."""
    from driver.vehicle import Vehicle, VehicleConfig
    probe = WireProbe()
    vehicle = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{probe.port}")).start()
    try:
        if not vehicle.wait_for(lambda s: s.mode == "GUIDED", 10):
            raise RuntimeError("embedded driver did not see the probe")
        local = figures("embedded (Vehicle → wire)", stick_to_wire(vehicle.set_velocity, probe, sticks))
    finally:
        vehicle.close()
        probe.close()
    probe = WireProbe()
    try:
        screen, gamepad = through_the_window(probe, sticks)
    finally:
        probe.close()
    s = figures("window, on-screen stick → wire", screen)
    g = figures("window, gamepad axis event → wire", gamepad)
    print(f"  the gamepad adds {(g - s) * 1e3:.2f} ms to a stick movement (median; SDL polls the pads every 1 ms)")
    return local


if __name__ == "__main__":
    sys.exit(main())
