"""The fault matrix: takeoff, forward, stop, land under every firmware profile and link fault.

    .venv/bin/python bench/fault_matrix.py [--speedup 2] [--profiles copter-4,solo] [--faults clean,loss30]
                                           [--markdown] [--rows flights,transfers,params,logs]

Each cell flies the simulated vehicle (real sockets, real time scaled by --speedup) with the embedded
driver: takeoff to 3 m, 2 m/s forward along the nose (at 60°) for 3 s (a stick refreshed every 100 ms, as the
viewer does), Stop, Land, until the vehicle has disarmed; a pilot told that Takeoff or Land failed presses it
once more. It prints, per cell, whether the flight completed, what the pilot was told (the final answers to
takeoff, stop and land), the time to each phase, how far the course flown was off the nose, and the *wrong
reports*: a command the driver reported accepted that the vehicle never carried out, or reported failed although
the vehicle did it. Every answer the driver gives is checked against the simulated vehicle's truth at the
moment the driver gives it. Target: no wrong report anywhere; every cell up to 30 % loss completes.

The driver of a flight runs on the vehicle's clock (the simulator's seconds, which the vehicle's own timers
read): its command retries (3 s), the deadman and the link's loss are then timed as against a real vehicle, at
any speed-up and however loaded the machine. On the real clock a 2x speed-up let the vehicle's 10 s DISARM_DELAY
pass in 5 real seconds, room for two NAV_TAKEOFF tries instead of three, and a loaded machine moved that again.

The transfer rows (bench/transfer_matrix.py) follow: a 50-item mission and a fence uploaded and downloaded in
each cell, each answer checked against what the vehicle holds; target 0 corrupted plans, 0 wrong reports.
The parameter row (bench/param_cells.py): per profile, read path (MAVLink FTP in the recorded ArduCopter 4.6.3
shape, and the list) and fault, every parameter downloaded and no wrong "set" report.
The log rows (bench/log_cells.py): per profile, download path (LOG_DATA; MAVLink FTP where the profile has it) and
fault, the vehicle's DataFlash log downloaded, byte-identical to the simulator's own file (or, not finished, a
resumable .part truthfully told).

Then the gate (bench/verdicts.py): every cell right, wrong or unfinished, the cells that are not right named, and
the exit code: 0 only when every cell is right (completed, or refused by the driver for what the firmware lacks,
as the Solo's fence), 1 on any wrong report or unfinished cell.
"""
from __future__ import annotations

import argparse
import logging
import math
import os
import sys
import threading
import time
from dataclasses import dataclass, field

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from driver.sim import SimConfig, SimVehicle  # noqa: E402
from driver.vehicle.state import CommandStatus, LandedState  # noqa: E402
from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402
import log_cells  # noqa: E402
import param_cells  # noqa: E402
import tables  # noqa: E402
import verdicts  # noqa: E402
from faults import FAULTS, PROFILES  # noqa: E402
from transfer_matrix import run_transfers, transfer_table, verdict as transfer_verdict  # noqa: E402

ALTITUDE = 3.0
FORWARD_SPEED = 2.0
FORWARD_SECONDS = 3.0        # sim seconds
HEADING = 60.0               # degrees: the nose points neither north nor east, so a frame mix-up shows


@dataclass
class Cell:
    profile: str
    fault: str
    completed: bool = False
    told: dict = field(default_factory=dict)            # takeoff / stop / land -> status
    times: dict = field(default_factory=dict)           # phase -> seconds from the start of the flight
    wrong: list = field(default_factory=list)           # wrong reports
    answers: int = 0
    moved: float = 0.0
    off_nose: float = 0.0                               # degrees between the nose and the course flown
    error: str = ""


class Judge:
    """Checks every answer the driver gives against the simulated vehicle's truth when it is given."""

    def __init__(self, vehicle: Vehicle, sim: SimVehicle, cell: Cell):
        self.vehicle, self.sim, self.cell = vehicle, sim, cell
        self._seen = 0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2)
        self.now()

    def now(self) -> None:
        """Judge every answer given so far, now: before the pilot acts on one (a second Takeoff or Land), so the
        truth it is judged against is not the next command's."""
        with self._lock:
            self._check()

    def _run(self) -> None:
        while not self._stop.is_set():
            self.vehicle.wait_for(lambda s: len(s.results) and s.results[-1].index > self._seen, 0.2)
            self.now()

    def _check(self) -> None:
        truth = self.sim.truth()
        for r in self.vehicle.state().results_since(self._seen):
            self._seen = r.index
            self.cell.answers += 1
            ok = r.status is CommandStatus.ACCEPTED
            failed = r.status in (CommandStatus.REFUSED, CommandStatus.TIMED_OUT)
            wrong = None
            if r.command.startswith("mode "):
                mode = r.command[5:]
                if ok and truth.mode != mode:
                    wrong = f"{r} but the vehicle is in {truth.mode}"
                elif failed and truth.mode == mode:
                    wrong = f"{r} but the vehicle is in {mode}"
            elif r.command == "arm":
                if ok and not truth.armed:
                    wrong = f"{r} but the vehicle is disarmed"
                elif failed and truth.armed:
                    wrong = f"{r} but the vehicle is armed"
            elif r.command == "takeoff":
                if ok and truth.altitude < 0.9 * ALTITUDE:
                    wrong = f"{r} but the vehicle is at {truth.altitude:.1f} m"
                elif failed and (truth.altitude > 1.0 or truth.landed_state != LandedState.ON_GROUND):
                    wrong = f"{r} but the vehicle is taking off ({truth.altitude:.1f} m)"
            elif r.command.startswith("NAV_TAKEOFF") and ok and truth.landed_state == LandedState.ON_GROUND \
                    and truth.altitude < 0.2 and not truth.armed:
                wrong = f"{r} but the vehicle is on the ground, disarmed"
            if wrong:
                self.cell.wrong.append(wrong)


