"""Time to the complete parameter list: clean and at 10 % and 30 % loss each way, against the link's floor.

    .venv/bin/python bench/bench_params.py [--links tcp,radio] [--losses 0,0.1,0.3] [--methods list,ftp]
                                           [--runs 1] [--markdown] [--write-docs]

Each cell starts the simulated ArduCopter (real time; its 1,392 parameters of ArduCopter 4.6.3) and the
embedded driver, sets the loss on both directions, calls ``fetch_parameters(refresh=True)`` and times it to the
vehicle's last parameter in ``state().parameters``; every value is then checked against the vehicle's own.

Links: ``tcp`` streams the list as fast as the recording's TCP did (2,300 a second); ``radio`` is a 57,600 baud
telemetry radio (SiK's default), which ArduPilot's queued_param_send keeps the list within (the sim models
that: ``SimConfig.radio_baud``). The floor is what the link's bandwidth allows for the list alone: 1,392
PARAM_VALUE frames of 37 bytes (MAVLink 2), and at a loss p each way every frame is needed 1/(1 - p) times on
average (a lost frame is asked again, and a lost request too; the floor counts the frames only). FTP's floor is
the file's 64 frames of 266 bytes, the same way, but never below the burst's own pace (ArduPilot's: 5.5 ms a packet
over TCP, a third of a radio's bandwidth), which no loss lengthens: lost packets are read again unpaced.

Methods: ``list`` is PARAM_REQUEST_LIST and re-asks by index; ``ftp`` reads ``@PARAM/param.pck`` over MAVLink FTP
(driver/params/ftp.py: 15,258 bytes in 64 packets for the same table), falling back to the list if FTP fails.
"""
from __future__ import annotations

import argparse
import logging
import os
import re
import statistics
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from driver.sim import SimConfig, SimVehicle  # noqa: E402
from driver.sim.ftp import BURST_SHARE, CHUNK, PACKET_INTERVAL, pack, sim_entries  # noqa: E402
from driver.sim.params import FTP_FRAME_BYTES, PARAM_VALUE_BYTES, RECORDED_RATE  # noqa: E402
from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402
import tables  # noqa: E402  (bench/tables.py: this script runs from bench/)

LINKS = {"tcp": None, "radio": 57600}


def floor(link: str, count: int, loss: float, pck_bytes: int | None = None) -> float:
    """Seconds the link's bandwidth needs for the list's frames (or, with ``pck_bytes``, the FTP file's, whose burst
    ArduPilot's FTP worker paces: one packet every PACKET_INTERVAL, and on a radio a third of its bandwidth; the
    packets a loss takes are read again unpaced, so that part does not grow with the loss)."""
    baud = LINKS[link]
    rate = RECORDED_RATE * PARAM_VALUE_BYTES if baud is None else min(RECORDED_RATE * PARAM_VALUE_BYTES, baud / 10.0)
    frames = count * PARAM_VALUE_BYTES if pck_bytes is None else -(-pck_bytes // CHUNK) * FTP_FRAME_BYTES
    interval = PACKET_INTERVAL if baud is None else max(PACKET_INTERVAL, BURST_SHARE * FTP_FRAME_BYTES / rate)
    paced = 0.0 if pck_bytes is None else -(-pck_bytes // CHUNK) * interval
    return max(frames / rate / (1.0 - loss), paced)


def run(link: str, loss: float, seed: int, method: str) -> dict:
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=1.0, ready_after=1.0, seed=seed, radio_baud=LINKS[link]))
    sim.start()
    vehicle = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{sim.tcp_port}", param_cache=None,
                                    param_ftp=method == "ftp")).start()
    try:
        if not vehicle.wait_for(lambda s: s.connected and s.firmware, 20):     # AUTOPILOT_VERSION: FTP offered
            raise RuntimeError("no heartbeat")
        sim.faults.uplink.loss = sim.faults.downlink.loss = loss
        frames_before = sim.faults.counters.downlink.frames
        start = time.monotonic()
        result = vehicle.fetch_parameters(refresh=True).result(timeout=600)
        seconds = time.monotonic() - start
        table = vehicle.state().parameters
        params = sim.autopilot.params
        wrong = [n for n in params.names if table.get(n) is None or (
            not n.startswith("SR0_") and abs(table.get(n).value - params[n]) > 1e-6 * max(1.0, abs(params[n])))]
        reads = re.search(r"\((\d+) asked again", result.reason)
        return dict(ok=result.ok and table.complete and not wrong, seconds=seconds, count=len(params),
                    pck=len(pack(sim_entries(params), CHUNK)),
                    reads=int(reads.group(1)) if reads else 0, wrong=len(wrong), reason=result.reason,
                    frames=sim.faults.counters.downlink.frames - frames_before)
    finally:
        vehicle.close()
        sim.stop()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--links", default="tcp,radio")
    ap.add_argument("--losses", default="0,0.1,0.3")
    ap.add_argument("--methods", default="list,ftp")
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--markdown", action="store_true")
    tables.add_write_docs(ap)
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    os.environ.setdefault("XDG_CACHE_HOME", tempfile.mkdtemp(prefix="bench-params-"))
    head = ("link", "method", "loss each way", "complete", "time s", "floor s", "time / floor", "re-asked by index",
            "frames down", "wrong values")
    rows = []
    ok = True
    for link, method, loss in [(k, m, float(x)) for k in args.links.split(",") for m in args.methods.split(",")
                               for x in args.losses.split(",")]:
        cells = [run(link, loss, seed, method) for seed in range(1, args.runs + 1)]
        seconds = statistics.median(c["seconds"] for c in cells)
        done = all(c["ok"] for c in cells)
        ok &= done
        used = "ftp" if all("over MAVLink FTP" in c["reason"] for c in cells) else "list" if method == "list" else "ftp→list"
        low = floor(link, cells[0]["count"], loss, cells[0]["pck"] if used == "ftp" else None)
        rows.append((link, used, f"{loss:.0%}", "yes" if done else f"NO ({cells[0]['reason']})", f"{seconds:.2f}",
                     f"{low:.2f}", f"{seconds / low:.2f}", str(round(statistics.median(c['reads'] for c in cells))),
                     str(round(statistics.median(c['frames'] for c in cells))), str(max(c["wrong"] for c in cells))))
        print(" ".join(rows[-1]), file=sys.stderr, flush=True)
    print("\n".join(tables.render(head, rows, args.markdown)))
    print(f"(real time; median of {args.runs} run(s); tcp = the recording's 2,300 PARAM_VALUE/s, radio = 57,600 baud; "
          "frames down: every frame the vehicle sent meanwhile, telemetry included)")
    return 0 if ok else 1


if __name__ == "__main__":
    with tables.publishing("params"):
        sys.exit(main())
