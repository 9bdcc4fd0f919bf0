"""How long a test waits for something that must happen: its stated time times PATIENCE.

A wait's timeout is a safety net, never the verdict: no test here waits for something *not* to happen, and none
passes faster for waiting less. On 2 cores the suite's own 8 workers (and other work on the machine) starve a
process for seconds at a time, and a window or a driver that only lagged failed a wait sized for an idle machine.
The verdict of a test whose result depends on timing is reached on the driver's own clock instead (the manual
clock, the lockstep: tests/lockstep_fixtures.py); what is left here are waits for an event. A test that hangs still
ends at pytest-timeout's limit (pytest.ini).
"""
from __future__ import annotations

import functools
import os

PATIENCE = float(os.environ.get("UAV_TEST_PATIENCE", "3"))


def patient(seconds: float) -> float:
    """``seconds`` of a test's wait, stretched by PATIENCE."""
    return seconds * PATIENCE


def stretch_qtbot_waits() -> None:
    """pytest-qt's waits (waitUntil, waitSignal(s), waitCallback, waitExposed, waitActive) stretched by PATIENCE;
    their default (5 s) too."""
    from pytestqt.qtbot import QtBot

    def stretched(wait):
        @functools.wraps(wait)
        def call(self, *args, timeout=5000, **kwargs):
            if timeout and timeout > 0:
                timeout = int(timeout * PATIENCE)
            return wait(self, *args, timeout=timeout, **kwargs)
        return call

    for name in ("waitUntil", "waitSignal", "waitSignals", "waitCallback", "waitExposed", "waitActive"):
        wait = getattr(QtBot, name)
        if not getattr(wait, "_stretched", False):
            call = stretched(wait)
            call._stretched = True
            setattr(QtBot, name, call)


def patient_waits(drone):
    """``drone.wait_for(predicate, timeout)`` stretched by PATIENCE for this drone (a test's safety net), set on
    the instance: the driver's own callers of its class's method are not touched. Returns the drone."""
    wait_for = drone.wait_for

    @functools.wraps(wait_for)
    def call(predicate, timeout):
        return wait_for(predicate, patient(timeout))

    drone.wait_for = call
    return drone
