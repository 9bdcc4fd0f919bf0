"""Check against real firmware: the driver's every answer judged against a real ArduCopter 4.6.3 SITL.

    .venv/bin/python bench/real_sitl.py --sitl /work/sitl/ardupilot/build/sitl/bin/arducopter [--loss 0.3]
                                        [--instance 0] [--seed 1] [--blackout 0] [--markdown] [--keep] [--write-docs]
    .venv/bin/python bench/real_sitl.py --connect [--instance 0] ...        # a SITL already running

A bench, not a test: it needs ArduPilot's SITL binary, which CI cannot build (docs: /work/shared/reference/sitl.md
or docs/real-sitl.md). With ``--sitl`` it starts the SITL itself, wiped (``-w``), in a
scratch folder, kept on 127.0.0.1 by an LD_PRELOAD shim (``--shim``), and kills it by its PID on any exit.

The driver (``Vehicle``, the viewer's own, through its public API only) reaches the vehicle's SERIAL0 through
bench/lossy_relay.py, which drops each MAVLink frame with probability ``--loss`` each way (seeded) and can black
the link out. The truth is read on SERIAL1, loss-free, with plain pymavlink (bench/sitl_judge.py). In order:
ready to arm; a 40-item mission, a 5-vertex inclusion fence and 3 rally points uploaded; every parameter fetched
(over MAVLink FTP where the driver chooses it); five parameters set; a 5-item mission flown (takeoff, three
waypoints, land) with a pause and a resume; every parameter fetched again by the list (a second driver with FTP
off); and the newest DataFlash log downloaded, disarmed (``op_log_download``), compared byte for byte with the
SITL's own file in its scratch folder's logs/.

Each answer is judged against what the vehicle holds or did once the answer is given:

* **right**: accepted and the vehicle holds it (or did it); or not accepted and the vehicle does not hold it,
  for a reason that is true of the vehicle;
* **wrong**: accepted but the vehicle does not hold it; not accepted although it does; a reason that is false of
  the vehicle (it "has no parameter" it has, it "has not sent its home" when it has one); a refusal by the driver
  itself (``rejected``) of what the vehicle can do (every operation here is one it can); or no answer at all
  within the operation's time limit (so a transfer that never ends shows, and the bench never hangs).

The table: operation | driver said | vehicle holds | s | verdict, then "N answers, W wrong" and the reasons.
"""
from __future__ import annotations

import argparse
import atexit
import contextlib
import logging
import math
import os
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
from concurrent.futures import TimeoutError as FutureTimeout
from dataclasses import dataclass

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from pymavlink.dialects.v20 import ardupilotmega as mavlink  # noqa: E402

from log_cells import LogCell, judge as judge_log_download  # noqa: E402
from lossy_relay import LossyRelay, free_udp_port  # noqa: E402
from sitl_judge import HeldItem, Judge  # noqa: E402
import tables  # noqa: E402

from driver import CommandStatus, Vehicle, VehicleConfig  # noqa: E402
from driver.core.frames import offset_latlon  # noqa: E402
from driver.mission.plan import MissionItem, MissionRunState, Plan, PlanKind  # noqa: E402

HOME = (-35.363261, 149.165230, 584.0, 353.0)           # ArduPilot's CMAC, as in sitl.md and the recordings
#: The loopback shim: bench/bind_loopback.c built next to it (docs/real-sitl.md's gcc line), or $UAV_BIND_SHIM.
SHIM = os.environ.get("UAV_BIND_SHIM") or os.path.join(os.path.dirname(os.path.abspath(__file__)), "bind_loopback.so")
MISSION_ITEMS = 40
#: (name, value): a float, an int32, two int16, an int8; none of them their default, all harmless to the flight
#: (a quicker waypoint speed and landing; a longer disarm delay, so a mission start slowed by loss still finds
#: the vehicle armed: at 5 s it often did not, and the start is then refused).
SETS = (("WPNAV_SPEED", 750.0), ("RTL_ALT", 1200.0), ("LAND_SPEED", 100.0), ("PILOT_SPEED_UP", 300.0),
        ("DISARM_DELAY", 15.0))
