"""Mission upload over a slow, lossy link: the driver against the protocol floor and a MAVProxy-style uploader.

    .venv/bin/python bench/bench_mission.py [--items 100] [--latency 0.025] [--loss 0,0.3] [--runs 1] [--write-docs]

On the simulated vehicle at real speed (1 ms physics steps, so the link and not the simulator sets the pace),
with ``--latency`` seconds each way (a telemetry radio's 50 ms round trip by default) and ``--loss`` each way:

* **driver**: ``Vehicle.upload_plan`` of ``--items`` items, which ends only once MISSION_ACK accepted it and the
  plan read back means the same; its upload phase (to the MISSION_ACK) is timed on its own too;
* **reference**: an uploader written here after MAVProxy's wp module (MAVProxy/modules/lib/
  mission_item_protocol.py, ``send_all_items`` and ``process_waypoint_request``): it sends MISSION_COUNT once,
  answers each MISSION_REQUEST with the item, relies on the vehicle to ask again (ArduPilot: every 1 s), stops
  answering once the last item is sent or 10 s after the previous one, and does not read back. It is timed to
  the vehicle's MISSION_ACK (ok when ACCEPTED and the vehicle holds the plan).

The protocol floor is the round trips a transfer cannot avoid times the round-trip time: an upload of W items
on the wire (the home slot and the items) is W + 1 round trips (MISSION_COUNT to the first request, each item
to the next request or the ACK); a read back is 1 + ceil(W / 4) more (MISSION_REQUEST_LIST to the count, then the
items asked four at a time, as the driver does; MAVProxy asks five). Each line prints the time and its ratio to
its floor.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from types import SimpleNamespace

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
os.environ["MAVLINK20"] = "1"                # the reference speaks MAVLink 2 (mission_type), as MAVProxy does

from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import ardupilotmega as mavlink  # noqa: E402

from driver.mission.plan import PlanKind  # noqa: E402
from driver.mission.transfer import WINDOW  # noqa: E402
from driver.mission.wire import home_slot, to_wire  # noqa: E402
from driver.sim import SimConfig, SimVehicle  # noqa: E402
from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402
from transfer_matrix import HOME, as_held, held, mission, same  # noqa: E402
import tables  # noqa: E402  (bench/tables.py: this script runs from bench/)

MAVPROXY_TIMEOUT = 10.0      # s without a request before MAVProxy's wp module gives a load up


def new_sim(seed: int) -> SimVehicle:
    """A clean link: degrade() slows it once the vehicle is up."""
    sim = SimVehicle(SimConfig(tcp_port=0, speedup=1.0, ready_after=1.0, rate_hz=1000, seed=seed, home=HOME))
    sim.start()
    return sim


def degrade(sim: SimVehicle, latency: float, loss: float) -> None:
    for link in (sim.faults.uplink, sim.faults.downlink):
        link.latency = latency
        link.loss = loss


def driver_run(items: int, latency: float, loss: float, seed: int) -> dict:
    sim = new_sim(seed)
    vehicle = Vehicle(VehicleConfig(connection=f"tcp:127.0.0.1:{sim.tcp_port}")).start()
    try:
        assert vehicle.wait_for(lambda s: s.connected and s.home is not None and s.firmware, 30), "no vehicle"
        plan = mission(items)
        degrade(sim, latency, loss)
        t0 = time.monotonic()
        future = vehicle.upload_plan(plan)
        reading = vehicle.wait_for(lambda s: future.done() or any(
            t.kind is PlanKind.MISSION and "reading back" in t.detail for t in s.mission.transfers), 600)
        upload = time.monotonic() - t0 if reading is not None and not future.done() else None
        outcome = future.result(timeout=600)
        total = time.monotonic() - t0
        exact = same(held(sim, PlanKind.MISSION), as_held(plan), 1)
        told = outcome.result.status.value if outcome.result.ok else str(outcome.result)
        return dict(ok=outcome.result.ok and exact, told=told, total=total, upload=upload)
    finally:
        vehicle.close()
        sim.stop()


def reference_run(items: int, latency: float, loss: float, seed: int) -> dict:
    """The MAVProxy-style upload: COUNT once, answer the requests until the last item went, then the ACK."""
    sim = new_sim(seed)
    link = mavutil.mavlink_connection(f"tcp:127.0.0.1:{sim.tcp_port}", source_system=255, source_component=190,
                                      dialect="ardupilotmega")
    try:
        link.wait_heartbeat(timeout=30)
        deadline = time.monotonic() + 30
        while not sim.autopilot.home_set and time.monotonic() < deadline:
            link.recv_match(blocking=True, timeout=0.1)
        plan = mission(items)
        lat, lon, alt, _ = HOME
        wire = [home_slot(SimpleNamespace(lat=lat, lon=lon, alt=alt))] + list(plan.items)
        degrade(sim, latency, loss)
        t0 = time.monotonic()
        link.mav.mission_count_send(1, 1, len(wire), mavlink.MAV_MISSION_TYPE_MISSION)
        loading, last_sent = True, time.monotonic()
        done = None
        while done is None:
            m = link.recv_match(type=["MISSION_REQUEST", "MISSION_REQUEST_INT", "MISSION_ACK"], blocking=True,
                                timeout=0.1)
            now = time.monotonic()
            if now - last_sent > MAVPROXY_TIMEOUT:
                loading = False
                done = done or "no MISSION_ACK (MAVProxy stopped answering)"
            if m is None:
                continue
            if m.get_type() == "MISSION_ACK":
                name = mavlink.enums["MAV_MISSION_RESULT"][m.type].name.replace("MAV_MISSION_", "").lower()
                done = "accepted" if m.type == mavlink.MAV_MISSION_ACCEPTED else f"MISSION_ACK {name}"
                continue
            if not loading or not 0 <= m.seq < len(wire):
                continue
            link.mav.send(to_wire(link.mav, wire[m.seq], m.seq, PlanKind.MISSION, (1, 1), True, True))
            last_sent = now
            if m.seq == len(wire) - 1:
                loading = False                    # "Sent all N waypoints": requests after it go unanswered
        total = time.monotonic() - t0
        exact = same(held(sim, PlanKind.MISSION), as_held(plan), 1)
        return dict(ok=done == "accepted" and exact, told=done, total=total, upload=total)
    finally:
        link.close()
        sim.stop()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--items", type=int, default=100)
    ap.add_argument("--latency", type=float, default=0.025, help="s each way")
    ap.add_argument("--loss", default="0,0.3", help="shares lost each way, one run set per value")
    ap.add_argument("--runs", type=int, default=1)
    tables.add_write_docs(ap)
    args = ap.parse_args()
    wire = args.items + 1
    rtt = 2 * args.latency
    floor_up = (wire + 1) * rtt
    floor_all = floor_up + (1 + -(-wire // WINDOW)) * rtt
    print(f"{args.items} items ({wire} on the wire with the home slot), {args.latency * 1000:.0f} ms each way: "
          f"floor {floor_up:.2f} s to upload, {floor_all:.2f} s to upload and read back")
    print(f"{'uploader':34s} {'loss':>5s} {'ok':>5s} {'upload s':>9s} {'x floor':>8s} {'verified s':>11s} "
          f"{'x floor':>8s}  told")
    for loss in (float(x) for x in args.loss.split(",")):
        for name, run in (("driver (upload + read back)", driver_run), ("reference (MAVProxy wp style)", reference_run)):
            results = [run(args.items, args.latency, loss, seed) for seed in range(1, args.runs + 1)]
            ups = [r["upload"] for r in results if r["ok"] and r["upload"] is not None]
            totals = [r["total"] for r in results if r["ok"]]
            up = statistics.median(ups) if ups else None
            verified = statistics.median(totals) if totals and name.startswith("driver") else None
            print(f"{name:34s} {loss * 100:4.0f}% {sum(r['ok'] for r in results):>2d}/{len(results):<2d} "
                  f"{(f'{up:9.2f}' if up else '        -')} {(f'{up / floor_up:8.1f}' if up else '       -')} "
                  f"{(f'{verified:11.2f}' if verified else '          -')} "
                  f"{(f'{verified / floor_all:8.1f}' if verified else '       -')}  "
                  f"{', '.join(sorted({r['told'] for r in results}))}", flush=True)
    return 0


if __name__ == "__main__":
    with tables.publishing("mission"):
        sys.exit(main())
