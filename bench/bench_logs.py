"""Log download bench (issue 31): a 2 MB and a 20 MB DataFlash log from the simulator, by LOG_DATA and by MAVLink
FTP, over TCP at 0, 10 and 30 % loss each way, with the embedded driver; and the MAVProxy-style baseline
(LOG_REQUEST_DATA for the whole log, started again from byte 0 after a silence).

    .venv/bin/python bench/bench_logs.py [--sizes 2,20] [--paths log_data,ftp,baseline] [--loss 0,10,30]
                                         [--speedup 1] [--ftp-speedup 20] [--markdown]

Per cell: the time (from the request to the last byte, the DFReader check not counted), the protocol floor (the
simulator's own pace for that path: LOG_DATA at min(61,000/s recorded, 600 a step x 50 steps) sim-s, FTP one
239-byte packet every 5.5 ms sim-s, as recorded; divided by the speed-up), the ratio, bytes asked again that
were held already, and whether the file is byte-identical to the simulator's own (and DFReader reads it). The
simulator is Python: at 0 % loss LOG_DATA runs at what its CPU sends, well below the recorded 5.5 MB/s.
"""
from __future__ import annotations

import argparse
import logging
import math
import os
import shutil
import socket
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from pymavlink.dialects.v20 import ardupilotmega as mavlink  # noqa: E402

from driver.sim import SimConfig, SimVehicle  # noqa: E402
from driver.sim import ftp as simftp  # noqa: E402
from driver.sim import logs as simlogs  # noqa: E402
from driver.sim.dataflash import LogFolder, write_flight_log  # noqa: E402
from driver.sim.faults import LinkFaults  # noqa: E402
from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402
import tables  # noqa: E402

BASELINE_SILENCE = 1.0       # s without LOG_DATA before the baseline starts the whole log again (MAVProxy-like)
CELL_LIMIT = 300.0           # s a cell may take before it counts as not finished


def floor_seconds(path: str, size: int, speedup: float) -> float:
    if path == "ftp":
        return math.ceil(size / simftp.CHUNK) * simftp.PACKET_INTERVAL / speedup
    rate = min(simlogs.LOG_DATA_RATE, simlogs.MAX_DATA_STEP * SimConfig.rate_hz)
    return math.ceil(size / simlogs.LOG_DATA_SIZE) / rate / speedup


def make_log(folder: str, megabytes: float) -> tuple[LogFolder, int]:
    logs = LogFolder(folder)
    return logs, write_flight_log(logs, int(megabytes * 1_000_000))


def driver_cell(logs: LogFolder, number: int, path: str, loss: float, speedup: float, out: str) -> dict:
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=speedup, ready_after=1.0, seed=7, log_dir=logs.folder)).start()
    v = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{sim.tcp_port}")).start()
    try:
        if not v.wait_for(lambda s: s.connected, 20):
            return {"ok": False, "why": "no heartbeat"}
        sim.faults.uplink = LinkFaults(loss=loss)
        sim.faults.downlink = LinkFaults(loss=loss)
        outcome = v.logs.download(number, out, via=path).result(CELL_LIMIT)
        same = outcome.ok and open(out, "rb").read() == open(logs.path(number), "rb").read()
        return {"ok": outcome.ok, "why": outcome.reason, "seconds": outcome.seconds, "identical": same,
                "rerequested": outcome.bytes_rerequested, "received": outcome.bytes_received}
    except TimeoutError:
        return {"ok": False, "why": f"not finished in {CELL_LIMIT:.0f} s"}
    finally:
        v.close()
        sim.stop()


def baseline_cell(logs: LogFolder, number: int, loss: float, speedup: float) -> dict:
    """MAVProxy-style: the whole log asked at once; after a silence with bytes missing, all of it again."""
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=speedup, ready_after=1.0, seed=7, log_dir=logs.folder)).start()
    sock = socket.create_connection(("127.0.0.1", sim.tcp_port))
    sock.settimeout(0.05)
    mav = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
    parser = mavlink.MAVLink(None)
    parser.robust_parsing = True
    own = open(logs.path(number), "rb").read()
    size = len(own)
    try:
        sim.faults.uplink = LinkFaults(loss=loss)
        sim.faults.downlink = LinkFaults(loss=loss)
        start = time.monotonic()
        restarts, received = 0, 0
        chunks: dict[int, bytes] = {}
        last = 0.0
        sock.sendall(mav.log_request_data_encode(1, 1, number, 0, 0xFFFFFFFF).pack(mav))
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
                sock.sendall(mav.log_request_data_encode(1, 1, number, 0, 0xFFFFFFFF).pack(mav))
                last = time.monotonic()
        return {"ok": False, "why": f"not finished in {CELL_LIMIT:.0f} s ({restarts} restarts)", "identical": False,
                "rerequested": restarts * size, "received": received}
    finally:
        sock.close()
        sim.stop()


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", default="2,20", help="MB, comma-separated")
    p.add_argument("--paths", default="log_data,ftp,baseline")
    p.add_argument("--loss", default="0,10,30", help="percent each way, comma-separated")
    p.add_argument("--speedup", type=float, default=1.0, help="the sim's speed-up for LOG_DATA and the baseline")
    p.add_argument("--ftp-speedup", type=float, default=20.0, help="the sim's speed-up for FTP (paced at 5.5 ms)")
    p.add_argument("--markdown", action="store_true")
    opts = p.parse_args()
    logging.basicConfig(level=logging.ERROR)
    head = ("log", "path", "loss", "time s", "floor s", "x floor", "re-asked held B", "received B", "identical",
            "note")
    rows = []
    work = tempfile.mkdtemp(prefix="bench-logs-")
    try:
        for mb in (float(x) for x in opts.sizes.split(",")):
            logs, number = make_log(os.path.join(work, f"{mb:g}MB"), mb)
            size = os.path.getsize(logs.path(number))
            for path in opts.paths.split(","):
                speedup = opts.ftp_speedup if path == "ftp" else opts.speedup
                for pct in (float(x) for x in opts.loss.split(",")):
                    out = os.path.join(work, f"got-{mb:g}-{path}-{pct:g}.BIN")
                    if path == "baseline":
                        r = baseline_cell(logs, number, pct / 100, speedup)
                    else:
                        r = driver_cell(logs, number, path, pct / 100, speedup, out)
                    floor = floor_seconds("ftp" if path == "ftp" else "log_data", size, speedup)
                    secs = r.get("seconds")
                    rows.append((f"{size / 1e6:.1f} MB", path, f"{pct:g} %",
                                 f"{secs:.2f}" if secs is not None and r["ok"] else "-", f"{floor:.2f}",
                                 f"{secs / floor:.1f}" if secs and r["ok"] else "-",
                                 str(r.get("rerequested", "-")), str(r.get("received", "-")),
                                 "yes" if r.get("identical") else "NO",
                                 ("" if r["ok"] else r["why"][:60]) + (f" (x{speedup:g} sim)" if speedup != 1 else "")
                                 if path != "baseline" else r["why"][:60]))
                    print("  ".join(rows[-1]), flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print()
    print("\n".join(tables.render(head, rows, opts.markdown)))


if __name__ == "__main__":
    main()
