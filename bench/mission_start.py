"""Does a mission start through a lossy link, and fly? Real ArduCopter 4.6.3 SITL, one seed of loss after another.

    .venv/bin/python bench/mission_start.py --sitl /work/sitl/ardupilot/build/sitl/bin/arducopter \\
        --shim /work/sitl/bind_loopback.so [--loss 0.3] [--seeds 10] [--markdown] [--write-docs]

For each seed the driver (a fresh ``Vehicle``, the viewer's own) reaches the SITL's SERIAL0 through
bench/lossy_relay.py dropping ``--loss`` of the frames each way, uploads a 5-item mission (takeoff to 5 m, three
waypoints 15 m apart, land) and presses Start mission from the ground, the vehicle disarmed in STABILIZE. The truth
is read on SERIAL1, loss-free, with plain pymavlink (bench/sitl_judge.py). ArduCopter's DISARM_DELAY stays at its
default (10 s): a start whose steps a lossy link slows past it finds the vehicle disarmed, and the mission never
flies. A seed passes when the driver said the mission started *and* the vehicle flew it: every waypoint reached,
landed and disarmed by itself; and, once it has, the driver says the mission is complete, not still running. A
driver that says "refused" for a start that did not fly is honest but fails the seed: the mission did not fly.
"""
from __future__ import annotations

import argparse
import atexit
import contextlib
import logging
import os
import shutil
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from pymavlink.dialects.v20 import ardupilotmega as mavlink  # noqa: E402

from lossy_relay import LossyRelay, free_udp_port  # noqa: E402
from real_sitl import HOME, SHIM, Sitl  # noqa: E402
from sitl_judge import Judge  # noqa: E402
import tables  # noqa: E402

from driver import Vehicle, VehicleConfig  # noqa: E402
from driver.core.frames import offset_latlon  # noqa: E402
from driver.mission.plan import MissionItem, MissionRunState, Plan, PlanKind  # noqa: E402

WAYPOINTS = ((15.0, 0.0), (15.0, 15.0), (0.0, 15.0))
ALTITUDE = 5.0


def mission() -> Plan:
    items = [MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=ALTITUDE)]
    for north, east in WAYPOINTS:
        lat, lon = offset_latlon(HOME[0], HOME[1], north, east)
        items.append(MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, lat=lat, lon=lon, alt=ALTITUDE))
    items.append(MissionItem(mavlink.MAV_CMD_NAV_LAND))
    return Plan(PlanKind.MISSION, tuple(items))


