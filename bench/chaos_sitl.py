"""Pilot chaos against real firmware: random pilot sequences flown on ArduCopter 4.6.3 SITL through a faulty link,
judged on a second, loss-free link (SITL's SERIAL1) with plain pymavlink.

    .venv/bin/python bench/chaos_sitl.py --sitl /work/sitl/ardupilot/build/sitl/bin/arducopter \\
        --shim /work/sitl/bind_loopback.so [--sequences 20] [--seed 1] [--markdown] [--write-docs]

Each sequence: a fresh driver (the viewer's own ``Vehicle``) through bench/lossy_relay.py with its own faults (loss
0-40 % each way, latency 0-2 s each way, duplicates), a 5-item mission uploaded through it, then up to 8 of the
pilot's actions (the same as bench/chaos.py's: arm, takeoff, sticks, Stop, Land, RTL, mission start, pause, resume,
mode change, motor test, level calibration, log download, link loss, reconnect, wait), each followed by a few
seconds of flight. What the vehicle does is read on SERIAL1 every 50 ms, and broken if:

* it is ever in a mode that takes its throttle from a stick (STABILIZE, ACRO, SYSTEMID, TURTLE) while in the air,
  or disarms in the air (nothing but this ground station commands it here);
* the driver says it is surely on the ground while it has been in the air longer than the link's latency and a
  few heartbeats;
* an answer disagrees with what the vehicle did (driver.sim.chaos.wrong_answer), or a motor test or calibration is
  said accepted while the vehicle was armed or in the air.

Between sequences the judge lands the vehicle and waits for it to disarm. Exit 0 when nothing broke.
"""
from __future__ import annotations

import argparse
import atexit
import contextlib
import logging
import os
import random
import shutil
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from pymavlink.dialects.v20 import ardupilotmega as mavlink  # noqa: E402

from lossy_relay import LossyRelay, free_udp_port  # noqa: E402
from mission_start import mission  # noqa: E402
from real_sitl import SHIM, Sitl  # noqa: E402
from sitl_judge import Judge  # noqa: E402
import tables  # noqa: E402

from driver import Vehicle, VehicleConfig  # noqa: E402
from driver.sim.chaos import ACTIONS, MODES, Action, FaultSet, Violation, wrong_answer  # noqa: E402
from driver.vehicle.safety import MANUAL_THROTTLE_MODES  # noqa: E402

SETTLE = 45.0                   # s after the last action for the answers still awaited
SEEN_AIRBORNE = 4.0             # s in the air beyond the latency before the driver must know it
#: s the judge's link may hear the vehicle later than the driver's: ArduCopter sends each link's 1 Hz HEARTBEAT
#: from its own timer, so the judge's (SERIAL1) can show a new mode up to a heartbeat after the driver's (SERIAL0)
HEARTBEAT_LAG = 1.2


