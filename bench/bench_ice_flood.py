"""Can Ice clients that flood the server starve the driver's flight threads?

    .venv/bin/python bench/bench_ice_flood.py [--clients 4] [--inflight 4] [--seconds 10] [--pool 2,8] [--write-docs]

The simulated vehicle runs in a process of its own (as the autopilot is a machine of its own) and stamps,
with the system's monotonic clock, every HEARTBEAT and SET_POSITION_TARGET_LOCAL_NED it receives from the
driver. This process is the server as ``python -m driver`` runs it: the driver plus the Ice server, hovering
at 3 m. A pilot process holds a yaw stick over Ice (CMDVel every 100 ms, as the viewer) and polls the
status, timing each call. First a quiet phase, then N flooding client processes, each keeping K calls in
flight (getPose3DData, setCMDVelData with the pilot's own value, getStatus(-1, -1) for every message),
for the same time. Printed: the driver's heartbeat and setpoint streams at the vehicle, the pilot's round
trips, the flood's throughput, and the ratios flood/quiet.
"""
from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import statistics
import sys
import threading
import time
import tables  # bench/tables.py: this script runs from bench/

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

PILOT_YAW = 0.2                      # rad/s, nose right: the stick the pilot holds (the vehicle turns in place)


# -- the vehicle, in its own process ----------------------------------------------------------------------
def vehicle_process(conn) -> None:
    """The simulator; stamps what the driver sends it; answers ("collect", t0, t1) with those stamps."""
    from driver.sim import SimConfig, SimVehicle
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=1.0, ready_after=1.0))
    stamps: list[tuple[float, str]] = []
    lock = threading.Lock()
    forward = sim.server.on_message

    def stamped(msg, *rest):
        kind = msg.get_type()
        if kind in ("HEARTBEAT", "SET_POSITION_TARGET_LOCAL_NED"):
            with lock:
                stamps.append((time.monotonic(), kind))
        return forward(msg, *rest)
    sim.server.on_message = stamped
    sim.start()
    conn.send(sim.tcp_port)
    while True:
        request = conn.recv()
        if request[0] == "stop":
            break
        _, t0, t1 = request
        with lock:
            conn.send([s for s in stamps if t0 <= s[0] < t1])
    sim.stop()


# -- the pilot and the flooders, each a process -------------------------------------------------------------
def pilot_process(endpoint: str, seconds: float, conn) -> None:
    """Holds the yaw stick (CMDVel at 10 Hz) and polls getStatus at 10 Hz, as the viewer; times each call."""
    import Ice
    from driver.ice import load_slice
    jderobot, mavlinkserver = load_slice()
    com = Ice.initialize(["--Ice.Default.InvocationTimeout=5000"])
    cmdvel = jderobot.CMDVelPrx.uncheckedCast(com.stringToProxy(f"CMDVel:{endpoint}"))
    vehicle = mavlinkserver.VehiclePrx.uncheckedCast(com.stringToProxy(f"Vehicle:{endpoint}"))
    stick = jderobot.CMDVelData(0.0, 0.0, 0.0, 0.0, 0.0, -PILOT_YAW)       # angularZ counter-clockwise
    samples: list[tuple[float, str, float]] = []
    end = time.monotonic() + seconds
    next_call = time.monotonic()
    while time.monotonic() < end:
        for name, call in (("CMDVel", lambda: cmdvel.setCMDVelData(stick)),
                           ("getStatus", lambda: vehicle.getStatus(0, 0))):
            t = time.monotonic()
            try:
                call()
                samples.append((t, name, time.monotonic() - t))
            except Ice.Exception:
                samples.append((t, name, float("inf")))
        next_call += 0.1
        time.sleep(max(0.0, next_call - time.monotonic()))
    com.destroy()
    conn.send(samples)


