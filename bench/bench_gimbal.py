#!/usr/bin/env python3
"""Gimbal figures against the simulated vehicle at real time (speedup 1): from Drone.point_gimbal to the
vehicle's ACK (the Future), and to the attitude the vehicle reports within 1° of the target (the state), for
the gimbal manager (copter-4) and the Solo's MOUNT_CONTROL; and a picture from take_photo to its confirmation.

    python bench/bench_gimbal.py [--rounds 10] [--write-docs]

The recording shows ArduCopter 4.6 reaching a commanded angle within 0.2 s (5 Hz reports); the simulator is
built to match, so the state figure is mostly the report interval.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
import tables  # bench/tables.py: this script runs from bench/

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)


def run(profile: str, rounds: int) -> None:
    from driver.sim import SimConfig, SimVehicle
    from driver.vehicle import Vehicle, VehicleConfig
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=1.0, ready_after=1.0, camera=True, profile=profile)).start()
    v = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{sim.tcp_port}")).start()
    try:
        v.wait_for(lambda s: s.connected and s.gimbal.known and s.camera.kind.value != "unknown", 20)
        acked, reached, photos = [], [], []
        for i in range(rounds):
            target = -80.0 if i % 2 else -10.0
            start = time.monotonic()
            result = v.point_gimbal(target).result(10)
            acked.append(time.monotonic() - start)
            ok = v.wait_for(lambda s: s.gimbal.pitch_deg is not None and abs(s.gimbal.pitch_deg - target) <= 1.0, 10)
            reached.append(time.monotonic() - start)
            assert result.ok and ok is not None, result
            start = time.monotonic()
            assert v.take_photo().result(10).ok
            photos.append(time.monotonic() - start)

        def ms(xs):
            return f"median {statistics.median(xs) * 1000:.0f} ms, max {max(xs) * 1000:.0f} ms"
        print(f"{profile:9s} point_gimbal -> answered: {ms(acked)}; -> reported within 1°: {ms(reached)}; "
              f"take_photo -> confirmed: {ms(photos)}  ({rounds} rounds, {v.state().gimbal.protocol})")
    finally:
        v.close()
        sim.stop()


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rounds", type=int, default=10)
    tables.add_write_docs(p)
    args = p.parse_args()
    for profile in ("copter-4", "solo"):
        run(profile, args.rounds)


if __name__ == "__main__":
    with tables.publishing("gimbal"):
        main()
