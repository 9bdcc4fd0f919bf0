"""The Setup procedures against ArduCopter's own firmware (issue 32): a real SITL on ArduPilot's ``calibration``
model, whose airframe is turned by servo outputs 5-8 (SIM_Calibration.cpp), the way the calib recording was made.

    .venv/bin/python bench/real_sitl_setup.py --sitl PATH/TO/arducopter [--instance 4] [--write-docs]
    .venv/bin/python bench/real_sitl_setup.py --connect --instance N    # a SITL already running, calibration model

The driver (``Vehicle`` on SERIAL0, through the same ``vehicle.setup`` API the Setup pages use) runs: gyro, barometer
and level calibration; the six-position accelerometer calibration, where the bench plays the pilot: at each position
the vehicle asks for, it turns the airframe on SERIAL1 (DO_SET_SERVO, plain pymavlink) and then confirms; the
compass calibration with the airframe tumbling (servo 5 at 1250: SIM_Calibration's poses), then Accept; a motor
test. Each row gives what the driver said, the vehicle's own verdict (its texts) and the seconds. Nothing here is
a test: CI cannot build the SITL.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from pymavlink.dialects.v20 import ardupilotmega as mavlink  # noqa: E402

from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402
from real_sitl import SHIM, Sitl  # noqa: E402
from sitl_judge import Judge  # noqa: E402
import tables  # noqa: E402

# the airframe's pose for each position ArduPilot asks (ACCELCAL_VEHICLE_POS 1..6): servo 6 roll, servo 7 pitch
# (1000..2000 = -180..180 degrees), as the calib recording turned it
POSES = {1: (1500, 1500), 2: (1250, 1500), 3: (1750, 1500), 4: (1500, 1250), 5: (1500, 1750), 6: (2000, 1500)}
SETTLE = 4.0                    # s the airframe is given to reach a pose before the position is confirmed


class Airframe:
    """SERIAL1 (the judge's loss-free link): turns the calibration model's airframe with DO_SET_SERVO 5..8."""

    def __init__(self, port: int) -> None:
        self.judge = Judge(port)

    def servo(self, number: int, pwm: int) -> None:
        if self.judge.command(mavlink.MAV_CMD_DO_SET_SERVO, number, pwm) is None:
            raise RuntimeError(f"DO_SET_SERVO {number} {pwm} not acknowledged")

    def pose(self, roll_pwm: int, pitch_pwm: int) -> None:
        self.servo(5, 1150)             # attitude control
        self.servo(6, roll_pwm)
        self.servo(7, pitch_pwm)
        self.servo(8, 1500)

    def tumble(self) -> None:
        self.servo(5, 1250)             # SIM_Calibration's calibration poses, over and over


def texts_since(vehicle, since: float) -> str:
    return "; ".join(m.text for m in vehicle.state().messages if m.time >= since)[-300:]


def row(name: str, said: str, verdict: str, seconds: float) -> None:
    print(f"| {name} | {said} | {verdict} | {seconds:.1f} |", flush=True)


def run(port0: int, port1: int) -> None:
    v = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{port0}")).start()
    air = Airframe(port1)
    try:
        if v.wait_for(lambda s: s.connected and s.readiness.gps_ok, 120) is None:
            raise SystemExit("the vehicle never got a GPS fix")
        print("| procedure | driver said | the vehicle's texts | s |\n|---|---|---|---|")
        for name, call in (("gyro", v.setup.calibrate_gyro), ("barometer", v.setup.calibrate_baro),
                           ("level", v.setup.calibrate_level)):
            t0, wall = time.monotonic(), time.time()
            r = call().result(60)
            row(name, f"{r.status.value}: {r.reason}", texts_since(v, wall), time.monotonic() - t0)

        t0, wall = time.monotonic(), time.time()
        cal = v.setup.accel_calibration()
        asked: list[int] = []
        while not cal.verdict.done() and time.monotonic() - t0 < 180:
            pos = cal.position
            if pos is not None and (not asked or asked[-1] != pos):
                asked.append(pos)
                air.pose(*POSES[pos])
                time.sleep(SETTLE)
                cal.confirm_position().result(20)
            time.sleep(0.2)
        r = cal.verdict.result(30)
        row("accelerometer (6 positions)", f"{r.status.value}: {r.reason} (asked {asked})", texts_since(v, wall),
            time.monotonic() - t0)

        air.pose(1500, 1500)
        time.sleep(SETTLE)
        t0, wall = time.monotonic(), time.time()
        air.tumble()
        mag = v.setup.compass_calibration()
        mag.started.result(20)
        compasses = None
        while time.monotonic() - t0 < 240:
            c = v.state().setup.compass
            compasses = compasses or {p.compass for p in c.progress} or None
            if compasses and {r.compass for r in c.reports} >= compasses:
                break
            time.sleep(0.5)
        c = v.state().setup.compass
        fits = ", ".join(f"compass {r.compass}: {'ok' if r.ok else f'status {r.status}'} fitness {r.fitness:.2f}"
                         for r in c.reports) or "no report"
        accepted = mag.accept().result(20) if c.reports and all(r.ok for r in c.reports) else None
        air.pose(1500, 1500)
        row("compass (tumbled)", f"{fits}; accept: {accepted.status.value if accepted else 'not offered'}",
            texts_since(v, wall), time.monotonic() - t0)

        t0, wall = time.monotonic(), time.time()
        r = v.setup.motor_test(1, throttle_pct=10, seconds=2, propellers_removed=True).result(20)
        seen = v.wait_for(lambda s: any(x > 1100 for x in s.setup.outputs.values), 5) is not None
        row("motor test 1 at 10 %", f"{r.status.value}: {r.reason}; output moved: {seen}", texts_since(v, wall),
            time.monotonic() - t0)
    finally:
        v.close()
        air.judge.close()


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--sitl", help="the arducopter binary (started here on the calibration model, wiped)")
    p.add_argument("--connect", action="store_true", help="use a SITL already running for --instance")
    p.add_argument("--instance", type=int, default=4)
    tables.add_write_docs(p)
    args = p.parse_args()
    port0, port1 = 5760 + 10 * args.instance, 5762 + 10 * args.instance
    sitl = None
    if not args.connect:
        if not args.sitl:
            p.error("--sitl PATH or --connect")
        sitl = Sitl(args.sitl, args.instance, tempfile.mkdtemp(prefix="real-sitl-setup-"), SHIM, None,
                    model="calibration")
        sitl.start()
    try:
        run(port0, port1)
    finally:
        if sitl is not None:
            sitl.stop()


if __name__ == "__main__":
    with tables.publishing("real_sitl_setup"):
        main()
