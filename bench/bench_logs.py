"""Log download bench: a DataFlash log downloaded by the embedded driver, by LOG_DATA and by MAVLink FTP, at 0, 10 and
30 % loss each way, against the link's floor; and the same log downloaded by the real MAVProxy (1.8.75) on the same
link, for comparison.

    .venv/bin/python bench/bench_logs.py [--sizes 2,20] [--paths log_data,ftp[,mavproxy]] [--loss 0,10,30]
                                         [--links tcp,radio,solo] [--loss-at sim,relay] [--runs 1]
                                         [--speedup 1] [--ftp-speedup 1] [--radio-speedup 10] [--cell-limit 300]
                                         [--mavproxy PATH] [--sitl PATH/arducopter [--instance 0]] [--markdown]
                                         [--write-docs]

The vehicle is the simulator (``python -m driver.sim`` in a process of its own, the log in its log folder) or, with
``--sitl``, ArduPilot's own SITL binary serving the same log file from its ``logs/`` folder (started here wiped, on
loopback, as bench/real_sitl.py starts it; the link is always ``tcp``, SITL's SERIAL0).

Links: ``tcp`` (the copter-4 profile over TCP, as SITL), ``radio`` (copter-4 behind a 57,600-baud SiK radio without
flow control: one LOG_DATA per call, a 1 kB transmit buffer) and ``solo`` (the Solo profile on its own 921,600-baud
flow-controlled link to its companion computer: ten LOG_DATA per call, 3.3's request handling).

Where the link loses frames (``--loss-at``): ``sim``, the simulator drops them each way on its TCP port (the
ground station on TCP: it cannot lose more than that); ``relay``, bench/lossy_relay.py in a process of its own
between the vehicle's TCP port and the ground station's ``udpin`` drops them, seeded (run N uses seed N for both
ground stations), and sends each frame the vehicle sends as one datagram, as a radio's bridge does: a ground station
that reads slower than the vehicle sends loses datagrams in its socket's buffer besides. Through the relay, the
relay's own pace (a Python process) bounds the clean link.

Paths: ``log_data`` and ``ftp``, the driver (``vehicle.logs.download(N, FILE, via=path)``), timed from the call (the
log list it reads first included) to the last byte, the DFReader check not counted; ``mavproxy``, MAVProxy's
``log download N FILE`` typed into its console once it has found the vehicle and fetched its parameters, timed to
its "Finished downloading" (bench/mavproxy_download.py says how it is run and what its log module does).

Per cell: the time (the median of ``--runs``, with the range), the protocol floor, the ratio, the lossy floor and
its ratio, bytes asked again that were held already, bytes received, and whether the file is byte-identical to the
vehicle's own. Then, for each link, loss and place of loss with both, the driver's LOG_DATA against MAVProxy.

The floor is the time the simulator's link needs to send every packet of the log once: LOG_DATA at
min(61,000/s recorded, 600 a step x 50 steps) = 30,000 packets a sim second over TCP, and on a radio its baud / 10
bytes a second of 109-byte LOG_DATA frames; FTP one 239-byte packet every 5.5 ms sim, as recorded; divided by the
speed-up. The lossy floor is that floor / (1 - loss): through a link that drops that share every byte must cross
at least once, so the vehicle sends each packet 1 / (1 - loss) times on average (lost requests cost round trips,
not counted). SITL's and the relay's rates are not modelled: their rows have no floor. The simulator is Python:
at 0 % loss LOG_DATA runs at what its CPU sends, well below the recorded 5.5 MB/s, and it shares this 2-core
machine with the driver (and with whatever else runs).
"""
from __future__ import annotations

import argparse
import contextlib
import logging
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from driver.sim import SimConfig  # noqa: E402
from driver.sim import ftp as simftp  # noqa: E402
from driver.sim import logs as simlogs  # noqa: E402
from driver.sim.dataflash import LogFolder, write_flight_log  # noqa: E402
from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402
from lossy_relay import free_udp_port  # noqa: E402
import mavproxy_download  # noqa: E402
import tables  # noqa: E402

LINKS = {"tcp": ("copter-4", None), "radio": ("copter-4", 57_600), "solo": ("solo", 921_600)}
CELL_LIMIT = 300.0           # s a cell may take before it counts as not finished
SITL_SETTLE = 10.0           # s the SITL runs after its first heartbeat before the first cell (its boot messages)
SITL_SERIAL0 = 5760          # SITL's SERIAL0 (tcp:0) for instance 0; 10 more for each instance after it


