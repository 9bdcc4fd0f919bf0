"""Pilot chaos at scale: thousands of random pilot sequences under random link faults, on the simulated ArduCopter in
lockstep with the driver (driver.sim.chaos), every flight rule and every answer judged against the vehicle's truth.

    .venv/bin/python bench/chaos.py [--sequences 1000] [--workers 2] [--seed 1] [--markdown] [--write-docs]
    .venv/bin/python bench/chaos.py --sitl /work/sitl/ardupilot/build/sitl/bin/arducopter \
        --shim /work/sitl/bind_loopback.so --sequences 20          # the same judge on real SITL (chaos_sitl.py)

Hypothesis draws the sequences (up to 8 actions: arm, takeoff, sticks, Stop, Land, RTL, mission start, pause,
resume, mode change, motor test, level calibration, log download, link loss, reconnect, wait) and the faults (loss
0-40 % each way, latency 0-2 s each way, 10 % duplicates, outages as an action); a sequence that breaks a rule is
shrunk to the smallest that still does, and printed. Each worker runs its own search from its own seed. Exit 0
when no sequence broke a rule.

With ``--sitl PATH`` (or ``--connect``) the sequences fly on real ArduCopter 4.6.3 SITL instead, through
bench/lossy_relay.py, judged on SERIAL1 (bench/chaos_sitl.py, which this hands the arguments to).
"""
from __future__ import annotations

import argparse
import collections
import logging
import multiprocessing
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

import tables  # noqa: E402

from driver.sim.chaos import ACTIONS, Action, FaultSet, Flight  # noqa: E402


def search(args: tuple[int, int]) -> dict:
    """One worker's search: ``count`` sequences from Hypothesis seed ``seed``; what they came to."""
    seed, count = args
    logging.disable(logging.CRITICAL)
    from hypothesis import HealthCheck, given, seed as hseed, settings, strategies as st
    tally = collections.Counter()
    answers = collections.Counter()
    failures: list[str] = []
    flown = {"sim_seconds": 0.0, "actions": 0}

    faults = st.builds(FaultSet, loss=st.sampled_from((0.0, 0.1, 0.2, 0.3, 0.4)),
                       latency=st.sampled_from((0.0, 0.1, 0.5, 1.0, 2.0)), duplicate=st.sampled_from((0.0, 0.1)))
    actions = st.lists(st.builds(Action, st.sampled_from(ACTIONS), st.floats(0.0, 1.0), st.floats(0.2, 6.0)),
                       min_size=1, max_size=8)

    @hseed(seed)
    @settings(max_examples=count, deadline=None, database=None,
              suppress_health_check=list(HealthCheck))
    @given(vehicle_seed=st.integers(0, 1_000_000), fault=faults, sequence=actions)
    def fly(vehicle_seed, fault, sequence):
        flight = Flight(vehicle_seed, fault)
        violations = flight.fly(sequence)
        tally["sequences"] += 1
        flown["actions"] += len(sequence)
        flown["sim_seconds"] += flight.seconds
        for action, result in flight.answers:
            status = getattr(result, "status", None)
            answers[(action.kind, status.value if status else ("done" if result.ok else "not done"))] += 1
        if violations:
            raise AssertionError(f"{fault}, seed {vehicle_seed}: {Flight.describe(sequence)}\n" +
                                 "\n".join(str(v) for v in violations[:12]))
    try:
        fly()
    except AssertionError as exc:                         # Hypothesis shrank it: the smallest that still breaks
        failures.append(str(exc))
    except BaseExceptionGroup as group:                   # several distinct ones, each shrunk
        failures += [str(exc) for exc in group.exceptions]
    return dict(tally=tally, answers=answers, failures=failures, **flown)


def main() -> int:
    if "--sitl" in sys.argv or "--connect" in sys.argv:
        import chaos_sitl
        return chaos_sitl.main()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sequences", type=int, default=1000, help="sequences in all, split between the workers")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--markdown", action="store_true")
    tables.add_write_docs(ap)
    args = ap.parse_args()
    started = time.monotonic()
    share = [(args.seed * 1000 + i, args.sequences // args.workers + (i < args.sequences % args.workers))
             for i in range(args.workers)]
    with multiprocessing.get_context("spawn").Pool(args.workers) as pool:
        results = pool.map(search, share)
    tally, answers = collections.Counter(), collections.Counter()
    failures = []
    for r in results:
        tally.update(r["tally"])
        answers.update(r["answers"])
        failures += r["failures"]
    seconds = time.monotonic() - started
    sim = sum(r["sim_seconds"] for r in results)
    actions = sum(r["actions"] for r in results)
    kinds = sorted({k for k, _ in answers})
    statuses = sorted({s for _, s in answers})
    rows = [(k, *(str(answers[(k, s)] or "") for s in statuses)) for k in kinds]
    lines = [f"{tally['sequences']} sequences, {actions} actions, {sim / 60:.0f} min of flight simulated in "
             f"{seconds / 60:.1f} min ({args.workers} workers); rules broken: {len(failures)}", ""]
    lines += tables.render(("action", *statuses), rows, args.markdown)
    for failure in failures:
        lines += ["", "VIOLATION (shrunk):", failure]
    print("\n".join(lines))
    return 1 if failures else 0


if __name__ == "__main__":
    on_sitl = "--sitl" in sys.argv or "--connect" in sys.argv
    with tables.publishing("chaos_sitl" if on_sitl else "chaos"):
        sys.exit(main())
