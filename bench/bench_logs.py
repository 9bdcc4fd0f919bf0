"""Log download bench (issue 31): a 2 MB and a 20 MB DataFlash log from the simulator, by LOG_DATA and by MAVLink
FTP, at 0, 10 and 30 % loss each way, with the embedded driver; and the MAVProxy-style baseline (LOG_REQUEST_DATA
for the whole log, started again from byte 0 after a silence). Links: ``tcp`` (the copter-4 profile over TCP, as
SITL), ``radio`` (copter-4 behind a 57,600-baud SiK radio without flow control: one LOG_DATA per call, a 1 kB
transmit buffer) and ``solo`` (the Solo profile on its own 921,600-baud flow-controlled link to its companion
computer: ten LOG_DATA per call, 3.3's request handling).

    .venv/bin/python bench/bench_logs.py [--sizes 2,20] [--paths log_data,ftp,baseline] [--loss 0,10,30]
                                         [--links tcp,radio,solo] [--speedup 1] [--ftp-speedup 1]
                                         [--radio-speedup 10] [--cell-limit 300] [--markdown]

Per cell: the time (from the request to the last byte, the log list the download reads first included, the
DFReader check not counted), the protocol floor, the ratio, the lossy floor and its ratio, bytes asked again
that were held already, and whether the file is byte-identical to the simulator's own (and DFReader reads it).

The floor is the time the simulator's link needs to send every packet of the log once: LOG_DATA at
min(61,000/s recorded, 600 a step x 50 steps) = 30,000 packets a sim second over TCP, and on a radio its baud / 10
bytes a second of 109-byte LOG_DATA frames; FTP one 239-byte packet every 5.5 ms sim, as recorded; divided by the
speed-up. The lossy floor is that floor / (1 - loss): through a link that drops that share every byte must cross
at least once, so the vehicle sends each packet 1 / (1 - loss) times on average (lost requests cost round trips,
not counted). The simulator is Python: at 0 % loss LOG_DATA runs at what its CPU sends, well below the recorded
5.5 MB/s, and it shares this 2-core machine with the driver (and with whatever else runs).
"""
from __future__ import annotations

import argparse
import contextlib
import logging
import math
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from pymavlink.dialects.v20 import ardupilotmega as mavlink  # noqa: E402

from driver.sim import SimConfig  # noqa: E402
from driver.sim import ftp as simftp  # noqa: E402
from driver.sim import logs as simlogs  # noqa: E402
from driver.sim.dataflash import LogFolder, write_flight_log  # noqa: E402
from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402
import tables  # noqa: E402

LINKS = {"tcp": ("copter-4", None), "radio": ("copter-4", 57_600), "solo": ("solo", 921_600)}
BASELINE_SILENCE = 1.0       # s without LOG_DATA before the baseline starts the whole log again (MAVProxy-like)
CELL_LIMIT = 300.0           # s a cell may take before it counts as not finished


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
def vehicle(logs: LogFolder, speedup: float, link: str, loss: float):
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


def make_log(folder: str, megabytes: float) -> tuple[LogFolder, int]:
    logs = LogFolder(folder)
    return logs, write_flight_log(logs, int(megabytes * 1_000_000))


def driver_cell(logs: LogFolder, number: int, path: str, loss: float, speedup: float, out: str,
                link: str = "tcp") -> dict:
    with vehicle(logs, speedup, link, loss) as port:
        return driver_download(port, logs, number, path, out)


def driver_download(port: int, logs: LogFolder, number: int, path: str, out: str) -> dict:
    v = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{port}")).start()
    try:
        if not v.wait_for(lambda s: s.connected, 20):
            return {"ok": False, "why": "no heartbeat"}
        outcome = v.logs.download(number, out, via=path).result(CELL_LIMIT)
        same = outcome.ok and open(out, "rb").read() == open(logs.path(number), "rb").read()
        return {"ok": outcome.ok, "why": outcome.reason, "seconds": outcome.seconds, "identical": same,
                "rerequested": outcome.bytes_rerequested, "received": outcome.bytes_received}
    except TimeoutError:
        return {"ok": False, "why": f"not finished in {CELL_LIMIT:.0f} s"}
    finally:
        v.close()


def baseline_cell(logs: LogFolder, number: int, loss: float, speedup: float, link: str = "tcp") -> dict:
    """MAVProxy-style: the whole log asked at once; after a silence with bytes missing, all of it again. Asked in
    MAVLink 1, which every firmware reads (the Solo's 3.3 reads nothing else)."""
    with vehicle(logs, speedup, link, loss) as port:
        return baseline_download(port, logs, number)