def hold(vehicle: Vehicle, sim: SimVehicle, forward: float, sim_seconds: float, during=None) -> None:
    """A pilot holding the stick: a set_velocity every 100 ms of vehicle time until sim_seconds of it pass (the
    driver's deadman counts the vehicle's seconds too)."""
    end = sim.truth().time + sim_seconds
    half = sim.truth().time + sim_seconds / 2
    while sim.truth().time < end:
        vehicle.set_velocity(forward, 0.0, 0.0, 0.0)
        if during is not None and sim.truth().time >= half:
            during()
            during = None
        due = sim.truth().time + 0.1
        while sim.truth().time < due:
            time.sleep(0.005)


def vehicle_clock(sim: SimVehicle):
    """The simulated vehicle's own seconds as a clock for the driver (offset as a monotonic clock is, never near
    zero): the driver's timers then keep the vehicle's pace whatever the speed-up and the machine's load."""
    start = time.monotonic()
    return lambda: start + sim.truth().time


def fly(profile: str, fault: str, speedup: float) -> Cell:
    cell = Cell(profile, fault)
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=speedup, ready_after=2.0, seed=7, profile=profile,
                               mavlink2=profile != "solo", home=(40.2839, -3.7940, 664.0, HEADING)))
    sim.start()
    vehicle = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{sim.tcp_port}"), clock=vehicle_clock(sim)).start()
    judge = Judge(vehicle, sim, cell)
    t0 = time.monotonic()
    try:
        if not vehicle.wait_for(lambda s: s.connected and s.readiness.ready_to_arm, 60):
            cell.error = "never ready"
            return cell
        FAULTS[fault][1](sim.faults)
        t0 = time.monotonic()
        result = vehicle.takeoff(ALTITUDE).result(timeout=180)
        cell.told["takeoff"] = result.status.value
        if not result.ok:                   # a pilot presses Takeoff again (the vehicle may have disarmed)
            judge.now()
            result = vehicle.takeoff(ALTITUDE).result(timeout=180)
            cell.told["takeoff"] += f", again: {result.status.value}"
        cell.times["takeoff"] = time.monotonic() - t0
        if not result.ok:
            cell.error = str(result)
            return cell
        start = sim.truth()
        outage = (lambda: sim.faults.outage(1.0)) if fault == "outage" else None
        hold(vehicle, sim, FORWARD_SPEED, FORWARD_SECONDS, outage)
        result = vehicle.stop().result(timeout=30)
        cell.told["stop"] = result.status.value
        still = vehicle.wait_for(lambda s: sim.truth().ground_speed < 0.3, 60)
        end = sim.truth()
        cell.moved = math.hypot(end.north - start.north, end.east - start.east)
        course = math.atan2(end.east - start.east, end.north - start.north)
        cell.off_nose = abs(math.degrees(math.atan2(math.sin(course - start.yaw), math.cos(course - start.yaw))))
        cell.times["stopped"] = time.monotonic() - t0
        if still is None:
            cell.error = "did not stop"
        result = vehicle.land().result(timeout=60)
        cell.told["land"] = result.status.value
        if not result.ok:                   # a pilot presses Land again
            judge.now()
            result = vehicle.land().result(timeout=60)
            cell.told["land"] += f", again: {result.status.value}"
        landed = vehicle.wait_for(lambda s: not sim.truth().armed and sim.truth().altitude < 0.1, 120)
        cell.times["landed"] = time.monotonic() - t0
        if cell.off_nose > 20.0:
            cell.error = cell.error or f"flew {cell.off_nose:.0f}° off its nose"
        cell.completed = landed is not None and cell.moved > 2.0 and not cell.error
        if landed is None:
            cell.error = cell.error or "did not land"
    except Exception as exc:  # noqa: BLE001 - a cell that crashes is reported, not fatal to the table
        cell.error = f"{type(exc).__name__}: {exc}"
    finally:
        judge.close()
        vehicle.close()
        sim.stop()
    return cell


