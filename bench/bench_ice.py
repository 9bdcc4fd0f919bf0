#!/usr/bin/env python3
"""Ice figures: Pose3D round trip beside an empty Ice call, and stick-to-wire latency through Ice.

    python bench/bench_ice.py [--calls 2000] [--sticks 200]

The server runs as its own process (``python -m driver``), connected to a small
MAVLink probe here that plays a GUIDED, armed vehicle and timestamps every
SET_POSITION_TARGET_LOCAL_NED the driver writes on the TCP link.

1. Round trip: ``getPose3DData`` and ``ice_ping`` (the empty call) alternate on
   the same proxy connection; median and 95th percentile, and their ratio
   (the server's own work per Pose3D call, the 2017 server slept 50 ms here).
2. Stick to wire: ``IceDrone.set_velocity`` (what the viewer calls when a stick
   moves) → CMDVel → server → driver → MAVLink on the wire; beside the same for
   the embedded driver (``Vehicle.set_velocity``, no Ice).
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


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--calls", type=int, default=2000)
    ap.add_argument("--sticks", type=int, default=200)
    opts = ap.parse_args()

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

    probe = WireProbe()
    vehicle = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{probe.port}")).start()
    try:
        if not vehicle.wait_for(lambda s: s.mode == "GUIDED", 10):
            raise RuntimeError("embedded driver did not see the probe")
        local = figures("embedded (Vehicle → wire)", stick_to_wire(vehicle.set_velocity, probe, opts.sticks))
    finally:
        vehicle.close()
        probe.close()
    print(f"  Ice adds {(ice - local) * 1e3:.2f} ms to a stick movement (median)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