def baseline_download(port: int, logs: LogFolder, number: int) -> dict:
    sock = socket.create_connection(("127.0.0.1", port))
    sock.settimeout(0.05)
    mav = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
    parser = mavlink.MAVLink(None)
    parser.robust_parsing = True
    own = open(logs.path(number), "rb").read()
    size = len(own)
    try:
        start = time.monotonic()
        restarts, received = 0, 0
        chunks: dict[int, bytes] = {}
        last = 0.0
        sock.sendall(mav.log_request_data_encode(1, 1, number, 0, 0xFFFFFFFF).pack(mav, force_mavlink1=True))
        last = time.monotonic()
        while time.monotonic() - start < CELL_LIMIT:
            try:
                data = sock.recv(65536)
            except socket.timeout:
                data = b""
            for m in parser.parse_buffer(data) or []:
                if m.get_type() == "LOG_DATA" and m.id == number:
                    chunks[m.ofs] = bytes(m.data[:m.count])
                    received += m.count
                    last = time.monotonic()
            if sum(len(c) for c in chunks.values()) >= size:
                got = b"".join(chunks[o] for o in sorted(chunks))
                return {"ok": True, "seconds": time.monotonic() - start, "identical": got == own,
                        "rerequested": restarts * size, "received": received, "why": f"{restarts} restarts"}
            if time.monotonic() - last > BASELINE_SILENCE:
                restarts += 1
                chunks.clear()
                sock.sendall(mav.log_request_data_encode(1, 1, number, 0, 0xFFFFFFFF).pack(mav, force_mavlink1=True))
                last = time.monotonic()
        return {"ok": False, "why": f"not finished in {CELL_LIMIT:.0f} s ({restarts} restarts)", "identical": False,
                "rerequested": restarts * size, "received": received}
    finally:
        sock.close()


def main() -> None:
    global CELL_LIMIT
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", default="2,20", help="MB, comma-separated")
    p.add_argument("--paths", default="log_data,ftp,baseline")
    p.add_argument("--loss", default="0,10,30", help="percent each way, comma-separated")
    p.add_argument("--links", default="tcp", help="tcp, radio (57,600-baud SiK), solo (its 921,600-baud link)")
    p.add_argument("--speedup", type=float, default=1.0, help="the sim's speed-up for LOG_DATA and the baseline")
    p.add_argument("--ftp-speedup", type=float, default=1.0,
                   help="the sim's speed-up for FTP (paced at 5.5 ms a packet, as recorded). Above 1 it flatters "
                        "nothing and misleads: the driver's timers run in real time, so a lost request's wait costs "
                        "that many times more packets of the vehicle's than on a real link")
    p.add_argument("--cell-limit", type=float, default=CELL_LIMIT, help="s a cell may take (20 MB by FTP: ~460 s "
                   "clean)")
    p.add_argument("--radio-speedup", type=float, default=10.0, help="the sim's speed-up on the 57,600-baud radio")
    p.add_argument("--markdown", action="store_true")
    opts = p.parse_args()
    CELL_LIMIT = opts.cell_limit
    logging.basicConfig(level=logging.ERROR)
    head = ("log", "link", "path", "loss", "time s", "floor s", "x floor", "lossy floor s", "x lossy floor",
            "re-asked held B", "received B", "identical", "note")
    rows = []
    work = tempfile.mkdtemp(prefix="bench-logs-")
    try:
        for mb in (float(x) for x in opts.sizes.split(",")):
            logs, number = make_log(os.path.join(work, f"{mb:g}MB"), mb)
            size = os.path.getsize(logs.path(number))
            for link in opts.links.split(","):
                for path in opts.paths.split(","):
                    if path == "ftp" and LINKS[link][0] == "solo":
                        continue                                # the Solo has no MAVLink FTP
                    speedup = opts.radio_speedup if link == "radio" else \
                        opts.ftp_speedup if path == "ftp" else opts.speedup
                    for pct in (float(x) for x in opts.loss.split(",")):
                        rows.append(cell(logs, number, size, mb, link, path, pct, speedup, work))
                        print("  ".join(rows[-1]), flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print()
    print("\n".join(tables.render(head, rows, opts.markdown)))


def cell(logs: LogFolder, number: int, size: int, mb: float, link: str, path: str, pct: float, speedup: float,
         work: str) -> tuple:
    out = os.path.join(work, f"got-{mb:g}-{link}-{path}-{pct:g}.BIN")
    if path == "baseline":
        r = baseline_cell(logs, number, pct / 100, speedup, link)
    else:
        r = driver_cell(logs, number, path, pct / 100, speedup, out, link)
    floor = floor_seconds("ftp" if path == "ftp" else "log_data", size, speedup, link)
    lossy = floor / (1 - pct / 100)
    secs = r.get("seconds") if r["ok"] else None
    note = r["why"][:60] if path == "baseline" or not r["ok"] else ""
    if speedup != 1:
        note += f" (x{speedup:g} sim)"
    return (f"{size / 1e6:.1f} MB", link, path, f"{pct:g} %", f"{secs:.2f}" if secs else "-", f"{floor:.2f}",
            f"{secs / floor:.1f}" if secs else "-", f"{lossy:.2f}", f"{secs / lossy:.1f}" if secs else "-",
            str(r.get("rerequested", "-")), str(r.get("received", "-")), "yes" if r.get("identical") else "NO",
            note.strip())


if __name__ == "__main__":
    main()