class SitlFlight:
    def __init__(self, judge: Judge, serial0: int, seed: int, fault: FaultSet, scratch: str) -> None:
        self.judge, self.serial0, self.seed, self.fault, self.scratch = judge, serial0, seed, fault, scratch
        self.violations: list[Violation] = []
        self.answers: list = []
        self.truth: list = []
        self._stop = threading.Event()
        self._asked: list = []
        self._answered_at: dict = {}          # id(future) -> when the judge first saw it answered
        self._airborne_since: float | None = None
        self._started = time.monotonic()

    # -- the flight ------------------------------------------------------------------------------------------
    def fly(self, actions: list[Action]) -> list[Violation]:
        f = self.fault
        self.relay = LossyRelay(self.serial0, free_udp_port(), f.loss, self.seed, latency=f.latency,
                                duplicate=f.duplicate)
        self.vehicle = self._driver()
        watcher = threading.Thread(target=self._watch, daemon=True)
        watcher.start()
        try:
            if self.vehicle.wait_for(lambda s: s.connected and s.home is not None and s.in_air is False, 120) is None:
                self._violate("setup", "the driver never saw the vehicle ready on the ground")
                return self.violations
            upload = self.vehicle.upload_plan(mission()).result(180)
            if not upload.result.ok:
                self._violate("setup", f"mission upload: {upload.result}")
            for action in actions:
                self._do(action)
                self._run(action.wait, sticks=action if action.kind == "sticks" else None)
            self._run(SETTLE, until=lambda: all(a[2].done() for a in self._asked if a[0].kind != "log download"))
            self._run(HEARTBEAT_LAG + 0.3)             # the last answers judged once the judge's link caught up
            for action, name, future, _ in self._asked:
                if not future.done() and action.kind != "log download":    # a log may take minutes: not a command
                    self._violate("no answer", f"{name}: nothing said {SETTLE:g} s after the last action")
        finally:
            self._stop.set()
            watcher.join(2)
            self.vehicle.close()
            self.relay.close()
        return self.violations

    def _driver(self) -> Vehicle:
        return Vehicle(VehicleConfig(connection=f"udpin:127.0.0.1:{self.relay.udp_port}", param_cache=None,
                                     tlog_path=None)).start()

    def _do(self, action: Action) -> None:
        v, kind, x = self.vehicle, action.kind, action.value
        mode = MODES[int(x * len(MODES)) % len(MODES)]
        call = {"arm": v.arm, "takeoff": lambda: v.takeoff(2.0 + 4.0 * x), "stop": v.stop, "land": v.land,
                "rtl": v.return_to_launch, "mission": v.start_mission, "pause": v.pause_mission,
                "resume": v.resume_mission, "mode": lambda: v.set_mode(mode),
                "motor test": lambda: v.setup.motor_test(1 + int(x * 4) % 4, throttle_pct=5, seconds=1,
                                                         propellers_removed=True),
                "calibrate": v.calibrate_level,
                "log download": lambda: v.logs.download_latest(os.path.join(self.scratch, "download.bin"))}.get(kind)
        if kind == "link loss":
            self.relay.blackout(0.5 + 6.0 * x)
        elif kind == "reconnect":
            self.vehicle.close()
            port = free_udp_port()
            self.relay.retarget(port)
            self.vehicle = Vehicle(VehicleConfig(connection=f"udpin:127.0.0.1:{port}", param_cache=None,
                                                 tlog_path=None)).start()
        elif call is not None:
            self._asked.append((action, f"mode {mode}" if kind == "mode" else kind, call(), len(self.truth)))

    def _run(self, seconds: float, until=None, sticks: Action | None = None) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            if sticks is not None:
                x = sticks.value
                self.vehicle.set_velocity(2 * x - 1, 1 - 2 * x, 0.5 - x, 0.3 * (x - 0.5))
            self._check()
            if until is not None and until():
                return
            time.sleep(0.1)

    # -- the truth ---------------------------------------------------------------------------------------------
    def _watch(self) -> None:
        j = self.judge
        while not self._stop.is_set():
            ess = j.latest("EXTENDED_SYS_STATE", 2.0)
            mc = j.latest("MISSION_CURRENT", 2.0)
            landed = ess is not None and ess.landed_state == mavlink.MAV_LANDED_STATE_ON_GROUND
            alt = j.altitude or 0.0
            now = time.monotonic() - self._started
            self.truth.append((now, j.mode, bool(j.armed), landed, alt,
                               mc is not None and getattr(mc, "mission_state", 0) == mavlink.MISSION_STATE_ACTIVE))
            if len(self.truth) > 1:
                before = self.truth[-2]
                if j.mode in MANUAL_THROTTLE_MODES and not landed:
                    self._violate("throttle mode", f"{j.mode} in the air, {alt:.1f} m up")
                if before[2] and not j.armed and not before[3] and alt > 1.0:
                    self._violate("disarm in the air", f"disarmed {alt:.1f} m up in {j.mode}")
            self._stop.wait(0.05)

    def _check(self) -> None:
        if not self.truth:
            return
        now, mode, armed, landed, alt, _ = self.truth[-1]
        if landed:
            self._airborne_since = None
        elif self._airborne_since is None:
            self._airborne_since = now
        elif now - self._airborne_since > self.fault.latency + SEEN_AIRBORNE \
                and not self.vehicle.state().may_be_airborne and self.vehicle.state().connected:
            self._violate("airborne unseen", f"{alt:.1f} m up in {mode} for {now - self._airborne_since:.0f} s, "
                          "the driver says surely on the ground")
        for asked in list(self._asked):
            action, name, future, since = asked
            if future.done() and asked not in [a for a, _ in self.answers]:
                answered = self._answered_at.setdefault(id(future), now)
                if now < answered + HEARTBEAT_LAG:
                    continue                    # what the judge's link shows of that moment is still coming
                result = future.result()
                result = getattr(result, "result", result)
                self.answers.append((asked, result))
                window = [t for t in self.truth[since:] if t[0] <= answered + HEARTBEAT_LAG]
                wrong = wrong_answer(action.kind, name, result, window)
                if not wrong and action.kind in ("motor test", "calibrate") and getattr(result, "ok", False) and \
                        window and (window[0][2] or not window[0][3]):     # as asked: a motor test arms it itself
                    wrong = "said accepted while the vehicle was armed or in the air"
                if wrong:
                    self._violate("wrong answer", f"{name}: {result}: {wrong}")

    def _violate(self, rule: str, detail: str) -> None:
        if not any(v.rule == rule for v in self.violations[-3:]):      # one line per rule broken, not per poll
            self.violations.append(Violation(time.monotonic() - self._started, rule, detail))


