#!/usr/bin/env python3
"""Setup figures on the simulated ArduCopter at its real pace (speedup 1): the time from Start to the vehicle's
verdict for each calibration, and how soon the motor test's first output change reaches the driver.

    python bench/bench_setup.py [--repeat 10] [--speedup 1] [--write-docs]

Calibrations: gyro, barometer, level (one COMMAND_LONG each, the verdict is the final COMMAND_ACK), the six-position
accelerometer calibration on the calibration model (each position confirmed as soon as it is asked), the onboard
compass calibration on the calibration model (start to the last MAG_CAL_REPORT). Motor test: from the call of
``motor_test()`` to the first VehicleState whose SERVO_OUTPUT_RAW shows the tested output changed (the outputs
streamed at 25 Hz while a motor test runs, as the setup asks for them); the target is 200 ms.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from driver.setup.model import AccelStep  # noqa: E402
from driver.sim import SimConfig, SimVehicle  # noqa: E402
from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402
import tables  # noqa: E402  (bench/tables.py: this script runs from bench/)

T = 120.0


def timed(call) -> tuple[float, object]:
    start = time.monotonic()
    result = call()
    return time.monotonic() - start, result


def accel(vehicle) -> object:
    cal = vehicle.setup.accel_calibration()
    asked: list[int] = []
    while not cal.verdict.done():
        state = vehicle.wait_for(lambda s: cal.verdict.done() or (s.setup.accel.step is AccelStep.WAITING
                                                                  and s.setup.accel.position not in asked), T)
        if state is None or cal.verdict.done():
            break
        asked.append(state.setup.accel.position)
        cal.confirm_position()
    return cal.verdict.result(T)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=10, help="motor tests to time")
    parser.add_argument("--speedup", type=float, default=1.0)
    tables.add_write_docs(parser)
    args = parser.parse_args()
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=args.speedup, ready_after=5.0, seed=1,
                               calibration_model=True)).start()
    vehicle = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{sim.tcp_port}", tlog_path=None)).start()
    try:
        if vehicle.wait_for(lambda s: s.connected and s.readiness.prearm_ok, 60) is None:
            print("the simulated vehicle did not become ready")
            return 1
        print(f"calibrations on the simulator (speedup {args.speedup:g}): Start to the vehicle's verdict")
        setup = vehicle.setup
        for name, call in (("gyro", lambda: setup.calibrate_gyro().result(T)),
                           ("barometer", lambda: setup.calibrate_baro().result(T)),
                           ("level", lambda: setup.calibrate_level().result(T)),
                           ("accelerometer (6 positions)", lambda: accel(vehicle)),
                           ("compass (tumbled)", lambda: setup.compass_calibration().finished.result(T))):
            seconds, result = timed(call)
            print(f"  {name:<28} {seconds:7.2f} s   {result}")
        setup.accept_compass().result(T)
        setup.watch_radio()
        vehicle.wait_for(lambda s: s.setup.outputs.values, 10)
        latencies = []
        for i in range(args.repeat):
            vehicle.wait_for(lambda s: not s.armed and s.setup.outputs.values[:4] == (1000,) * 4, 30)
            start = time.monotonic()
            setup.motor_test(1, throttle_pct=20, seconds=0.5, propellers_removed=True)
            state = vehicle.wait_for(lambda s: 1200 in s.setup.outputs.values[:4], 10)
            if state is None:
                print("  motor test: no output change seen")
                return 1
            latencies.append((time.monotonic() - start) * 1000.0)
            setup.stop_motor_test().result(T)
        latencies.sort()
        worst = latencies[-1]
        print(f"motor test, command to first output change ({len(latencies)} runs): median "
              f"{statistics.median(latencies):.0f} ms, worst {worst:.0f} ms (target <= 200 ms): "
              f"{'OK' if worst <= 200 else 'OVER'}")
        return 0 if worst <= 200 else 2
    finally:
        vehicle.close()
        sim.stop()


if __name__ == "__main__":
    with tables.publishing("setup"):
        sys.exit(main())
