"""Telemetry ingest: messages/s the driver turns into state, beside raw pymavlink parsing of the same bytes.

    .venv/bin/python bench/bench_ingest.py [--messages 60000] [--chunks frame,64,512,4096] [--repeat 15]
                                           [--write-docs]

The byte stream is a realistic ArduCopter telemetry mix (the messages and relative rates a ground station
requests), MAVLink 2, fed as the link delivers it: one frame per read (UDP datagrams, as from the Solo), or
chunks of N bytes (TCP/serial reads; the simulator over TCP gives a median of about 50 bytes per read).

Raw: pymavlink's ``parse_buffer`` on each read, nothing else. Driver: ``Vehicle.ingest`` on each read, the reader
thread's whole work (parse with the same pymavlink codec, count sequence gaps, keep the newest of each kind for the
inspector, dispatch events, fold the telemetry into the state and publish it at most at 100 Hz). The two take
turns, ``--repeat`` pairs, timed in this process's CPU time (``time.process_time``), so other jobs on a shared
machine do not count. Printed per read size: each side's messages a second from its best run, their ratio, and the
median of the pairs' ratios. The project's target is 0.8 of raw parse speed.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from pymavlink.dialects.v20 import ardupilotmega as mavlink  # noqa: E402

from driver.link.transport import frame_length  # noqa: E402
from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402
import tables  # noqa: E402  (bench/tables.py: this script runs from bench/)


def telemetry(n: int) -> bytes:
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    # one "second" of a 4 Hz stream set with 10 Hz attitude/VFR_HUD, as requested by the driver
    cycle = (
        [mavlink.MAVLink_heartbeat_message(2, 3, 217, 4, 4, 3)]
        + [mavlink.MAVLink_attitude_message(i, 0.01 * i, -0.02, 1.0 + 0.01 * i, 0.001, 0.002, 0.003) for i in range(10)]
        + [mavlink.MAVLink_vfr_hud_message(1.2, 1.3, 57, 40, 3.1, 0.2) for _ in range(10)]
        + [mavlink.MAVLink_global_position_int_message(i, 402839000 + i, -37940000 - i, 667000, 3000, 100, 50, -20, 5700) for i in range(4)]
        + [mavlink.MAVLink_local_position_ned_message(i, 1.0, 2.0, -3.0, 1.0, 0.5, -0.2) for i in range(4)]
        + [mavlink.MAVLink_sys_status_message(0x1FFFFFFF, 0x1FFFFFFF, 0x1FFFFFFF, 300, 16200, 1500, 87, 0, 0, 0, 0, 0, 0) for _ in range(4)]
        + [mavlink.MAVLink_gps_raw_int_message(0, 3, 402839000, -37940000, 667000, 90, 120, 150, 5700, 11) for _ in range(4)]
        + [mavlink.MAVLink_extended_sys_state_message(0, 2) for _ in range(4)]
        + [mavlink.MAVLink_ekf_status_report_message(0x3FF, 0.1, 0.1, 0.1, 0.1, 0.1) for _ in range(2)]
        + [mavlink.MAVLink_scaled_pressure_message(0, 1013.2, 0.1, 2100) for _ in range(2)]
        + [mavlink.MAVLink_raw_imu_message(0, 10, -5, -1000, 1, 2, 3, 200, 30, -400) for _ in range(2)]
        + [mavlink.MAVLink_wind_message(270, 3.5, 0.0) for _ in range(2)]
        + [mavlink.MAVLink_battery_status_message(0, 0, 0, 2100, [16200] + [65535] * 9, 1500, -1, -1, 87)]
        + [mavlink.MAVLink_home_position_message(402839000, -37940000, 664000, 0, 0, 0, [1, 0, 0, 0], 0, 0, 0)]
    )
    out = bytearray()
    count = 0
    while count < n:
        for msg in cycle:
            out += msg.pack(mav)
            mav.seq = (mav.seq + 1) % 256
            count += 1
    return bytes(out), count


def chunks(data: bytes, size: str):
    if size == "frame":
        out, i = [], 0
        while i < len(data):
            n = frame_length(data, i)
            out.append(data[i:i + n])
            i += n
        return out
    n = int(size)
    return [data[i:i + n] for i in range(0, len(data), n)]


def raw_parse(parts) -> int:
    codec = mavlink.MAVLink(None)
    codec.robust_parsing = True
    parse, n = codec.parse_buffer, 0
    for part in parts:
        n += len(parse(part) or ())
    return n


def driver_ingest(parts) -> int:
    vehicle = Vehicle(VehicleConfig(connection="udpin:127.0.0.1:0"))   # never started: no socket, no threads
    ingest, n = vehicle.ingest, 0
    for part in parts:                                # the same loop as raw_parse: only the driver differs
        n += ingest(part)
    state = vehicle.state()
    assert state.mode == "GUIDED" and state.position is not None and state.local is not None, state
    return n


def paired(parts, repeat: int) -> tuple[float, int, float, int, float]:
    """Raw parse and driver ingest run alternately, so both see the same machine (a shared machine's
    neighbours come and go): the best CPU time of each, and the median of the ratios of each pair."""
    raw_best = drv_best = float("inf")
    raw_n = drv_n = 0
    ratios = []
    for _ in range(repeat):
        t0 = time.process_time()
        raw_n = raw_parse(parts)
        t1 = time.process_time()
        drv_n = driver_ingest(parts)
        t2 = time.process_time()
        raw_best, drv_best = min(raw_best, t1 - t0), min(drv_best, t2 - t1)
        ratios.append((drv_n / (t2 - t1)) / (raw_n / (t1 - t0)))
    return raw_best, raw_n, drv_best, drv_n, statistics.median(ratios)


TARGET = 0.8


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--messages", type=int, default=60000)
    ap.add_argument("--chunks", default="frame,64,512,4096", help="reads to try: 'frame' or bytes per read")
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--markdown", action="store_true")
    tables.add_write_docs(ap)
    args = ap.parse_args()
    data, count = telemetry(args.messages)
    print(f"telemetry: {count} messages, {len(data)} bytes (MAVLink 2); raw parse and driver alternate, "
          f"{args.repeat} pairs, CPU time of this process")
    print()
    rows, met = [], 0
    for size in args.chunks.split(","):
        parts = chunks(data, size)
        raw_t, raw_n, drv_t, drv_n, median_ratio = paired(parts, args.repeat)
        ratio = (drv_n / drv_t) / (raw_n / raw_t)
        met += ratio >= TARGET
        rows.append(("1 frame" if size == "frame" else f"{size} B", f"{raw_n / raw_t:,.0f}", f"{drv_n / drv_t:,.0f}",
                     f"{ratio:.2f}", f"{median_ratio:.2f}", "met" if ratio >= TARGET else "NOT met"))
    print("\n".join(tables.render(("reads of", "raw parse msg/s", "driver msg/s", "driver / raw (bests)",
                                   "median of pair ratios", f"target {TARGET:.2f}"), rows, args.markdown)))
    print()
    print(f"The driver keeps {TARGET:.2f} of raw parse speed for {met} of {len(rows)} read sizes.")


if __name__ == "__main__":
    with tables.publishing("ingest"):
        main()
