"""One DataFlash log downloaded by the driver from any vehicle, timed, and compared with a file if given: the
driver's side of the comparison with MAVProxy on ArduPilot's SITL in docs/flight-logs.md.

    .venv/bin/python bench/log_download_once.py tcp:127.0.0.1:5820 [--id 1] [--out FILE] [--compare SITL/logs/00000001.BIN]
                                                [--via auto|log_data|ftp] [--loss 0.3 [--seed 1]]

With ``--loss`` the driver reaches the vehicle's TCP port through bench/lossy_relay.py (frames lost each way with
that share, the driver on ``udpin``), as bench/real_sitl.py does.
"""
from __future__ import annotations

import argparse
import filecmp
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("connection")
    p.add_argument("--id", type=int, default=1, help="the log's id in the vehicle's list")
    p.add_argument("--out", default=os.path.join(tempfile.mkdtemp(), "log.BIN"))
    p.add_argument("--via", default="auto", choices=("auto", "log_data", "ftp"))
    p.add_argument("--compare", help="the vehicle's own file, to say byte-identical or not")
    p.add_argument("--loss", type=float, help="through a lossy relay: the share of frames lost each way")
    p.add_argument("--seed", type=int, default=1, help="the relay's random streams")
    args = p.parse_args()
    relay, connection = None, args.connection
    if args.loss is not None:
        from lossy_relay import LossyRelay, free_udp_port
        udp = free_udp_port()
        relay = LossyRelay(int(args.connection.rsplit(":", 1)[1]), udp, args.loss, args.seed)
        connection = f"udpin:127.0.0.1:{udp}"
    v = Vehicle(VehicleConfig(connection=connection, tlog_path=None)).start()
    try:
        if v.wait_for(lambda s: s.connected, 60) is None:
            raise SystemExit("no heartbeat in 60 s")
        listed = v.logs.list().result(60)
        print("list:", listed.reason or "ok", [(e.id, e.size) for e in listed.entries])
        t0 = time.monotonic()
        out = v.logs.download(args.id, args.out, via=args.via).result(600)
        seconds = time.monotonic() - t0
        print(f"{'saved' if out.ok else 'failed'}: {out.reason}")
        if out.ok:
            print(f"{out.size:,} bytes in {seconds:.2f} s ({out.size / seconds / 1000:,.0f} kB/s), "
                  f"{out.bytes_received:,} received, {out.bytes_rerequested:,} held bytes asked again")
        if args.compare and out.ok:
            print("byte-identical:", filecmp.cmp(args.out, args.compare, shallow=False))
    finally:
        v.close()
        if relay is not None:
            relay.close()


if __name__ == "__main__":
    main()