#: Parameters that change by themselves (counters) or by the links' own stream requests: not compared.
VOLATILE = ("STAT_", "SR0_", "SR1_")
#: Seconds each operation may take before "no answer".
TIMEOUT = dict(ready=120.0, upload=60.0, params=60.0, set=15.0, start=60.0, pause=20.0, resume=20.0,
               flown=150.0, connect=30.0, log=300.0)


# -- the plans ------------------------------------------------------------------------------------------------
def _at(north: float, east: float) -> tuple[float, float]:
    return offset_latlon(HOME[0], HOME[1], north, east)


def survey_mission(count: int = MISSION_ITEMS) -> Plan:
    """A takeoff, a lawnmower of waypoints 5 m apart, an RTL: ``count`` items."""
    items = [MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=10)]
    for i in range(count - 2):
        lat, lon = _at(5.0 * (i % 10), 5.0 * (i // 10))
        items.append(MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, lat=lat, lon=lon, alt=10 + i % 5))
    items.append(MissionItem(mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH, frame=mavlink.MAV_FRAME_MISSION))
    return Plan(PlanKind.MISSION, tuple(items))


def fence() -> Plan:
    """A pentagon of 150 m around home: an inclusion fence of 5 vertices."""
    corners = [_at(150 * math.cos(math.radians(72 * k)), 150 * math.sin(math.radians(72 * k))) for k in range(5)]
    return Plan(PlanKind.FENCE, tuple(MissionItem(mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                                                  mavlink.MAV_FRAME_GLOBAL, 5, lat=a, lon=b) for a, b in corners))


def rally() -> Plan:
    return Plan(PlanKind.RALLY, tuple(MissionItem(mavlink.MAV_CMD_NAV_RALLY_POINT, lat=a, lon=b, alt=15)
                                      for a, b in (_at(40, 0), _at(0, 40), _at(-40, -40))))


def flight() -> Plan:
    """Takeoff to 10 m, a square of 30 m by three waypoints, land at home: 5 items, about a minute."""
    items = [MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=10)]
    items += [MissionItem(mavlink.MAV_CMD_NAV_WAYPOINT, lat=a, lon=b, alt=10) for a, b in (_at(30, 0), _at(30, 30),
                                                                                           _at(0, 30))]
    lat, lon = _at(0, 0)
    items.append(MissionItem(mavlink.MAV_CMD_NAV_LAND, lat=lat, lon=lon))
    return Plan(PlanKind.MISSION, tuple(items))


def held_like(plan: Plan, held: list[HeldItem] | None) -> bool:
    """The vehicle holds ``plan`` in meaning: each command, its position to 1e-7 degrees and its altitude (not
    for fence vertices) to a centimetre; frames and autocontinue come back changed (recordings' README)."""
    if held is None or len(held) != len(plan.items):
        return False
    for want, got in zip(plan.items, held):
        if want.command != got.command:
            return False
        if want.has_position and (abs(round(want.lat * 1e7) - got.x) > 1 or abs(round(want.lon * 1e7) - got.y) > 1):
            return False
        if want.has_position and plan.kind is not PlanKind.FENCE and abs(want.alt - got.z) > 0.01:
            return False
    return True


def float32(value: float) -> float:
    return struct.unpack("<f", struct.pack("<f", value))[0]


# -- judging ---------------------------------------------------------------------------------------------------
@dataclass
class Row:
    op: str
    said: str
    holds: str
    seconds: float | None = None
    verdict: str = "right"                   # "right", "wrong", or "-" (not an answer: the log hook)
    why: str = ""


def verdict(result, held: bool, false_premise: str = "", doing: bool = False) -> tuple[str, str]:
    """right/wrong and why, for a driver's CommandResult (None: no answer) and whether the vehicle holds it (or,
    ``doing``, is doing it)."""
    if result is None:
        return "wrong", "no answer within the time limit"
    if result.status is CommandStatus.ACCEPTED:
        return ("right", "") if held else \
            ("wrong", f"told accepted, but the vehicle {'is not doing' if doing else 'does not hold'} it")
    if held:
        return "wrong", f"told {result.status.value}, but the vehicle {'is doing' if doing else 'holds'} it"
    if false_premise:
        return "wrong", f"told {result.status.value} ({result.reason}), but {false_premise}"
    if result.status is CommandStatus.REJECTED:
        return "wrong", f"refused by the driver ({result.reason}), though the vehicle can do it"
    return "right", ""