def table(cells: list[Cell], speedup: float, markdown: bool) -> str:
    head = ("profile", "fault", "completed", "takeoff / stop / land told", "takeoff s", "stopped s", "landed s",
            "moved m", "off nose °", "answers", "wrong reports")
    rows = []
    for c in cells:
        told = " / ".join(c.told.get(k, "-") for k in ("takeoff", "stop", "land"))
        times = [f"{c.times[k]:.1f}" if k in c.times else "-" for k in ("takeoff", "stopped", "landed")]
        rows.append((c.profile, c.fault, "yes" if c.completed else f"NO ({c.error})", told, *times,
                     f"{c.moved:.1f}", f"{c.off_nose:.0f}", str(c.answers), str(len(c.wrong))))
    out = tables.render(head, rows, markdown)
    out.append(f"(times in real seconds at sim speed-up {speedup:g}; faults: "
               + "; ".join(f"{k} = {v[0]}" for k, v in FAULTS.items()) + ")")
    for c in cells:
        for w in c.wrong:
            out.append(f"WRONG {c.profile}/{c.fault}: {w}")
    return "\n".join(out)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speedup", type=float, default=2.0)
    ap.add_argument("--profiles", default=",".join(PROFILES))
    ap.add_argument("--faults", default=",".join(FAULTS))
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--rows", default="flights,transfers,params,logs",
                    help="flights (takeoff, forward, stop, land), transfers (bench/transfer_matrix.py), params "
                         "(bench/param_cells.py) and/or logs (bench/log_cells.py)")
    tables.add_write_docs(ap)
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)        # the table says what happened
    rows = args.rows.split(",")
    cells = []
    for profile in args.profiles.split(",") if "flights" in rows else ():
        for fault in args.faults.split(","):
            cell = fly(profile, fault, args.speedup)
            print(f"{profile:9s} {fault:11s} {'ok' if cell.completed else 'FAILED ' + cell.error} "
                  f"wrong={len(cell.wrong)}", file=sys.stderr, flush=True)
            cells.append(cell)
    if cells:
        print(table(cells, args.speedup, args.markdown))
    transfers = run_transfers(args.profiles.split(","), args.faults.split(","), args.speedup, FAULTS) \
        if "transfers" in rows else []
    if transfers:
        print(transfer_table(transfers, args.speedup, args.markdown))
    checks = []
    for profile in args.profiles.split(",") if "params" in rows else ():
        for method in param_cells.methods(profile):
            for fault in args.faults.split(","):
                checks.append(param_cells.check(profile, fault, args.speedup, FAULTS[fault][1], method))
                print(f"{profile:9s} {fault:11s} parameters over {method}: {checks[-1].downloaded}/"
                      f"{checks[-1].expected} ({checks[-1].used}) wrong={len(checks[-1].wrong)}", file=sys.stderr,
                      flush=True)
    if checks:
        head, lines = param_cells.rows(checks)
        print("\nParameters:")
        print("\n".join(tables.render(head, lines, args.markdown)))
        for c in checks:
            for w in c.wrong:
                print(f"WRONG parameters {c.profile}/{c.fault}: {w}")
    logs = run_logs(args.profiles.split(","), args.faults.split(","), args.speedup, args.markdown) \
        if "logs" in rows else []
    return gate(cells, transfers, checks, logs)


def gate(flights, transfers, checks, logs) -> int:
    """Each cell's verdict (bench/verdicts.py), printed after the tables with the cells that are not right; the exit
    code: 0 only when every cell is right."""
    return verdicts.report([verdicts.flight(c) for c in flights] + [transfer_verdict(c) for c in transfers]
                           + [verdicts.parameters(c) for c in checks] + [verdicts.log(c) for c in logs])


def run_logs(profiles, faults, speedup: float, markdown: bool) -> list:
    """The log rows (bench/log_cells.py), printed as a table; the cells."""
    import shutil
    import tempfile
    folder = log_cells.make_log(tempfile.mkdtemp(prefix="fault-matrix-logs-"))
    cells = []
    try:
        for profile in profiles:
            for path in log_cells.paths(profile):
                for fault in faults:
                    cells.append(log_cells.check(profile, fault, path, speedup, FAULTS[fault][1], folder))
                    c = cells[-1]
                    print(f"{profile:9s} {fault:11s} log over {path}: {c.error or c.told} identical={c.identical} "
                          f"wrong={len(c.wrong)}", file=sys.stderr, flush=True)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    if cells:
        head, lines = log_cells.rows(cells)
        print(f"\nLogs (a {cells[0].size:,}-byte DataFlash log; real seconds at sim speed-up {speedup:g}):")
        print("\n".join(tables.render(head, lines, markdown)))
        for c in cells:
            for w in c.wrong:
                print(f"WRONG log {c.profile}/{c.fault}/{c.path}: {w}")
    return cells


if __name__ == "__main__":
    with tables.publishing(tables.variant("fault_matrix", "--rows", "--profiles", "--faults")):
        sys.exit(main())