def flood_process(endpoint: str, seconds: float, inflight: int, conn) -> None:
    """Keeps ``inflight`` calls outstanding on one connection for ``seconds``; sends back how many completed.

    Niced: a flooder stands for another machine; on this one's few cores at full priority it would measure the
    kernel's scheduler sharing the cores, not what the flood does to the server's process."""
    os.nice(10)
    import Ice
    from driver.ice import load_slice
    jderobot, mavlinkserver = load_slice()
    com = Ice.initialize(["--Ice.Default.InvocationTimeout=5000", "--Ice.MessageSizeMax=65536"])
    pose = jderobot.Pose3DPrx.uncheckedCast(com.stringToProxy(f"Pose3D:{endpoint}"))
    cmdvel = jderobot.CMDVelPrx.uncheckedCast(com.stringToProxy(f"CMDVel:{endpoint}"))
    vehicle = mavlinkserver.VehiclePrx.uncheckedCast(com.stringToProxy(f"Vehicle:{endpoint}"))
    stick = jderobot.CMDVelData(0.0, 0.0, 0.0, 0.0, 0.0, -PILOT_YAW)
    calls = (pose.getPose3DDataAsync, lambda: cmdvel.setCMDVelDataAsync(stick), lambda: vehicle.getStatusAsync(-1, -1))
    slots = threading.Semaphore(inflight)
    counts = {"done": 0, "failed": 0}
    lock = threading.Lock()

    def done(future) -> None:
        with lock:
            counts["done" if future.exception() is None else "failed"] += 1
        slots.release()
    end = time.monotonic() + seconds
    i = 0
    while time.monotonic() < end:
        slots.acquire()
        calls[i % len(calls)]().add_done_callback(done)
        i += 1
    for _ in range(inflight):
        slots.acquire()
    com.destroy()
    conn.send(counts)


# -- figures ------------------------------------------------------------------------------------------------
def intervals(stamps: list[tuple[float, str]], kind: str) -> list[float]:
    times = [t for t, k in stamps if k == kind]
    return [b - a for a, b in zip(times, times[1:])]


def describe(gaps: list[float]) -> dict[str, float]:
    if not gaps:
        return {"rate": 0.0, "median": float("nan"), "p95": float("nan"), "max": float("nan")}
    ordered = sorted(gaps)
    return {"rate": len(gaps) / sum(gaps), "median": statistics.median(gaps),
            "p95": ordered[int(0.95 * (len(ordered) - 1))], "max": ordered[-1]}