def floor_seconds(path: str, size: int, speedup: float, link: str = "tcp") -> float:
    """The time the link needs to carry each packet of the log once (see the module's docstring)."""
    if path == "ftp":
        interval, baud = simftp.PACKET_INTERVAL, LINKS[link][1]
        if baud and link == "radio":        # ArduPilot's burst delay leaves 2/3 of a radio without flow control free
            interval = max(interval, simftp.BURST_SHARE * (simftp.FRAME_OVERHEAD + simftp.CHUNK) / (baud / 10.0))
        return math.ceil(size / simftp.CHUNK) * interval / speedup
    rate = min(simlogs.LOG_DATA_RATE, simlogs.MAX_DATA_STEP * SimConfig.rate_hz)
    baud = LINKS[link][1]
    if baud:
        rate = min(rate, baud / 10.0 / simlogs.LOG_DATA_FRAME)
    return math.ceil(size / simlogs.LOG_DATA_SIZE) / rate / speedup


@contextlib.contextmanager
def simulator(logs: LogFolder, speedup: float, link: str, loss: float):
    """``python -m driver.sim`` in a process of its own (a vehicle is a computer of its own: in this process it
    would share the interpreter's lock with the driver), lossy from the start; yields its TCP port."""
    profile, baud = LINKS[link]
    cmd = [sys.executable, "-m", "driver.sim", "--tcp", "127.0.0.1:0", "--speedup", f"{speedup:g}", "--ready-after",
           "1", "--seed", "7", "--log-dir", logs.folder, "--profile", profile, "--uplink-loss", f"{loss:g}",
           "--downlink-loss", f"{loss:g}"] + (["--radio-baud", str(baud)] if baud else [])
    proc = subprocess.Popen(cmd, cwd=ROOT, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    try:
        port = None
        for line in proc.stderr:
            found = re.search(r"serving MAVLink on tcp:[\d.]+:(\d+)", line)
            if found:
                port = int(found.group(1))
                break
        threading.Thread(target=lambda: [None for _ in proc.stderr], daemon=True).start()   # drained
        if port is None:
            raise RuntimeError(f"the simulator did not start: {' '.join(cmd)}")
        yield port
    finally:
        proc.terminate()
        proc.wait(10)


@contextlib.contextmanager
def relay(tcp_port: int, loss: float, seed: int):
    """bench/lossy_relay.py in a process of its own; yields the ``udpin`` port a ground station listens on."""
    udp = free_udp_port()
    proc = subprocess.Popen([sys.executable, os.path.join(ROOT, "bench", "lossy_relay.py"), str(tcp_port), str(udp),
                             "--loss", f"{loss:g}", "--seed", str(seed)], stdout=subprocess.PIPE, text=True)
    try:
        if proc.stdout.readline().strip() != "relaying":
            raise RuntimeError("the relay did not reach the vehicle")
        yield udp
    finally:
        proc.terminate()
        proc.wait(10)


def make_log(folder: str, megabytes: float) -> tuple[LogFolder, int]:
    logs = LogFolder(folder)
    return logs, write_flight_log(logs, int(megabytes * 1_000_000))


def driver_download(connection: str, original: str, number: int, path: str, out: str) -> dict:
    v = Vehicle(VehicleConfig(connection=connection, tlog_path=None)).start()
    try:
        if not v.wait_for(lambda s: s.connected, 60):
            return {"ok": False, "why": "no heartbeat"}
        outcome = v.logs.download(number, out, via=path).result(CELL_LIMIT)
        return {"ok": outcome.ok, "why": outcome.reason, "seconds": outcome.seconds,
                "identical": outcome.ok and same(out, original),
                "rerequested": outcome.bytes_rerequested, "received": outcome.bytes_received}
    except TimeoutError:
        return {"ok": False, "why": f"not finished in {CELL_LIMIT:.0f} s"}
    finally:
        v.close()


def mavproxy_cell(mavproxy: str, connection: str, original: str, number: int, out: str, solo: bool) -> dict:
    r = mavproxy_download.download(mavproxy, connection, number, out, CELL_LIMIT, mavlink1=solo)
    r["identical"] = r["ok"] and same(out, original)
    if not r["ok"] and os.path.exists(out):
        held = held_share(out, original)
        r["why"] += f"; {held:.0f} % of the log held" if held else \
            "; no LOG_DATA came: its request was lost, and MAVProxy asks again only around packets it holds"
    return r


def same(path: str, original: str) -> bool:
    with open(path, "rb") as a, open(original, "rb") as b:
        return a.read() == b.read()


def held_share(path: str, original: str) -> float:
    """Percent of the log's 90-byte packets that ``path`` holds right (MAVProxy writes each at its offset)."""
    with open(path, "rb") as a, open(original, "rb") as b:
        got, own = a.read(), b.read()
    packets = range(0, len(own), simlogs.LOG_DATA_SIZE)
    right = sum(got[o:o + simlogs.LOG_DATA_SIZE] == own[o:o + simlogs.LOG_DATA_SIZE] for o in packets)
    return 100.0 * right / max(1, len(packets))


class Vehicles:
    """Where each cell's log comes from: the simulator started for the cell, or one SITL for the whole run."""

    def __init__(self, opts, work: str) -> None:
        self.opts, self.work, self.sitl = opts, work, None

    @contextlib.contextmanager
    def port(self, logs: LogFolder, link: str, loss_at: str, pct: float, speedup: float):
        if self.opts.sitl:
            yield SITL_SERIAL0 + 10 * self.opts.instance
            return
        with simulator(logs, speedup, link, pct / 100 if loss_at == "sim" else 0.0) as port:
            yield port

    def start_sitl(self, logs: LogFolder, number: int) -> None:
        """SITL in a scratch folder whose logs/ holds the log as 00000001.BIN (its LASTLOG.TXT says 1)."""
        from real_sitl import SHIM, Sitl
        scratch = os.path.join(self.work, "sitl")
        os.makedirs(os.path.join(scratch, "logs"))
        shutil.copyfile(logs.path(number), os.path.join(scratch, "logs", "00000001.BIN"))
        with open(os.path.join(scratch, "logs", "LASTLOG.TXT"), "w") as f:
            f.write("1\r\n")
        self.sitl = Sitl(self.opts.sitl, self.opts.instance, scratch, SHIM, None)
        self.sitl.start()
        from pymavlink import mavutil          # its boot waits for a connection on SERIAL0: one first, to its end
        port = SITL_SERIAL0 + 10 * self.opts.instance
        with contextlib.redirect_stdout(sys.stderr):
            link = mavutil.mavlink_connection(f"tcp:127.0.0.1:{port}", retries=100)
        try:
            if link.wait_heartbeat(timeout=60) is None:
                raise RuntimeError(f"no heartbeat from SITL on {port}")
            deadline = time.monotonic() + SITL_SETTLE
            while time.monotonic() < deadline:
                link.recv_match(blocking=True, timeout=0.5)
        finally:
            link.close()

    def stop(self) -> None:
        if self.sitl is not None:
            self.sitl.stop()
            self.sitl = None


def run_cell(vehicles: Vehicles, logs: LogFolder, number: int, link: str, loss_at: str, path: str, pct: float,
             speedup: float, run: int, out: str) -> dict:
    original = logs.path(number)
    listed = 1 if vehicles.opts.sitl else number
    with vehicles.port(logs, link, loss_at, pct, speedup) as port:
        with (relay(port, pct / 100, run) if loss_at == "relay" else contextlib.nullcontext()) as udp:
            connection = f"udpin:127.0.0.1:{udp}" if udp else f"tcp:127.0.0.1:{port}"
            if path == "mavproxy":
                return mavproxy_cell(vehicles.opts.mavproxy, connection, original, listed, out,
                                     LINKS[link][0] == "solo")
            return driver_download(connection, original, listed, path, out)


def main() -> None:
    global CELL_LIMIT
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", default="2,20", help="MB, comma-separated")
    p.add_argument("--paths", default="log_data,ftp", help="log_data, ftp (the driver), mavproxy (MAVProxy 1.8.75)")
    p.add_argument("--loss", default="0,10,30", help="percent each way, comma-separated")
    p.add_argument("--links", default="tcp", help="tcp, radio (57,600-baud SiK), solo (its 921,600-baud link)")
    p.add_argument("--loss-at", default="sim", help="sim (the simulator's TCP port), relay (bench/lossy_relay.py)")
    p.add_argument("--runs", type=int, default=1, help="runs of each cell: the time is their median")
    p.add_argument("--speedup", type=float, default=1.0, help="the sim's speed-up for LOG_DATA and MAVProxy")
    p.add_argument("--ftp-speedup", type=float, default=1.0,
                   help="the sim's speed-up for FTP (paced at 5.5 ms a packet, as recorded). Above 1 it flatters "
                        "nothing and misleads: the driver's timers run in real time, so a lost request's wait costs "
                        "that many times more packets of the vehicle's than on a real link")
    p.add_argument("--cell-limit", type=float, default=CELL_LIMIT, help="s a cell may take (20 MB by FTP: ~460 s "
                   "clean)")
    p.add_argument("--radio-speedup", type=float, default=10.0, help="the sim's speed-up on the 57,600-baud radio")
    p.add_argument("--mavproxy", default=mavproxy_download.find(), help="mavproxy.py to run (MAVProxy 1.8.75)")
    p.add_argument("--sitl", metavar="PATH", help="ArduPilot's arducopter SITL binary as the vehicle, instead of "
                   "the simulator (its link: tcp; loss only at the relay)")
    p.add_argument("--instance", type=int, default=0, help="the SITL's instance: SERIAL0 on TCP 5760 + 10 x N")
    p.add_argument("--markdown", action="store_true")
    tables.add_write_docs(p)
    opts = p.parse_args()
    CELL_LIMIT = opts.cell_limit
    paths, links, places = opts.paths.split(","), opts.links.split(","), opts.loss_at.split(",")
    if "mavproxy" in paths and not opts.mavproxy:
        p.error("MAVProxy not found: install it beside the project (bench/mavproxy_download.py), or --paths "
                "log_data,ftp")
    if opts.sitl:
        links = ["tcp"]                                         # SITL's SERIAL0; "sim": straight to it, at 0 % only
    logging.basicConfig(level=logging.ERROR)
    section = "logs" + ("/sitl" if opts.sitl else "/mavproxy" if "mavproxy" in paths else "")
    with tables.publishing(section, opts.write_docs):
        run(opts, paths, links, places)


def run(opts, paths: list[str], links: list[str], places: list[str]) -> None:
    head = ("log", "vehicle", "link", "loss at", "path", "loss", "time s", "floor s", "x floor", "lossy floor s",
            "x lossy floor", "re-asked held B", "received B", "identical", "note")
    rows, medians = [], {}
    work = tempfile.mkdtemp(prefix="bench-logs-")
    vehicles = Vehicles(opts, work)
    try:
        for mb in (float(x) for x in opts.sizes.split(",")):
            logs, number = make_log(os.path.join(work, f"{mb:g}MB"), mb)
            size = os.path.getsize(logs.path(number))
            if opts.sitl:
                vehicles.stop()
                vehicles.start_sitl(logs, number)
            for link in links:
                for place in places:
                    for path in paths:
                        if path == "ftp" and LINKS[link][0] == "solo":
                            continue                            # the Solo has no MAVLink FTP
                        speedup = opts.radio_speedup if link == "radio" else \
                            opts.ftp_speedup if path == "ftp" else opts.speedup
                        for pct in (float(x) for x in opts.loss.split(",")):
                            if opts.sitl and pct and place != "relay":
                                continue                        # SITL loses nothing by itself
                            results = []
                            for run in range(1, opts.runs + 1):
                                out = os.path.join(work, f"got-{mb:g}-{link}-{place}-{path}-{pct:g}-{run}.BIN")
                                results.append(run_cell(vehicles, logs, number, link, place, path, pct, speedup,
                                                        run, out))
                                print(f"  {mb:g} MB {link} {place} {path} {pct:g} % run {run}: "
                                      f"{summary(results[-1])}", file=sys.stderr, flush=True)
                            rows.append(row(results, size, mb, link, place, path, pct, speedup, opts))
                            medians[(mb, link, place, pct, path)] = results
    finally:
        vehicles.stop()
        shutil.rmtree(work, ignore_errors=True)
    vehicle = "ArduCopter 4.6.3 SITL" if opts.sitl else "the simulator"
    print(f"Log download from {vehicle}, {opts.runs} run(s) a cell (time: median, range when more than one; "
          f"cell limit {CELL_LIMIT:.0f} s)")
    print()
    print("\n".join(tables.render(head, rows, opts.markdown)))
    comparison = compare(medians, opts)
    if comparison:
        print()
        print("The driver's LOG_DATA against MAVProxy 1.8.75 on the same link (median times; the driver's includes "
              "the log list it reads first, MAVProxy's starts at its download command):")
        print()
        print("\n".join(tables.render(("log", "link", "loss at", "loss", "driver s", "MAVProxy s",
                                       "MAVProxy / driver", "MAVProxy finished", "byte-identical"),
                                      comparison, opts.markdown)))


def summary(r: dict) -> str:
    if r["ok"]:
        return f"{r['seconds']:.2f} s, identical {bool(r.get('identical'))}"
    return f"not done: {r.get('why', '')}"


def median_seconds(results: list[dict]) -> float | None:
    """The median time of the runs, a run not finished counting as longer than any finished (None: most did not)."""
    times = sorted(r["seconds"] if r["ok"] else math.inf for r in results)
    m = statistics.median_low(times) if len(times) % 2 == 0 else statistics.median(times)
    return None if math.isinf(m) else m


def timed(results: list[dict]) -> str:
    m = median_seconds(results)
    done = [r["seconds"] for r in results if r["ok"]]
    if m is None:
        return "-"
    if len(results) == 1:
        return f"{m:.2f}"
    return f"{m:.2f} ({min(done):.2f}-{max(done):.2f}, {len(done)}/{len(results)} done)"


def row(results: list[dict], size: int, mb: float, link: str, place: str, path: str, pct: float, speedup: float,
        opts) -> tuple:
    m = median_seconds(results)
    modelled = not opts.sitl and place == "sim"
    floor = floor_seconds("ftp" if path == "ftp" else "log_data", size, speedup, link) if modelled else None
    lossy = floor / (1 - pct / 100) if floor else None
    unfinished = [r["why"] for r in results if not r["ok"]]       # first: why a run did not finish
    notes = list(dict.fromkeys(unfinished + [r["why"][:90] for r in results if r["ok"] and path == "mavproxy"]))
    note = "; ".join(n for n in notes[:2] if n)
    if speedup != 1:
        note += f" (x{speedup:g} sim)"

    def ratio(over: float | None) -> str:
        return f"{m / over:.1f}" if m and over else "-"

    def most(key: str) -> str:
        values = [r[key] for r in results if key in r]
        return f"{max(values):,}" if values else "-"
    return (f"{size / 1e6:.1f} MB", "SITL" if opts.sitl else "sim", link, where(place, opts),
            "MAVProxy 1.8.75" if path == "mavproxy" else "driver " + {"log_data": "LOG_DATA", "ftp": "FTP"}[path],
            f"{pct:g} %", timed(results), f"{floor:.2f}" if floor else "-", ratio(floor),
            f"{lossy:.2f}" if lossy else "-", ratio(lossy), most("rerequested"), most("received"),
            identical(results), note.strip())


def identical(results: list[dict]) -> str:
    """Whether every download that finished is byte-identical ("-": none finished): one that did not finish is
    counted in its own column, not as a corrupt file."""
    done = [r for r in results if r["ok"]]
    if not done:
        return "-"
    return ("yes" if all(r.get("identical") for r in done) else "NO") + \
        (f" ({len(done)} of {len(results)} finished)" if len(done) < len(results) else "")


def where(place: str, opts) -> str:
    """Where the link loses frames, in words: SITL loses none by itself, so "sim" there is its plain TCP port."""
    return "none (TCP)" if opts.sitl and place == "sim" else place


def compare(medians: dict, opts) -> list[tuple]:
    out = []
    for (mb, link, place, pct, path), results in medians.items():
        if path != "log_data" or (mb, link, place, pct, "mavproxy") not in medians:
            continue
        theirs = medians[(mb, link, place, pct, "mavproxy")]
        ours_s, theirs_s = median_seconds(results), median_seconds(theirs)
        finished = sum(r["ok"] for r in theirs)
        if theirs_s is None:
            ratio = f"> {CELL_LIMIT / ours_s:.0f}" if ours_s else "-"
        else:
            ratio = f"{theirs_s / ours_s:.1f}" if ours_s else "-"
        out.append((f"{mb:g} MB", link, where(place, opts), f"{pct:g} %", f"{ours_s:.2f}" if ours_s else "-",
                    f"{theirs_s:.2f}" if theirs_s else f"not done in {CELL_LIMIT:.0f}", ratio,
                    f"{finished}/{len(theirs)}",
                    identical(results + theirs)))
    return out


if __name__ == "__main__":
    main()