def fly_one(judge: Judge, serial0: int, loss: float, seed: int, scratch: str) -> dict:
    """One seed; returns the row's cells."""
    row = dict(seed=seed, told="-", armed="-", auto="-", airborne="-", reached="-", landed="no", after="-",
               verdict="fail")
    judge.command(mavlink.MAV_CMD_DO_SET_MODE, 1, 0)                     # STABILIZE, disarmed: as a pilot finds it
    relay = LossyRelay(serial0, free_udp_port(), loss, seed)
    vehicle = Vehicle(VehicleConfig(connection=f"udpin:127.0.0.1:{relay.udp_port}", tlog_path=os.path.join(
        scratch, f"seed{seed}.tlog"), param_cache=None)).start()
    try:
        ready = vehicle.wait_for(lambda s: s.connected and s.readiness.ready_to_arm and s.home is not None
                                 and s.in_air is False, 90)
        if ready is None:
            row["told"] = "never ready"
            return row
        upload = vehicle.upload_plan(mission()).result(120)
        if not upload.result.ok:
            row["told"] = f"upload: {upload.result.reason[:60]}"
            return row
        reached_before = len(judge.reached)
        started = time.monotonic()
        result = vehicle.start_mission().result(120)
        row["told"] = f"{result.status.value} ({result.reason[:50]})"
        changes = [c for c in judge.changes if c[0] >= started]
        armed_at = next((t for t, _mode, armed in changes if armed), None)
        auto = next((t for t, mode, armed in changes if mode == "AUTO" and armed and t >= (armed_at or 0)), None)
        row["armed"] = "-" if armed_at is None else f"{armed_at - started:.1f}"
        row["auto"] = "-" if auto is None else f"{auto - started:.1f}"
        if judge.wait(lambda: (judge.altitude or 0.0) > 1.0, 30):
            row["airborne"] = f"{time.monotonic() - started:.1f}"
        flown = judge.wait(lambda: len(judge.reached) - reached_before >= len(WAYPOINTS) + 1, 180)
        row["reached"] = f"{len(judge.reached) - reached_before}/{len(WAYPOINTS) + 1}"
        landed = flown and judge.wait(lambda: judge.armed is False, 120)
        row["landed"] = "yes" if landed else "no"
        if landed:
            after = vehicle.wait_for(lambda s: s.mission.state is MissionRunState.COMPLETE and not s.armed, 30)
            now = vehicle.state().mission
            row["after"] = "complete" if after is not None else f"{now.state.name} item {now.current}"
        ok = result.ok and flown and landed and row["after"] == "complete"
        row["verdict"] = "pass" if ok else "fail"
        return row
    finally:
        vehicle.close()
        relay.close()
        judge.wait(lambda: judge.armed is False, 60)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    where = ap.add_mutually_exclusive_group(required=True)
    where.add_argument("--sitl", metavar="PATH", help="the arducopter SITL binary: started here, wiped")
    where.add_argument("--connect", action="store_true", help="a SITL already running for --instance")
    ap.add_argument("--loss", type=float, default=0.3)
    ap.add_argument("--seeds", type=int, default=10, help="seeds 1..N, one mission each")
    ap.add_argument("--instance", type=int, default=0)
    ap.add_argument("--shim", default=SHIM)
    ap.add_argument("--defaults")
    ap.add_argument("--markdown", action="store_true")
    tables.add_write_docs(ap)
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    scratch = tempfile.mkdtemp(prefix="mission-start-")
    for var in ("XDG_STATE_HOME", "XDG_CACHE_HOME"):
        os.environ[var] = scratch
    sitl = Sitl(args.sitl, args.instance, scratch, args.shim, args.defaults) if args.sitl else None
    atexit.register(lambda: sitl and sitl.stop())
    serial0, serial1 = 5760 + 10 * args.instance, 5762 + 10 * args.instance
    started = time.monotonic()
    rows = []
    judge = None
    try:
        if sitl:
            sitl.start()
        keeper = LossyRelay(serial0, free_udp_port(), 0.0, 0)     # SERIAL1 listens once SERIAL0 has a client
        with contextlib.redirect_stdout(sys.stderr):
            judge = Judge(serial1, 60)
        keeper.close()
        if not judge.wait(lambda: judge.prearm_ok, 120):
            print("mission_start: the SITL never became ready to arm", file=sys.stderr)
            return 2
        for seed in range(1, args.seeds + 1):
            row = fly_one(judge, serial0, args.loss, seed, scratch)
            rows.append(row)
            print(" ".join(f"{k}={v}" for k, v in row.items()), file=sys.stderr, flush=True)
    finally:
        if judge is not None:
            judge.close()
        if sitl:
            sitl.stop()
        shutil.rmtree(scratch, ignore_errors=True)
    head = ("seed", "start told", "armed s", "AUTO s", "airborne s", "items reached", "landed", "driver after",
            "verdict")
    lines = tables.render(head, [tuple(str(r[k]) for k in ("seed", "told", "armed", "auto", "airborne", "reached",
                                                          "landed", "after", "verdict")) for r in rows], args.markdown)
    passed = sum(r["verdict"] == "pass" for r in rows)
    lines += ["", f"{passed} of {len(rows)} seeds started and flew the mission at {args.loss:.0%} loss each way "
                  f"(DISARM_DELAY 10 s; whole run {time.monotonic() - started:.0f} s)"]
    print("\n".join(lines))
    return 0 if passed >= 0.9 * len(rows) else 1


if __name__ == "__main__":
    with tables.publishing(tables.variant("mission_start", "--loss")):
        sys.exit(main())
