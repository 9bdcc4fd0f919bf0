#!/usr/bin/env python3
"""Ice figures: every JdeRobot call beside an empty Ice call, and stick-to-wire latency through Ice, the
embedded driver, and the window (on-screen stick, gamepad).

    python bench/bench_ice.py [--calls 2000] [--sticks 200] [--no-ice] [--write-docs]

The server runs as its own process (``python -m driver --camera sim``), connected to a small
MAVLink probe here that plays a GUIDED, armed vehicle and timestamps every
SET_POSITION_TARGET_LOCAL_NED the driver writes on the TCP link.

1. Round trip: ``ice_ping`` (the empty call), ``Pose3D.getPose3DData``, ``Navdata.getNavdata``,
   ``CMDVel.setCMDVelData`` (JdeRobot's CMDVel has no getter) and ``Camera.getImageData("RGB8")``
   (the current 640×480 frame) take turns on one connection, all in one run; median and 95th
   percentile, and each one's ratio to the empty call (the server's own work per call; the 2017
   server slept 50 ms here). A frame is 921,600 bytes that Ice must copy whatever the servant does,
   so getImageData is also set beside the floor for that reply: a second process whose Camera answers
   with one prepared ImageData of the same size and does nothing else; likewise setCMDVelData beside a
   CMDVel there that takes the same CMDVelData and answers 0.
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
import tables  # noqa: E402  (bench/tables.py: this script runs from bench/)


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
    print(f"  {name:38} median {median * 1e6:8.0f} µs   p95 {p95 * 1e6:8.0f} µs   (n={len(samples)})")
    return median


IMAGE_SIZE = (640, 480)


def serve_floor() -> int:
    """The floor for a frame-sized reply: a Camera that answers one prepared 640×480 RGB8 ImageData."""
    import Ice

    from driver.ice import load_slice
    jderobot, _ = load_slice()
    w, h = IMAGE_SIZE
    data = jderobot.ImageData(jderobot.Time(0, 0), jderobot.ImageDescription(w, h, w * h * 3, "RGB8", ""),
                              bytes(w * h * 3))

    class Floor(jderobot.Camera):
        def getImageData(self, format, current=None):
            return data

    class FloorCMDVel(jderobot.CMDVel):
        def setCMDVelData(self, data, current=None):
            return 0

    props = Ice.createProperties()
    props.setProperty("Ice.MessageSizeMax", "4096")
    props.setProperty("Ice.ThreadPool.Server.Size", "1")       # as the driver's server
    props.setProperty("Ice.ThreadPool.Server.SizeMax", "2")
    init = Ice.InitializationData()
    init.properties = props
    with Ice.initialize(init) as com:
        adapter = com.createObjectAdapterWithEndpoints("Floor", "tcp -h 127.0.0.1")
        print(com.proxyToString(adapter.add(Floor(), Ice.stringToIdentity("Camera"))), flush=True)
        print(com.proxyToString(adapter.add(FloorCMDVel(), Ice.stringToIdentity("CMDVel"))), flush=True)
        adapter.activate()
        sys.stdin.read()                                        # until the bench closes our stdin
    return 0


def round_trips(calls: dict, count: int) -> dict[str, list[float]]:
    """Each call in turn, ``count`` times (after a warm-up): every call sees the same moments of the machine."""
    samples: dict[str, list[float]] = {name: [] for name in calls}
    for i in range(count + 200):
        for name, call in calls.items():
            t0 = time.perf_counter()
            call()
            t1 = time.perf_counter()
            if i >= 200:
                samples[name].append(t1 - t0)
    return samples


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
    from uavviewer.input.gamepad import VirtualPad
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
    ap.add_argument("--serve-floor", action="store_true", help=argparse.SUPPRESS)
    tables.add_write_docs(ap)
    opts = ap.parse_args()
    if opts.serve_floor:
        return serve_floor()
    if opts.no_ice:
        print(f"stick to wire, {opts.sticks} velocity changes at 20 Hz")
        embedded_and_window(opts.sticks)
        return 0

    import Ice

    from driver.ice import load_slice
    from driver.ice.client import IceDrone, viewer_properties
    jderobot, mavlinkserver = load_slice()

    probe = WireProbe()
    port = free_port()
    server = subprocess.Popen([sys.executable, "-m", "driver", "--master", f"tcp:127.0.0.1:{probe.port}",
                               "--daemon", "--no-log", "--one-port", str(port), "--camera", "sim"], cwd=ROOT,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    floor = subprocess.Popen([sys.executable, os.path.abspath(__file__), "--serve-floor"], cwd=ROOT,
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    com = Ice.initialize(["--Ice.Default.InvocationTimeout=5000", "--Ice.MessageSizeMax=4096"])
    drone = None
    try:
        def proxy(kind, name):
            return kind.uncheckedCast(com.stringToProxy(f"{name}:tcp -h 127.0.0.1 -p {port}"))
        pose = proxy(jderobot.Pose3DPrx, "Pose3D")
        nav = proxy(jderobot.NavdataPrx, "Navdata")
        cmdvel = proxy(jderobot.CMDVelPrx, "CMDVel")
        camera = proxy(jderobot.CameraPrx, "Camera")
        status = proxy(mavlinkserver.VehiclePrx, "Vehicle")
        floor_camera = jderobot.CameraPrx.uncheckedCast(com.stringToProxy(floor.stdout.readline().strip()))
        floor_cmdvel = jderobot.CMDVelPrx.uncheckedCast(com.stringToProxy(floor.stdout.readline().strip()))
        deadline = time.monotonic() + 20
        while True:
            try:
                if status.getStatus(-1, -1).mode == "GUIDED":
                    camera.getImageData("RGB8")
                    break
            except (Ice.ConnectionRefusedException, jderobot.DataNotExistException):
                pass
            if time.monotonic() > deadline:
                raise RuntimeError("server did not come up")
            time.sleep(0.1)

        hover = jderobot.CMDVelData(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        calls = {
            "ice_ping (empty call)": pose.ice_ping,
            "Pose3D.getPose3DData": pose.getPose3DData,
            "Navdata.getNavdata": nav.getNavdata,
            "CMDVel.setCMDVelData": lambda: cmdvel.setCMDVelData(hover),
            "Camera.getImageData RGB8 640x480": lambda: camera.getImageData("RGB8"),
            "floor: same-size ImageData, no work": lambda: floor_camera.getImageData("RGB8"),
            "floor: CMDVelData in, 0 out, no work": lambda: floor_cmdvel.setCMDVelData(hover),
        }
        print(f"Ice {Ice.stringVersion()}, server process, loopback, {opts.calls} calls each, taking turns")
        samples = round_trips(calls, opts.calls)
        medians = {name: figures(name, values) for name, values in samples.items()}
        empty = medians["ice_ping (empty call)"]
        for name in ("Pose3D.getPose3DData", "Navdata.getNavdata", "CMDVel.setCMDVelData",
                     "Camera.getImageData RGB8 640x480"):
            print(f"  ratio {name} / empty call: {medians[name] / empty:.2f}")
        image, floor_image = medians["Camera.getImageData RGB8 640x480"], medians["floor: same-size ImageData, no work"]
        print(f"  ratio Camera.getImageData / the floor for a 921,600-byte reply: {image / floor_image:.2f}")
        print(f"  ratio CMDVel.setCMDVelData / the floor for a CMDVelData call: "
              f"{medians['CMDVel.setCMDVelData'] / medians['floor: CMDVelData in, 0 out, no work']:.2f}")

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
        floor.stdin.close()
        floor.wait(10)
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
    with tables.publishing(tables.variant("ice", "--no-ice")):
        sys.exit(main())