def row(label: str, quiet: dict, flood: dict, unit: str = "ms", scale: float = 1e3) -> str:
    def ratio(key: str) -> str:
        return f"{flood[key] / quiet[key]:.2f}" if quiet[key] else "-"
    return (f"{label:34} quiet median {quiet['median'] * scale:7.1f} p95 {quiet['p95'] * scale:7.1f} max "
            f"{quiet['max'] * scale:7.1f} {unit} | flood median {flood['median'] * scale:7.1f} p95 "
            f"{flood['p95'] * scale:7.1f} max {flood['max'] * scale:7.1f} {unit} | ratio median {ratio('median')} "
            f"p95 {ratio('p95')} max {ratio('max')}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clients", type=int, default=4, help="flooding client processes (default 4)")
    ap.add_argument("--inflight", type=int, default=4, help="calls each keeps outstanding (default 4)")
    ap.add_argument("--seconds", type=float, default=10.0, help="length of each phase (default 10)")
    ap.add_argument("--pool", help="server thread pool SIZE,SIZEMAX (default: the server's)")
    ap.add_argument("--switch-interval", type=float, help="sys.setswitchinterval for the server's process (s)")
    ap.add_argument("--ice", action="append", default=[], metavar="KEY=VALUE",
                    help="more server properties, e.g. --ice MAVLinkServer.CallRate=200")
    tables.add_write_docs(ap)
    args = ap.parse_args()
    import Ice  # noqa: F401  (the server's process: import before the driver's threads start)
    if args.switch_interval:
        sys.setswitchinterval(args.switch_interval)

    from driver.ice.server import IceServer, default_properties
    from driver.vehicle import Vehicle, VehicleConfig

    ctx = mp.get_context("spawn")                      # children carry none of this process's threads
    sim_end, sim_side = ctx.Pipe()
    sim = ctx.Process(target=vehicle_process, args=(sim_side,), daemon=True)
    sim.start()
    port = sim_end.recv()
    drone = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{port}", tlog_path=None)).start()
    server_port = 20999
    props = [f"--MAVLinkServer.Endpoints=tcp -h 127.0.0.1 -p {server_port}"]
    if args.pool:
        size, size_max = args.pool.split(",")
        props += [f"--Ice.ThreadPool.Server.Size={size}", f"--Ice.ThreadPool.Server.SizeMax={size_max}"]
    props += [f"--{kv}" for kv in args.ice]
    server = IceServer(drone, default_properties(props)).start()
    endpoint = f"tcp -h 127.0.0.1 -p {server_port}"
    workers: list = []
    try:
        result = drone.takeoff(3.0).result(timeout=90)
        assert result.ok, result
        print(f"GIL switch interval {sys.getswitchinterval() * 1e3:g} ms, "
              f"server pool Size={server.properties.getProperty('Ice.ThreadPool.Server.Size')} "
              f"SizeMax={server.properties.getProperty('Ice.ThreadPool.Server.SizeMax')}, "
              f"{args.clients} flooding clients x {args.inflight} calls in flight, {args.seconds:g} s per phase, "
              f"{os.cpu_count()} cores")
        pilot_end, pilot_side = ctx.Pipe()
        pilot = ctx.Process(target=pilot_process, args=(endpoint, 2 * args.seconds + 2.0, pilot_side), daemon=True)
        pilot.start()
        workers.append(pilot)
        time.sleep(1.0)                                # the pilot's stick is streaming
        quiet = (time.monotonic(), time.monotonic() + args.seconds)
        time.sleep(args.seconds)

        ends = []
        for _ in range(args.clients):
            end, side = ctx.Pipe()
            p = ctx.Process(target=flood_process, args=(endpoint, args.seconds + 1.5, args.inflight, side),
                            daemon=True)
            p.start()
            workers.append(p)
            ends.append(end)
        time.sleep(1.5)                                # the flooders are up (spawned Python starts slowly)
        flood = (time.monotonic(), time.monotonic() + args.seconds)
        flood_counts = [end.recv() for end in ends]
        pilot_samples = pilot_end.recv()

        def at_vehicle(window):
            sim_end.send(("collect", *window))
            return sim_end.recv()
        quiet_stamps, flood_stamps = at_vehicle(quiet), at_vehicle(flood)
        done = sum(c["done"] for c in flood_counts)
        failed = sum(c["failed"] for c in flood_counts)
        print(f"flood: {done / (args.seconds + 1.5):.0f} calls/s answered over {args.clients} connections, "
              f"{failed} failed")
        for kind, label in (("SET_POSITION_TARGET_LOCAL_NED", "setpoint interval at the vehicle"),
                            ("HEARTBEAT", "heartbeat interval at the vehicle")):
            q, f = describe(intervals(quiet_stamps, kind)), describe(intervals(flood_stamps, kind))
            print(row(label, q, f))
            print(f"{'':34} rate quiet {q['rate']:.2f} Hz, flood {f['rate']:.2f} Hz (ratio "
                  f"{f['rate'] / q['rate'] if q['rate'] else float('nan'):.2f})")
        for name in ("CMDVel", "getStatus"):
            def rtts(window):
                return [r for t, n, r in pilot_samples if n == name and window[0] <= t < window[1]]
            q, f = rtts(quiet), rtts(flood)
            lost = sum(1 for r in f if r == float("inf"))
            print(row(f"pilot {name} round trip", describe(q), describe([r for r in f if r != float("inf")]))
                  + (f", {lost} failed" if lost else ""))
    finally:
        for p in workers:
            p.join(timeout=5)
        try:
            drone.land().result(timeout=5)
        except Exception:
            pass
        server.close()
        drone.close()
        sim_end.send(("stop",))
        sim.join(timeout=5)


if __name__ == "__main__":
    with tables.publishing("ice_flood"):
        main()
