"""What many observers cost a MAVLinkServer: polling it against subscribing to its IceStorm topic.

    .venv/bin/python bench/bench_fleet.py [--observers 1,10,50] [--seconds 8] [--lookups 300] [--write-docs]

Starts a lab (Debian's icegridregistry and IceStorm in IceBox, :mod:`driver.ice.lab`) on a free loopback port
and one server as ``python -m driver --sim --daemon --registry ... --name bench-1`` in its own process (the
simulated vehicle inside it, hovering on the ground). For each number of observers, first polling then
IceStorm, two observer processes (niced: they stand for other machines) run half the observers each:

- polling: each observer, on its own connection, calls ``getStatus`` every 0.1 s as the viewer's client does;
- IceStorm: each observer subscribes its own servant to the vehicle's topic (the server publishes at 10 Hz).

Printed per row: the server process's CPU (user + system, % of one core) and IceBox's, and the age of the
status an observer receives (receipt wall clock − the driver's snapshot time), p50/p95; with IceStorm also
the pose's publish-to-receipt latency (the server stamps each pose as it publishes it), p50/p95. Then the
registry's lookup time: listing the fleet (IceGrid::Query), resolving an adapter id (Locator), and a fresh
client's first call through ``Pose3D@bench-1`` against a direct proxy.
"""
from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import statistics
import subprocess
import sys
import threading
import time
import tables  # bench/tables.py: this script runs from bench/

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

NAME = "bench-1"
TICK = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process so far (its threads included)."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def percentile(values: list[float], q: float) -> float:
    if not values:
        return float("nan")
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


# -- observers, in processes of their own ---------------------------------------------------------------------
def observer_process(locator: str, mode: str, count: int, seconds: float, conn) -> None:
    os.nice(5)
    import Ice
    from driver.ice import load_slice
    from driver.ice.publisher import topic
    from driver.ice.registry import TOPIC_MANAGER
    jderobot, mavlinkserver = load_slice()
    com = Ice.initialize([f"--Ice.Default.Locator={locator}", "--Ice.Default.InvocationTimeout=5000",
                          "--Ice.ThreadPool.Server.SizeMax=4", "--Ice.ThreadPool.Client.SizeMax=4"])
    ages: list[float] = []
    latencies: list[float] = []
    lock = threading.Lock()
    stop = threading.Event()
    measuring = threading.Event()

    if mode == "poll":
        def poll(i: int) -> None:
            prx = mavlinkserver.VehiclePrx.uncheckedCast(com.stringToProxy(f"Vehicle@{NAME}").ice_connectionId(f"o{i}"))
            since_m = since_r = -1
            next_call = time.monotonic()
            while not stop.is_set():
                try:
                    st = prx.getStatus(since_m, since_r)
                    now = time.time()
                    if st.messages:
                        since_m = st.messages[-1].index
                    if st.results:
                        since_r = st.results[-1].index
                    if measuring.is_set():
                        with lock:
                            ages.append(now - st.time)
                except Ice.Exception:
                    pass
                next_call += 0.1
                stop.wait(max(0.0, next_call - time.monotonic()))
        threads = [threading.Thread(target=poll, args=(i,), daemon=True) for i in range(count)]
        for t in threads:
            t.start()
        subscription = None
    else:
        class Observer(mavlinkserver.Telemetry):
            def status(self, vehicle, status, current=None):
                if measuring.is_set():
                    now = time.time()
                    with lock:
                        ages.append(now - status.time)

            def pose(self, vehicle, published, pose, current=None):
                if measuring.is_set():
                    now = time.time()
                    with lock:
                        latencies.append(now - published)

            def navdata(self, vehicle, data, current=None):
                pass

            def event(self, vehicle, e, current=None):
                pass

            def payload(self, vehicle, p, current=None):
                pass
        adapter = com.createObjectAdapterWithEndpoints("Observers", "tcp -h 127.0.0.1")
        adapter.activate()
        t = topic(com, TOPIC_MANAGER, NAME)
        subscribers = [adapter.addWithUUID(Observer()).ice_oneway() for _ in range(count)]
        for s in subscribers:
            t.subscribeAndGetPublisher({}, s)
        subscription = (t, subscribers)
        threads = []
    conn.send("ready")
    conn.recv()                                 # "measure"
    measuring.set()
    time.sleep(seconds)
    measuring.clear()
    stop.set()
    if subscription is not None:
        t, subscribers = subscription
        for s in subscribers:
            t.unsubscribe(s)
    for th in threads:
        th.join(2)
    with lock:
        conn.send((ages, latencies))
    com.destroy()


