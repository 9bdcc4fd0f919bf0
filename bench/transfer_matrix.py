"""The fault matrix's transfer rows: upload and download of a 50-item mission and of a fence, per firmware profile
and link fault (bench/fault_matrix.py runs them after the flights; alone: python bench/transfer_matrix.py
[--markdown] [--write-docs]).

Every answer the driver gives is checked against what the simulated vehicle holds at that moment:

* a *wrong report*: an upload told ACCEPTED while the vehicle does not hold exactly that plan, told failed while
  it does hold it, a download told ACCEPTED whose plan is not the vehicle's, or a plan the driver says is on the
  vehicle (``state().mission.on_vehicle``) that is not;
* a *corrupted plan*: the vehicle holds part of a plan (ArduPilot writes mission items as they arrive) while the
  driver claims it holds something. After a failed upload the driver claims nothing and says so.

The Solo's ArduCopter 3.3 has no polygon fence: the fence row is correct when refused with that reason
(bench/faults.py's LACKS). Each cell's verdict, and the exit code, are bench/verdicts.py's.
"""
from __future__ import annotations

import os
import sys
import time
from dataclasses import dataclass, field

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from pymavlink.dialects.v20 import ardupilotmega as mavlink  # noqa: E402

from driver.core import frames  # noqa: E402
from driver.mission.plan import MissionItem, Plan, PlanKind  # noqa: E402
from driver.sim import SimConfig, SimVehicle  # noqa: E402
from driver.vehicle.state import CommandStatus  # noqa: E402
from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402
import tables  # noqa: E402  (bench/tables.py: this script runs from bench/)
import verdicts  # noqa: E402
from faults import LACKS  # noqa: E402

MISSION_ITEMS = 50
HOME = (40.2839, -3.7940, 664.0, 0.0)


def mission(count: int = MISSION_ITEMS, home=HOME) -> Plan:
    """A takeoff, a lawnmower of waypoints 5 m apart, an RTL: ``count`` items."""
    items = [MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=10)]
    for i in range(count - 2):
        lat, lon = frames.offset_latlon(home[0], home[1], 5.0 * (i % 10), 5.0 * (i // 10))
        items.append(MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, param1=i % 3, lat=lat, lon=lon, alt=10 + i % 5))
    items.append(MissionItem(mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH, frame=mavlink.MAV_FRAME_MISSION))
    return Plan(PlanKind.MISSION, tuple(items))


def fence(home=HOME) -> Plan:
    corners = [frames.offset_latlon(home[0], home[1], n, e) for n, e in ((-80, -80), (120, -80), (120, 120), (-80, 120))]
    items = [MissionItem(mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION, mavlink.MAV_FRAME_GLOBAL, 4, lat=a, lon=b)
             for a, b in corners]
    lat, lon = frames.offset_latlon(home[0], home[1], 60, 60)
    items.append(MissionItem(mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION, mavlink.MAV_FRAME_GLOBAL, 10, lat=lat, lon=lon))
    return Plan(PlanKind.FENCE, tuple(items))


def held(sim: SimVehicle, kind: PlanKind) -> list[tuple]:
    """What the vehicle holds, as (command, lat e7, lon e7) without the mission's home slot."""
    items = sim.autopilot.plan_items(kind)
    items = items[1:] if kind is PlanKind.MISSION else items
    return [(i.command, i.x, i.y) for i in items]


def as_held(plan: Plan) -> list[tuple]:
    def e7(v: float) -> int:
        return round(v * 1e7)
    return [(i.command, e7(i.lat) if i.has_position else 0, e7(i.lon) if i.has_position else 0) for i in plan.items]


def same(a: list[tuple], b: list[tuple], tolerance: int) -> bool:
    return len(a) == len(b) and all(x[0] == y[0] and abs(x[1] - y[1]) <= tolerance and abs(x[2] - y[2]) <= tolerance
                                    for x, y in zip(a, b))


@dataclass
class TransferCell:
    profile: str
    fault: str
    told: dict = field(default_factory=dict)       # row -> status told (as the table shows it)
    results: dict = field(default_factory=dict)    # row -> (status, reason) as the driver gave them
    times: dict = field(default_factory=dict)      # row -> real seconds
    holds: dict = field(default_factory=dict)      # row -> "new", "old", "part"
    wrong: list = field(default_factory=list)
    corrupted: int = 0
    error: str = ""


def _judge_upload(cell: TransferCell, row: str, sim, vehicle, plan: Plan, outcome, before: list[tuple]) -> None:
    tolerance = 1 if cell.profile != "solo" else 200            # MISSION_ITEM's float32 (~1.5e-5 degrees)
    now = held(sim, plan.kind)
    want = as_held(plan)
    new = same(now, want, tolerance)
    cell.holds[row] = "new" if new else "old" if now == before else "part"
    ok = outcome.result.status is CommandStatus.ACCEPTED
    if ok and not new:
        cell.wrong.append(f"{row}: told accepted, the vehicle holds {len(now)} other items")
    if not ok and new and outcome.result.status is not CommandStatus.REJECTED:
        cell.wrong.append(f"{row}: told {outcome.result.status.value} ({outcome.result.reason}) but the vehicle "
                          "holds the plan")
    claim = vehicle.state().mission.vehicle_plan(plan.kind)
    if claim is not None and not same(as_held(claim), now, tolerance):
        cell.wrong.append(f"{row}: the driver says the vehicle holds {len(claim)} items, it holds {len(now)}")
        if cell.holds[row] == "part":
            cell.corrupted += 1


def _judge_download(cell: TransferCell, row: str, sim, kind: PlanKind, outcome) -> None:
    tolerance = 1 if cell.profile != "solo" else 200
    if outcome.result.status is CommandStatus.ACCEPTED and not same(as_held(outcome.plan), held(sim, kind), tolerance):
        cell.wrong.append(f"{row}: told accepted with a plan that is not the vehicle's")


def transfer_cell(profile: str, fault: str, speedup: float, faults: dict) -> TransferCell:
    cell = TransferCell(profile, fault)
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=speedup, ready_after=2.0, seed=11, profile=profile,
                               mavlink2=profile != "solo", home=HOME))
    sim.start()
    vehicle = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{sim.tcp_port}")).start()
    try:
        if not vehicle.wait_for(lambda s: s.connected and s.home is not None and s.firmware, 60):
            cell.error = "never connected"
            return cell
        faults[fault][1](sim.faults)
        rows = (("mission up", mission()), ("mission down", PlanKind.MISSION), ("fence up", fence()),
                ("fence down", PlanKind.FENCE))
        for row, what in rows:
            if fault == "outage":
                sim.faults.outage(1.0)              # at the start of every transfer
            t0 = time.monotonic()
            if isinstance(what, Plan):
                before = held(sim, what.kind)
                outcome = vehicle.upload_plan(what).result(timeout=300)
                cell.times[row] = time.monotonic() - t0
                _judge_upload(cell, row, sim, vehicle, what, outcome, before)
            else:
                outcome = vehicle.download_plan(what).result(timeout=300)
                cell.times[row] = time.monotonic() - t0
                _judge_download(cell, row, sim, what, outcome)
            status = outcome.result.status
            cell.told[row] = status.value
            cell.results[row] = (status.value, outcome.result.reason)
            lacked = next((label for prefix, (words, label) in LACKS.get(profile, {}).items()
                           if row.startswith(prefix) and words in outcome.result.reason), None)
            if status is CommandStatus.REJECTED and lacked:
                cell.told[row] = lacked
                cell.times.pop(row, None)
    except Exception as exc:  # noqa: BLE001 - a cell that crashes is reported, not fatal to the table
        cell.error = f"{type(exc).__name__}: {exc}"
    finally:
        vehicle.close()
        sim.stop()
    return cell