def said(result, timeout: float, extra: str = "") -> str:
    if result is None:
        return f"no answer in {timeout:g} s" + (f" ({extra})" if extra else "")
    text = result.status.value + (f" ({extra})" if extra else "")
    if result.reason and not result.ok:
        reason = result.reason if len(result.reason) <= 70 else result.reason[:67] + "..."
        text += f": {reason}"
    return text


def answer(future, timeout: float):
    """The future's CommandResult (a TransferOutcome's result) and the seconds it took; None when none came."""
    t0 = time.monotonic()
    try:
        value = future.result(timeout=timeout)
    except FutureTimeout:
        return None, time.monotonic() - t0
    return getattr(value, "result", value), time.monotonic() - t0


class Bench:
    """One run: the driver through the relay, the judge on SERIAL1, a row per answer."""

    def __init__(self, judge: Judge, relay: LossyRelay, args, scratch: str):
        self.judge, self.relay, self.args, self.scratch = judge, relay, args, scratch
        self.rows: list[Row] = []
        self.vehicle = self.new_driver(param_ftp=True)

    def new_driver(self, param_ftp: bool) -> Vehicle:
        port = free_udp_port()
        self.relay.retarget(port)
        tlog = os.path.join(self.scratch, f"driver-{port}.tlog") if self.args.keep else None
        return Vehicle(VehicleConfig(connection=f"udpin:127.0.0.1:{port}", param_cache=None, tlog_path=tlog,
                                     param_ftp=param_ftp)).start()

    def add(self, row: Row) -> Row:
        self.rows.append(row)
        mark = "" if row.verdict != "wrong" else f"  WRONG: {row.why}"
        print(f"  {row.op}: {row.said} | {row.holds}{mark}", file=sys.stderr, flush=True)
        return row

    # -- the operations -------------------------------------------------------------------------------------
    def ready(self) -> None:
        t0 = time.monotonic()
        s = self.vehicle.wait_for(lambda s: s.connected and s.readiness.ready_to_arm, TIMEOUT["ready"])
        seconds = time.monotonic() - t0
        truth = self.judge.wait(lambda: self.judge.prearm_ok, 3.0 if s else 0.1)
        now = self.vehicle.state()
        told = "ready to arm" if s else f"not ready in {TIMEOUT['ready']:g} s (missing: " \
            f"{', '.join(now.readiness.missing) or 'link'})"
        holds = ("pre-arm OK" if truth else "pre-arm failing") + (", home set" if self.judge.home else ", no home")
        row = Row("ready to arm", told, holds, seconds)
        if s and not truth:
            row.verdict, row.why = "wrong", "told ready, but the vehicle's pre-arm check fails" \
                f" (the vehicle: {self.judge.story(t0 - 60.0)}; the judge's newest: {self.judge.ages()}; " \
                f"the driver's readiness: {now.readiness})"
        elif not s and truth:
            row.verdict, row.why = "wrong", "never told ready, though the vehicle is"
        self.add(row)

    def upload(self, op: str, plan: Plan, blackout: float = 0.0) -> bool:
        future = self.vehicle.upload_plan(plan)
        if blackout:
            time.sleep(1.0)
            self.relay.blackout(blackout)
        result, seconds = answer(future, TIMEOUT["upload"])
        held = self.judge.read_plan(int(plan.kind))
        holds_it = held_like(plan, held)
        holds = "unreadable" if held is None else f"{len(held)} items" + (", this plan" if holds_it else
                                                                            ", not this plan")
        premise = "the vehicle has its home" if result is not None and "home" in result.reason \
            and self.judge.home is not None else ""
        row = Row(op, said(result, TIMEOUT["upload"]), holds, seconds, *verdict(result, holds_it, premise))
        self.add(row)
        return holds_it

    def fetch_parameters(self, op: str, blackout: float = 0.0) -> None:
        future = self.vehicle.fetch_parameters(refresh=True)
        if blackout:
            time.sleep(0.3)
            self.relay.blackout(blackout)
        result, seconds = answer(future, TIMEOUT["params"])
        table = self.vehicle.state().parameters
        truth = self.judge.all_params()
        compared = [n for n in truth if not n.startswith(VOLATILE)]
        off = [n for n in compared if table.get(n) is None
               or float32(table.get(n).value) != float32(truth[n][0])]
        how = "" if result is None else "FTP" if "FTP" in result.reason else "list"
        count = f"{table.received}/{table.expected if table.expected is not None else '?'}" + (f" {how}" if how else "")
        told = said(result, TIMEOUT["params"], count if result is not None else
                    f"{table.received} values; {table.detail or 'no detail'}")
        holds = f"{len(truth)} parameters" + (f"; {len(off)} not in the driver's table as held (e.g. "
                                              f"{', '.join(off[:3])})" if off else "")
        row = Row(op, told, holds, seconds, *verdict(result, bool(truth) and not off))
        self.add(row)

    def set_parameter(self, name: str, value: float) -> None:
        future = self.vehicle.set_parameter(name, value)
        result, seconds = answer(future, TIMEOUT["set"])

        def holds_it() -> bool:
            got = self.judge.param(name)
            return got is not None and float32(got[0]) == float32(value)
        held = self.judge.wait(holds_it, 1.5) if result is not None and result.ok else holds_it()
        got = self.judge.param(name)
        premise = f"the vehicle has {name}" if result is not None and "no parameter" in result.reason \
            and got is not None else ""
        row = Row(f"set {name} = {value:g}", said(result, TIMEOUT["set"]),
                  "no such parameter" if got is None else f"{name} = {got[0]:g}", seconds,
                  *verdict(result, held, premise))
        self.add(row)

    def _flight_state(self) -> str:
        current = self.judge.mission_current
        item = f", item {current[0]} ({MissionRunState(current[1]).name.lower()})" if current else ""
        return f"{self.judge.mode}, {'armed' if self.judge.armed else 'disarmed'}{item}"

    def fly(self) -> None:
        if not self.upload("upload the flight (5 items)", flight()):
            self.add(Row("fly the mission", "not flown", "the vehicle does not hold the flight", verdict="-"))
            return
        asked = time.monotonic()
        result, seconds = answer(self.vehicle.start_mission(), TIMEOUT["start"])
        started = self.judge.wait(lambda: self.judge.mode == "AUTO" and self.judge.armed, 3.0 if result else 0.1)
        row = self.add(Row("mission start", said(result, TIMEOUT["start"]), self._flight_state(), seconds,
                           *verdict(result, started, doing=True)))
        if row.verdict == "wrong":
            row.why += f" (the vehicle: {self.judge.story(asked)})"
        if not started:
            return
        if not self.judge.wait(lambda: (self.judge.mission_current or (0,))[0] >= 2, 60):
            self.add(Row("mission progress", "-", f"never flew to item 2 ({self._flight_state()})", verdict="-"))
        result, seconds = answer(self.vehicle.pause_mission(), TIMEOUT["pause"])
        paused = self.judge.wait(lambda: self.judge.mode == "BRAKE", 2.0 if result else 0.1)
        self.add(Row("mission pause", said(result, TIMEOUT["pause"]), self._flight_state(), seconds,
                     *verdict(result, paused, doing=True)))
        time.sleep(3.0)                                     # held in BRAKE: the current item must stay
        self.progress("progress while paused")
        result, seconds = answer(self.vehicle.resume_mission(), TIMEOUT["resume"])
        running = self.judge.wait(lambda: self.judge.mode == "AUTO" and (self.judge.mission_current or (0, 0))[1]
                                  == MissionRunState.ACTIVE, 3.0 if result else 0.1)
        self.add(Row("mission resume", said(result, TIMEOUT["resume"]), self._flight_state(), seconds,
                     *verdict(result, running, doing=True)))
        t0 = time.monotonic()
        landed = self.judge.wait(lambda: self.judge.armed is False, TIMEOUT["flown"])
        time.sleep(2.0)                                     # the driver's MISSION_CURRENT at its stream rate
        self.progress("mission flown" if landed else f"mission not flown in {TIMEOUT['flown']:g} s",
                      time.monotonic() - t0)

    def progress(self, op: str, seconds: float | None = None) -> None:
        """The driver's mission progress and arming against the vehicle's, after up to 3 s to agree."""
        def agree() -> bool:
            s, current = self.vehicle.state(), self.judge.mission_current
            return current is not None and s.mission.current == current[0] and s.mission.state == current[1] \
                and s.armed == self.judge.armed
        agreed = self.judge.wait(agree, 3.0)
        s = self.vehicle.state()
        told = f"item {s.mission.current} ({s.mission.state.name.lower()}), " \
               f"{'armed' if s.armed else 'disarmed'}, last reached {s.mission.last_reached}"
        reached = self.judge.reached[-1] if self.judge.reached else None
        row = Row(op, told, f"{self._flight_state()}, last reached {reached}", seconds)
        if not agreed:
            row.verdict, row.why = "wrong", "the driver's item, mission state or arming is not the vehicle's" \
                f" (the judge's newest: {self.judge.ages()})"
        self.add(row)

    def parameters_by_list(self) -> None:
        """A second driver with FTP off: the classic PARAM_REQUEST_LIST path through the same lossy link."""
        self.vehicle.close()
        self.vehicle = self.new_driver(param_ftp=False)
        if not self.vehicle.wait_for(lambda s: s.connected, TIMEOUT["connect"]):
            self.add(Row("parameters (list)", "no link", "-", verdict="wrong", why="the second driver never connected"))
            return
        self.fetch_parameters("parameters (list, FTP off)")

    def op_log_download(self) -> None:
        """The newest log, once the vehicle has disarmed (armed, ArduPilot ignores every LOG_* request), judged
        against the SITL's own file (``logs/0000000N.BIN`` in its scratch folder). The newest log grows until a
        download starts, so the file is compared as the vehicle's stream ended: its first ``outcome.size`` bytes
        (the driver's size) must be the downloaded file, byte for byte."""
        self.judge.wait(lambda: self.judge.armed is False, 30.0)
        out = os.path.join(self.scratch, "downloaded", "newest.BIN")
        outcome, seconds = answer(self.vehicle.logs.download_latest(out), TIMEOUT["log"])
        if outcome is None:
            self.add(Row("log download (newest)", f"no answer in {TIMEOUT['log']:g} s", "-", seconds, "wrong",
                         "no answer within the time limit"))
            return
        if not outcome.ok and "Disarm for log download" in outcome.reason:
            armed = self.judge.armed
            self.add(Row("log download (newest)", said_log(outcome), "armed" if armed else "disarmed", seconds,
                         "right" if armed else "wrong", "" if armed else "told armed, but the vehicle is disarmed"))
            return
        own_path = os.path.join(self.scratch, "logs", f"{outcome.log_id:08d}.BIN")
        if not outcome.log_id or not os.path.exists(own_path):
            listed = self.judge.logs()
            holds = f"newest log {listed[-1].id}, {listed[-1].size} bytes listed" if listed else "no log listed"
            self.add(Row("log download (newest)", said_log(outcome), holds + "; no SITL file at hand to compare",
                         seconds, "-"))
            return
        with open(own_path, "rb") as f:
            own = f.read()
        cell = LogCell("sitl", "", "log_data")
        judge_log_download(cell, outcome, out, own[:outcome.size] if outcome.ok else own)
        holds = f"{own_path[len(self.scratch) + 1:]}: {len(own):,} bytes now" + \
            (f"; its first {outcome.size:,} {'are' if cell.identical else 'are NOT'} the download" if outcome.ok
             else "")
        self.add(Row("log download (newest)", said_log(outcome), holds, seconds,
                     "wrong" if cell.wrong else "right", "; ".join(cell.wrong)))

    def run(self) -> None:
        self.ready()
        self.upload(f"upload a {MISSION_ITEMS}-item mission", survey_mission(), self.args.blackout)
        self.upload("upload a 5-vertex fence", fence())
        self.upload("upload 3 rally points", rally())
        self.fetch_parameters("parameters (as the driver chooses)", self.args.blackout)
        for name, value in SETS:
            self.set_parameter(name, value)
        self.fly()
        self.parameters_by_list()
        self.op_log_download()


