"""The velocity stream as the vehicle receives it: rate, jitter, and the deadman's reaction.

    .venv/bin/python bench/bench_setpoints.py [--seconds 5] [--write-docs]

Flies the simulated vehicle (real time, TCP) with the embedded driver, holds a stick the way the viewer
does (a set_velocity call every 100 ms), and reads the SET_POSITION_TARGET_LOCAL_NED arrival times the
simulated autopilot recorded. Then the stick calls stop, as when the UI stalls, and it measures how long
until a zero setpoint reaches the vehicle (the deadman is configured at 0.5 s).
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from driver.sim import SimConfig, SimVehicle  # noqa: E402
from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402
import tables  # noqa: E402  (bench/tables.py: this script runs from bench/)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=5.0)
    tables.add_write_docs(ap)
    args = ap.parse_args()
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=1.0, ready_after=1.0, rate_hz=1000))
    sim.start()
    drone = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{sim.tcp_port}")).start()
    try:
        result = drone.takeoff(3.0).result(timeout=60)
        assert result.ok, result
        start = len(sim.received_setpoints)
        end = time.monotonic() + args.seconds
        while True:
            drone.set_velocity(1.0, 0.0, 0.0, 0.0)
            last_call = sim.truth().time
            if time.monotonic() >= end:
                break
            time.sleep(0.1)                                       # the viewer's 10 Hz refresh of a held stick
        deadline = time.monotonic() + 3.0
        while time.monotonic() < deadline and not any(
                r[3] == 0.0 and r[0] > last_call for r in list(sim.received_setpoints)[start:]):
            time.sleep(0.005)
        got = list(sim.received_setpoints)[start:]
        moving = [r[0] for r in got if r[3] == 1.0]
        zero = next((r[0] for r in got if r[3] == 0.0 and r[0] > last_call), None)
        gaps = [b - a for a, b in zip(moving, moving[1:])]
        rate = (len(moving) - 1) / (moving[-1] - moving[0])
        print(f"setpoints while holding a stick: {len(moving)} in {moving[-1] - moving[0]:.2f} s = {rate:.1f} Hz "
              f"(target 20 Hz)")
        print(f"interval at the vehicle: median {statistics.median(gaps) * 1e3:.1f} ms, "
              f"p95 {sorted(gaps)[int(0.95 * (len(gaps) - 1))] * 1e3:.1f} ms, max {max(gaps) * 1e3:.1f} ms")
        if zero is None:
            print("deadman: NO zero setpoint within 3 s")
        else:
            print(f"deadman: zero setpoint at the vehicle {zero - last_call:.3f} s after the last stick call "
                  f"(configured 0.5 s + at most one 50 ms tick)")
    finally:
        drone.land()
        drone.close()
        sim.stop()


if __name__ == "__main__":
    with tables.publishing("setpoints"):
        main()