def land_and_wait(judge: Judge) -> None:
    """Back on the ground, disarmed, in STABILIZE: where every sequence starts."""
    if judge.armed:
        judge.command(mavlink.MAV_CMD_DO_SET_MODE, 1, 9)
        judge.wait(lambda: judge.armed is False, 120)
    judge.command(mavlink.MAV_CMD_DO_SET_MODE, 1, 0)


def draw(rng: random.Random) -> tuple[FaultSet, list[Action]]:
    fault = FaultSet(loss=rng.choice((0.0, 0.1, 0.2, 0.3, 0.4)), latency=rng.choice((0.0, 0.2, 0.5, 1.0, 2.0)),
                     duplicate=rng.choice((0.0, 0.1)))
    return fault, [Action(rng.choice(ACTIONS), rng.random(), rng.uniform(0.5, 8.0)) for _ in range(rng.randint(2, 8))]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    where = ap.add_mutually_exclusive_group(required=True)
    where.add_argument("--sitl", metavar="PATH", help="the arducopter SITL binary: started here, wiped")
    where.add_argument("--connect", action="store_true", help="a SITL already running for --instance")
    ap.add_argument("--sequences", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--instance", type=int, default=0)
    ap.add_argument("--shim", default=SHIM)
    ap.add_argument("--defaults")
    ap.add_argument("--markdown", action="store_true")
    tables.add_write_docs(ap)
    args = ap.parse_args()
    logging.basicConfig(level=logging.CRITICAL)
    scratch = tempfile.mkdtemp(prefix="chaos-sitl-")
    for var in ("XDG_STATE_HOME", "XDG_CACHE_HOME"):
        os.environ[var] = scratch
    sitl = Sitl(args.sitl, args.instance, scratch, args.shim, args.defaults) if args.sitl else None
    atexit.register(lambda: sitl and sitl.stop())
    serial0, serial1 = 5760 + 10 * args.instance, 5762 + 10 * args.instance
    rng = random.Random(args.seed)
    rows, broken = [], []
    started = time.monotonic()
    judge = None
    try:
        if sitl:
            sitl.start()
        keeper = LossyRelay(serial0, free_udp_port(), 0.0, 0)     # SERIAL1 listens once SERIAL0 has a client
        with contextlib.redirect_stdout(sys.stderr):
            judge = Judge(serial1, 60)
        keeper.close()
        judge.wait(lambda: judge.prearm_ok, 120)
        for n in range(1, args.sequences + 1):
            fault, actions = draw(rng)
            land_and_wait(judge)
            flight = SitlFlight(judge, serial0, args.seed * 1000 + n, fault, scratch)
            t0 = time.monotonic()
            violations = flight.fly(actions)
            told = ", ".join(f"{a[0].kind}: {getattr(r, 'status', None) and r.status.value or ('done' if r.ok else 'not done')}"
                             for a, r in flight.answers)
            rows.append((str(n), f"{fault.loss:.0%} / {fault.latency:g} s / {fault.duplicate:.0%}",
                         " · ".join(a.kind for a in actions), told, f"{time.monotonic() - t0:.0f}",
                         str(len(violations))))
            broken += [f"sequence {n} ({fault}; {'; '.join(map(str, actions))}): {v}" for v in violations]
            print(f"sequence {n}: {len(violations)} broken; {told}", file=sys.stderr, flush=True)
    finally:
        if judge is not None:
            land_and_wait(judge)
            judge.close()
        if sitl:
            sitl.stop()
        shutil.rmtree(scratch, ignore_errors=True)
    lines = tables.render(("#", "loss / latency / dup", "actions", "answers", "s", "broken"), rows, args.markdown)
    lines += ["", f"{len(rows)} sequences on ArduCopter 4.6.3 SITL, {len(broken)} rules broken "
                  f"(whole run {(time.monotonic() - started) / 60:.0f} min)"] + [f"BROKEN {b}" for b in broken]
    print("\n".join(lines))
    return 1 if broken else 0


if __name__ == "__main__":
    with tables.publishing("chaos_sitl"):
        sys.exit(main())