def said_log(outcome) -> str:
    if not outcome.ok:
        return outcome.reason if len(outcome.reason) <= 110 else outcome.reason[:107] + "..."
    return f"log {outcome.log_id}: {outcome.size:,} bytes in {outcome.seconds:.1f} s " \
           f"({outcome.rate / 1000:,.0f} kB/s), {outcome.bytes_received:,} received" + \
           (f"; ends with {outcome.ending}" if outcome.ending else "")


def start_sim(instance: int, scratch: str):
    """driver.sim on the SITL's ports: its USB-like port as SERIAL0, its telemetry port as SERIAL1; its logs in
    the scratch folder's logs/, where the SITL keeps its own."""
    from driver.sim import SimConfig, SimVehicle
    sim = SimVehicle(SimConfig(usb_port=5760 + 10 * instance, tcp_port=5762 + 10 * instance, home=HOME,
                               ready_after=5.0, seed=1, log_dir=os.path.join(scratch, "logs")))
    sim.start()
    return sim


# -- the SITL ------------------------------------------------------------------------------------------------------
class Sitl:
    """ArduCopter SITL started here, wiped, in ``scratch``, on loopback only; stopped by its PID."""

    def __init__(self, binary: str, instance: int, scratch: str, shim: str, defaults: str | None, model: str = "+"):
        self.binary, self.instance, self.scratch, self.shim = os.path.abspath(binary), instance, scratch, shim
        self.model = model                      # "+" (a quad); "calibration": the airframe turned by servos 5-8
        root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(self.binary))))
        self.defaults = defaults or os.path.join(root, "Tools", "autotest", "default_params", "copter.parm")
        self.proc: subprocess.Popen | None = None
        self.log_path = os.path.join(scratch, "sitl.log")

    def start(self) -> None:
        for what, path in (("SITL binary", self.binary), ("loopback shim", self.shim), ("defaults", self.defaults)):
            if not os.path.exists(path):
                raise SystemExit(f"real_sitl: the {what} {path} does not exist")
        home = ",".join(f"{v:.7f}".rstrip("0").rstrip(".") for v in HOME)
        with open(self.log_path, "wb") as log:
            self.proc = subprocess.Popen(
                [self.binary, "--model", self.model, "--speedup", "1", "-I", str(self.instance), "-w",
                 "--defaults", self.defaults, "--home", home, "--serial0", "tcp:0", "--serial1", "tcp:2"],
                cwd=self.scratch, env=dict(os.environ, LD_PRELOAD=self.shim), stdin=subprocess.DEVNULL,
                stdout=log, stderr=subprocess.STDOUT)
        print(f"SITL pid {self.proc.pid} in {self.scratch}", file=sys.stderr, flush=True)

    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def stop(self) -> None:
        if not self.alive():
            return
        self.proc.terminate()
        try:
            self.proc.wait(5)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(5)

    def tail(self, lines: int = 15) -> str:
        try:
            with open(self.log_path, "rb") as f:
                return b"\n".join(f.read().splitlines()[-lines:]).decode(errors="replace")
        except OSError:
            return ""