def run_row(locator: str, mode: str, count: int, seconds: float, server_pid: int, box_pid: int) -> dict:
    ctx = mp.get_context("spawn")
    split = [count - count // 2, count // 2] if count > 1 else [1]
    procs, pipes = [], []
    for n in split:
        parent, child = ctx.Pipe()
        p = ctx.Process(target=observer_process, args=(locator, mode, n, seconds, child), daemon=True)
        p.start()
        procs.append(p)
        pipes.append(parent)
    for pipe in pipes:
        pipe.recv()
    time.sleep(2.0)                             # connections made, subscriptions flowing
    c0, b0, t0 = cpu_seconds(server_pid), cpu_seconds(box_pid), time.monotonic()
    for pipe in pipes:
        pipe.send("measure")
    ages, latencies = [], []
    for pipe in pipes:
        a, lat = pipe.recv()
        ages += a
        latencies += lat
    elapsed = time.monotonic() - t0
    c1, b1 = cpu_seconds(server_pid), cpu_seconds(box_pid)
    for p in procs:
        p.join(10)
    return dict(mode=mode, observers=count, server_cpu=100 * (c1 - c0) / elapsed, box_cpu=100 * (b1 - b0) / elapsed,
                received=len(ages) / elapsed, age50=percentile(ages, 0.5) * 1e3, age95=percentile(ages, 0.95) * 1e3,
                lat50=percentile(latencies, 0.5) * 1e3, lat95=percentile(latencies, 0.95) * 1e3)


def lookups(locator: str, count: int, direct: str) -> dict:
    import Ice
    from driver.ice import load_slice
    from driver.ice.registry import list_vehicles
    jderobot, _ = load_slice()
    com = Ice.initialize([f"--Ice.Default.Locator={locator}"])
    listing, resolving = [], []
    loc = com.getDefaultLocator()
    for _ in range(count):
        t = time.perf_counter()
        list_vehicles(com)
        listing.append(time.perf_counter() - t)
        t = time.perf_counter()
        loc.findAdapterById(NAME)
        resolving.append(time.perf_counter() - t)
    com.destroy()

    def first_call(proxy: str) -> float:
        c = Ice.initialize([f"--Ice.Default.Locator={locator}"])
        try:
            t = time.perf_counter()
            jderobot.Pose3DPrx.uncheckedCast(c.stringToProxy(proxy)).getPose3DData()
            return time.perf_counter() - t
        finally:
            c.destroy()
    indirect = [first_call(f"Pose3D@{NAME}") for _ in range(max(5, count // 10))]
    straight = [first_call(direct) for _ in range(max(5, count // 10))]
    return dict(listing=statistics.median(listing) * 1e3, listing95=percentile(listing, 0.95) * 1e3,
                resolving=statistics.median(resolving) * 1e3, resolving95=percentile(resolving, 0.95) * 1e3,
                indirect=statistics.median(indirect) * 1e3, direct=statistics.median(straight) * 1e3)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--observers", default="1,10,50")
    p.add_argument("--seconds", type=float, default=8.0)
    p.add_argument("--lookups", type=int, default=300)
    tables.add_write_docs(p)
    opts = p.parse_args()
    counts = [int(n) for n in opts.observers.split(",")]

    import Ice
    from driver.ice.lab import Lab
    from driver.ice.registry import list_vehicles
    sys.path.insert(0, os.path.join(ROOT, "tests"))
    from ice_fixtures import free_port

    with Lab(port=free_port()) as lab:
        box_pid = lab._procs[-1].pid
        server = subprocess.Popen([sys.executable, "-m", "driver", "--sim", "--daemon", "--no-log", "--registry",
                                   lab.address, "--name", NAME], cwd=ROOT, stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True)
        try:
            com = Ice.initialize([f"--Ice.Default.Locator={lab.locator}"])
            deadline = time.monotonic() + 30
            while NAME not in list_vehicles(com):
                if time.monotonic() > deadline or server.poll() is not None:
                    raise SystemExit(f"the server did not register: {server.stdout.read()}")
                time.sleep(0.1)
            endpoints = com.getDefaultLocator().findAdapterById(NAME)
            direct = com.proxyToString(endpoints.ice_identity(Ice.stringToIdentity("Pose3D")))
            com.destroy()
            time.sleep(2.0)                                     # the vehicle found, telemetry flowing
            print(f"# bench_fleet: server pid {server.pid} ({NAME}, simulated vehicle inside), IceBox pid {box_pid}, "
                  f"{os.cpu_count()} cores, {opts.seconds:g} s per row")
            print("| observers | mode | server CPU % | IceBox CPU % | statuses received /s | status age p50 / p95 ms "
                  "| pose publish→receipt p50 / p95 ms |")
            print("|---|---|---|---|---|---|---|")
            for count in counts:
                for mode in ("poll", "icestorm"):
                    r = run_row(lab.locator, mode, count, opts.seconds, server.pid, box_pid)
                    lat = f"{r['lat50']:.1f} / {r['lat95']:.1f}" if mode == "icestorm" else "–"
                    print(f"| {count} | {'polling' if mode == 'poll' else 'IceStorm'} | {r['server_cpu']:.1f} | "
                          f"{r['box_cpu']:.1f} | {r['received']:.0f} | {r['age50']:.1f} / {r['age95']:.1f} | {lat} |",
                          flush=True)
            r = lookups(lab.locator, opts.lookups, direct)
            print(f"\nregistry lookups ({opts.lookups}): list the fleet (IceGrid::Query) median {r['listing']:.2f} ms "
                  f"(p95 {r['listing95']:.2f}); resolve an adapter id (Locator) median {r['resolving']:.2f} ms "
                  f"(p95 {r['resolving95']:.2f}); a fresh client's first getPose3DData: Pose3D@{NAME} "
                  f"{r['indirect']:.2f} ms, direct proxy {r['direct']:.2f} ms")
        finally:
            server.terminate()
            try:
                server.wait(10)
            except subprocess.TimeoutExpired:
                server.kill()
            if server.stdout is not None:
                server.stdout.close()


if __name__ == "__main__":
    with tables.publishing("fleet"):
        main()