ROWS = ("mission up", "mission down", "fence up", "fence down")


def transfer_table(cells: list[TransferCell], speedup: float, markdown: bool) -> str:
    head = ("profile", "fault", *[f"{r} (told, s)" for r in ROWS], "vehicle holds", "corrupted", "wrong reports")
    out_rows = []
    for c in cells:
        cols = []
        for r in ROWS:
            told = c.told.get(r, "-")
            cols.append(f"{told}, {c.times[r]:.1f}" if r in c.times else told)
        holds = "/".join(c.holds.get(r, "-") for r in ("mission up", "fence up"))
        out_rows.append((c.profile, c.fault, *cols, holds if not c.error else f"ERROR {c.error}", str(c.corrupted),
                         str(len(c.wrong))))
    out = tables.render(head, out_rows, markdown)
    out.append(f"(transfers: a {MISSION_ITEMS}-item mission and a 5-item fence; times in real seconds at sim "
               f"speed-up {speedup:g}, upload = accepted and read back; vehicle holds mission/fence after the upload)")
    for c in cells:
        for w in c.wrong:
            out.append(f"WRONG {c.profile}/{c.fault}: {w}")
    return "\n".join(out)


def main() -> int:
    import argparse
    import logging

    from faults import FAULTS, PROFILES           # the same faults and profiles as the flights
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speedup", type=float, default=2.0)
    ap.add_argument("--profiles", default=",".join(PROFILES))
    ap.add_argument("--faults", default=",".join(FAULTS))
    ap.add_argument("--markdown", action="store_true")
    tables.add_write_docs(ap)
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    cells = run_transfers(args.profiles.split(","), args.faults.split(","), args.speedup, FAULTS)
    print(transfer_table(cells, args.speedup, args.markdown))
    return verdicts.report([verdict(c) for c in cells])


def verdict(cell: TransferCell) -> verdicts.Verdict:
    """The cell's verdict: every row accepted, or refused for what the profile's firmware lacks."""
    lacks = {prefix: words for prefix, (words, _) in LACKS.get(cell.profile, {}).items()}
    return verdicts.transfers(cell, ROWS, lacks)


def run_transfers(profiles, faults_names, speedup: float, faults: dict) -> list[TransferCell]:
    cells = []
    for profile in profiles:
        for fault in faults_names:
            cell = transfer_cell(profile, fault, speedup, faults)
            print(f"{profile:9s} {fault:11s} transfers {cell.error or 'done'} wrong={len(cell.wrong)}",
                  file=sys.stderr, flush=True)
            cells.append(cell)
    return cells


if __name__ == "__main__":
    with tables.publishing("transfer_matrix"):
        sys.exit(main())

