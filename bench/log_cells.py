"""The fault matrix's log rows: the vehicle's DataFlash log downloaded under each fault (issue 31).

One cell per firmware profile, path and fault of bench/fault_matrix.py: the simulator holds a flight log
(dataflash.write_flight_log, :data:`LOG_BYTES`) in its log folder, and the embedded driver downloads it with
``vehicle.logs.download(1, FILE, via=path)``: ``log_data`` (LOG_REQUEST_DATA, both profiles) or ``ftp``
(logs/00000001.BIN by MAVLink FTP; the Solo's 3.3 has no FTP, so its rows are LOG_DATA only). The outage fault
cuts the link both ways for 1 s once a third of the log is held.

The verdict is the driver's word against the simulator's own file:

* told saved: right only when FILE is byte-identical to the simulator's log;
* told not finished: right only when the reason says the download can be resumed, the .part is there, and every
  byte its map (FILE.part.json) names is the simulator's (what the next download would resume from). Such a
  cell is right but not completed.

Anything else is a wrong report. Target: every cell completed and byte-identical, 0 wrong reports.
"""
from __future__ import annotations

import os
import shutil
import tempfile
import time
from dataclasses import dataclass, field

from driver.logs.ranges import load_part_map
from driver.sim import SimConfig, SimVehicle
from driver.sim.dataflash import LogFolder, write_flight_log
from driver.vehicle import Vehicle, VehicleConfig

LOG_BYTES = 300_000
CELL_LIMIT = 300.0            # s a download may take before the cell counts as not finished


@dataclass
class LogCell:
    profile: str
    fault: str
    path: str
    told: str = ""
    seconds: float = 0.0
    size: int = 0
    received: int = 0
    identical: bool = False
    kept: int = 0                                   # bytes of a resumable .part when the driver did not finish
    wrong: list = field(default_factory=list)
    error: str = ""

    @property
    def completed(self) -> bool:
        return not self.error and self.identical


def paths(profile: str) -> tuple[str, ...]:
    """The download paths a profile offers: LOG_DATA everywhere, MAVLink FTP where the firmware has it."""
    return ("log_data", "ftp") if profile != "solo" else ("log_data",)


def make_log(folder: str) -> str:
    """The simulator's log folder with one flight log in it; returns the folder."""
    logs = LogFolder(folder)
    write_flight_log(logs, LOG_BYTES)
    return folder


def judge(cell: LogCell, outcome, out: str, own: bytes) -> None:
    """The verdict on one download: FILE (told saved) or FILE.part (told not finished) against ``own``, the
    vehicle's bytes."""
    if outcome.ok:
        got = open(out, "rb").read() if os.path.exists(out) else None
        cell.identical = got == own
        if not cell.identical:
            cell.wrong.append(f"told saved, but the file is {'missing' if got is None else f'{len(got)} bytes'} "
                              f"and not the vehicle's {len(own)} bytes")
        return
    part = load_part_map(out)
    if part is None or not os.path.exists(out + ".part"):
        cell.wrong.append(f"told '{outcome.reason}' but no resumable .part is left")
        return
    with open(out + ".part", "rb") as f:
        for a, b in part.ranges.spans:
            f.seek(a)
            if f.read(b - a) != own[a:b]:
                cell.wrong.append(f"the .part's bytes {a}..{b} are not the vehicle's")
                return
    cell.kept = part.ranges.total()
    if "resum" not in outcome.reason:
        cell.wrong.append(f"told '{outcome.reason}' without saying the download can be resumed")


def check(profile: str, fault: str, path: str, speedup: float, apply_fault, log_dir: str) -> LogCell:
    cell = LogCell(profile, fault, path)
    own = open(os.path.join(log_dir, "00000001.BIN"), "rb").read()
    cell.size = len(own)
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=speedup, ready_after=2.0, seed=7, profile=profile,
                               mavlink2=profile != "solo", log_dir=log_dir))
    sim.start()
    vehicle = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{sim.tcp_port}")).start()
    scratch = tempfile.mkdtemp(prefix="log-cell-")
    out = os.path.join(scratch, "got.BIN")
    try:
        if not vehicle.wait_for(lambda s: s.connected and s.firmware, 60):
            cell.error = "no heartbeat"
            return cell
        apply_fault(sim.faults)
        start = time.monotonic()
        future = vehicle.logs.download(1, out, via=path)
        if fault == "outage":                           # mid-download: a third of the log held
            while not future.done() and not (vehicle.logs.progress and vehicle.logs.progress.held >= len(own) // 3):
                time.sleep(0.01)
            sim.faults.outage(1.0)
        outcome = future.result(timeout=CELL_LIMIT)
        cell.seconds = time.monotonic() - start
        cell.received = outcome.bytes_received
        cell.told = "saved" if outcome.ok else outcome.reason
        judge(cell, outcome, out, own)
    except Exception as exc:  # noqa: BLE001 - a cell that crashes is reported, not fatal to the table
        cell.error = f"{type(exc).__name__}: {exc}"
    finally:
        vehicle.close()
        sim.stop()
        shutil.rmtree(scratch, ignore_errors=True)
    return cell


def rows(cells: list[LogCell]) -> tuple[tuple, list[tuple]]:
    head = ("profile", "fault", "path", "told", "download s", "bytes received", "byte-identical", "wrong reports")
    lines = []
    for c in cells:
        told = f"ERROR {c.error}" if c.error else c.told if c.told == "saved" else \
            f"not finished, {c.kept} bytes kept resumable ({c.told})"
        lines.append((c.profile, c.fault, "LOG_DATA" if c.path == "log_data" else "FTP", told, f"{c.seconds:.1f}",
                      f"{c.received:,}", "yes" if c.identical else "no", str(len(c.wrong))))
    return head, lines
