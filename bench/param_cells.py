"""The fault matrix's parameter row: every parameter downloaded, and no wrong "set" report, under each fault.

One cell per firmware profile, read path and fault of bench/fault_matrix.py: the embedded driver downloads the whole
table (``fetch_parameters(refresh=True)``) with the fault on, over MAVLink FTP (``ftp``: @PARAM/param.pck, which the
copter-4 sim serves as the ArduCopter 4.6.3 recording does: the open's size only an estimate, 500-packet bursts, EOF
as a short packet and a NAK, 5.5 ms a packet) or the PARAM_REQUEST_LIST (``list``; the Solo's 3.3 has no FTP); the
"read over" column says which path brought the table (``ftp→list``: FTP gave up, and why). It then writes parameters (a float, an int8, an int32, back
again, and a name the vehicle does not have). Every answer is judged against the simulated vehicle's own table
the moment it is given: a set reported ACCEPTED that the vehicle does not hold, or reported refused or timed
out although the vehicle holds it, is a wrong report; so is a download reported complete with a value that is
not the vehicle's. The outage fault cuts the link for 1 s in the middle of the download.
"""
from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field

from driver.sim import SimConfig, SimVehicle
from driver.vehicle.state import CommandStatus
from driver.vehicle import Vehicle, VehicleConfig

UNKNOWN = "NO_SUCH_PARAM"    # a name the vehicle does not have: ArduPilot never answers it
SETS = (("WPNAV_SPEED", 750.0), ("FS_GCS_ENABLE", 1.0), ("RTL_ALT", 2500.0), ("WPNAV_SPEED", 1000.0),
        ("FS_GCS_ENABLE", 0.0), (UNKNOWN, 1.0))


@dataclass
class ParamCell:
    profile: str
    fault: str
    method: str = "ftp"
    used: str = ""
    downloaded: int = 0
    expected: int = 0
    seconds: float = 0.0
    told: list = field(default_factory=list)
    wrong: list = field(default_factory=list)
    error: str = ""

    @property
    def completed(self) -> bool:
        return not self.error and self.expected > 0 and self.downloaded == self.expected

    @property
    def sets_confirmed(self) -> bool:
        """Every set of a name the vehicle has was told accepted (``told``: the download, then each of SETS)."""
        sets = self.told[1:]
        return len(sets) == len(SETS) and all(t == "accepted" for (name, _), t in zip(SETS, sets)
                                              if name != UNKNOWN)


def _holds(sim: SimVehicle, name: str, value: float) -> bool:
    held = sim.autopilot.params.get(name)
    return held is not None and abs(float(held) - value) <= 1e-6 * max(1.0, abs(value))


def methods(profile: str) -> tuple[str, ...]:
    """The read paths a profile offers: FTP and the list where the firmware has FTP (copter-4), else the list."""
    return ("ftp", "list") if profile != "solo" else ("list",)


def check(profile: str, fault: str, speedup: float, apply_fault, method: str = "ftp") -> ParamCell:
    cell = ParamCell(profile, fault, method)
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=speedup, ready_after=2.0, seed=7, profile=profile,
                               mavlink2=profile != "solo"))
    sim.start()
    vehicle = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{sim.tcp_port}", param_cache=None,
                                    param_ftp=method == "ftp")).start()
    try:
        if not vehicle.wait_for(lambda s: s.connected and s.firmware, 60):   # FTP where the firmware offers it
            cell.error = "no heartbeat"
            return cell
        apply_fault(sim.faults)
        start = time.monotonic()
        future = vehicle.fetch_parameters(refresh=True)
        if fault == "outage":
            time.sleep(0.2)                             # mid-transfer (the FTP file or the list)
            sim.faults.outage(1.0)
        result = future.result(timeout=300)
        cell.seconds = time.monotonic() - start
        params = sim.autopilot.params
        table = vehicle.state().parameters
        cell.expected = len(params)
        cell.downloaded = sum(1 for n in params.names if table.get(n) is not None and (
            n.startswith("SR0_") or _holds(sim, n, table.get(n).value)))
        cell.used = "ftp" if "over MAVLink FTP" in result.reason else \
            "list" if "MAVLink FTP" not in result.reason else f"ftp→list ({result.reason})"
        cell.told.append(result.status.value)
        if result.ok and cell.downloaded != cell.expected:
            cell.wrong.append(f"{result} but {cell.expected - cell.downloaded} values are not the vehicle's")
        if not result.ok:
            cell.error = str(result)
        for name, value in SETS:
            answered = threading.Event()
            verdict = {}

            def judge(f, name=name, value=value):
                r = f.result()
                holds = _holds(sim, name, value)       # the vehicle's truth when the answer is given
                verdict["r"] = r
                if r.status is CommandStatus.ACCEPTED and not holds:
                    verdict["wrong"] = f"{r} but the vehicle holds {sim.autopilot.params.get(name)}"
                elif r.status in (CommandStatus.REFUSED, CommandStatus.TIMED_OUT) and holds:
                    verdict["wrong"] = f"{r} but the vehicle holds {value:g}"
                answered.set()
            vehicle.set_parameter(name, value).add_done_callback(judge)
            if not answered.wait(120):
                cell.wrong.append(f"param {name}={value:g}: no answer at all")
                continue
            cell.told.append(verdict["r"].status.value)
            if "wrong" in verdict:
                cell.wrong.append(verdict["wrong"])
    except Exception as exc:  # noqa: BLE001 - reported in the table
        cell.error = f"{type(exc).__name__}: {exc}"
    finally:
        vehicle.close()
        sim.stop()
    return cell


def rows(cells: list[ParamCell]) -> tuple[tuple, list[tuple]]:
    head = ("profile", "fault", "asked over", "read over", "every parameter", "downloaded", "download s",
            "told (download, sets; last: an unknown name)", "wrong reports")
    out = [(c.profile, c.fault, c.method, c.used, "yes" if c.completed else f"NO ({c.error})",
            f"{c.downloaded}/{c.expected}", f"{c.seconds:.1f}", ", ".join(c.told), str(len(c.wrong))) for c in cells]
    return head, out