def report(rows: list[Row], relay: LossyRelay | None, args, markdown: bool) -> str:
    head = ("operation", "driver said", "vehicle holds", "s", "verdict")
    def cell(text: str) -> str:
        return text.replace("|", "\\|") if markdown else text
    lines = tables.render(head, [(cell(r.op), cell(r.said), cell(r.holds),
                                  "-" if r.seconds is None else f"{r.seconds:.1f}", r.verdict) for r in rows], markdown)
    if markdown:
        lines.append("")                                   # a Markdown table ends at a blank line
    answers = [r for r in rows if r.verdict != "-"]
    wrong = [r for r in answers if r.verdict == "wrong"]
    lines.append(f"{len(answers)} answers, {len(wrong)} wrong")
    if relay is not None:
        def share(way) -> str:
            total = way.passed + way.dropped
            return f"{way.dropped}/{total} frames dropped ({100.0 * way.dropped / max(1, total):.1f} %)"
        lines.append(f"(loss {args.loss:g} each way, seed {args.seed}, blackout {args.blackout:g} s: vehicle to "
                     f"driver {share(relay.down)}, driver to vehicle {share(relay.up)})")
    lines += [f"WRONG {r.op}: {r.why}" for r in wrong]
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    where = ap.add_mutually_exclusive_group(required=True)
    where.add_argument("--sitl", metavar="PATH", help="the arducopter SITL binary: started here, wiped")
    where.add_argument("--connect", action="store_true", help="use a SITL already running for --instance")
    where.add_argument("--sim", action="store_true",
                       help="the project's simulated vehicle in the SITL's place, on the same ports: checks the bench "
                            "itself, not the driver against real firmware")
    ap.add_argument("--loss", type=float, default=0.3, help="share of frames dropped each way (0.3)")
    ap.add_argument("--instance", type=int, default=0, help="SITL instance: ports 5760/5762 + 10*N")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--blackout", type=float, default=0.0,
                    help="seconds the link goes dark both ways during the mission upload and the parameter fetch")
    ap.add_argument("--shim", default=SHIM, help="LD_PRELOAD library keeping the SITL on 127.0.0.1")
    ap.add_argument("--defaults", help="the SITL's defaults (Tools/autotest/default_params/copter.parm)")
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--keep", action="store_true", help="keep the scratch folder (SITL log, driver tlogs)")
    tables.add_write_docs(ap)
    args = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)

    scratch = tempfile.mkdtemp(prefix="real-sitl-")
    for var in ("XDG_STATE_HOME", "XDG_CACHE_HOME"):       # the driver's per-user files go to the scratch folder
        os.environ[var] = scratch
    sitl = Sitl(args.sitl, args.instance, scratch, args.shim, args.defaults) if args.sitl else None
    atexit.register(lambda: sitl and sitl.stop())

    def on_signal(number, _frame):
        raise SystemExit(128 + number)                     # runs every finally below: the SITL is stopped
    for number in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(number, on_signal)

    relay = judge = bench = None
    started = time.monotonic()
    try:
        if sitl:
            sitl.start()
        elif args.sim:
            simulated = start_sim(args.instance, scratch)
            atexit.register(simulated.stop)
        serial0, serial1 = 5760 + 10 * args.instance, 5762 + 10 * args.instance
        try:
            relay = LossyRelay(serial0, free_udp_port(), args.loss, args.seed, TIMEOUT["connect"])
            with contextlib.redirect_stdout(sys.stderr):     # pymavlink says each refused connect on stdout
                judge = Judge(serial1, TIMEOUT["connect"])
        except OSError as exc:
            print(f"real_sitl: no SITL on 127.0.0.1:{serial0}/{serial1}: {exc}", file=sys.stderr)
            if sitl:
                print(sitl.tail(), file=sys.stderr)
            return 2
        bench = Bench(judge, relay, args, scratch)
        try:
            bench.run()
        except Exception as exc:  # noqa: BLE001 - the rows so far are printed, and the failure with them
            bench.add(Row("bench", f"stopped: {type(exc).__name__}: {exc}", "-", verdict="-"))
        if sitl and not sitl.alive():
            bench.add(Row("SITL", "-", f"exited early: {sitl.tail(3)}", verdict="-"))
        print(report(bench.rows, relay, args, tables.markdown(args.markdown)))
        print(f"(whole run {time.monotonic() - started:.0f} s)")
        return 1 if any(r.verdict == "wrong" for r in bench.rows) else 0
    finally:
        if bench is not None:
            bench.vehicle.close()
        for part in (judge, relay):
            if part is not None:
                part.close()
        if sitl:
            sitl.stop()
        if args.keep:
            print(f"(scratch kept: {scratch})", file=sys.stderr)
        else:
            shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    with tables.publishing(tables.variant("real_sitl", "--loss", "--blackout", "--sim", "--connect")):
        sys.exit(main())
