"""The real window on the real driver and simulated ArduCopter in lockstep (driver.sim.lockstep): one hand-driven
clock, the sim's faulty link between them, no thread and no socket.

The window polls the driver after every step of it, so it is shown every state the driver publishes, whatever the
machine's load: a test that must see the window *during* something (a download's progress, each motor of a
sequence) sees it, where over real sockets a starved window only polled the end. Waits are bounded in the
vehicle's seconds, never in real ones.
"""
from __future__ import annotations

import pytest
from PyQt5.QtWidgets import QApplication

from driver.sim.lockstep import DRIVER_EVERY, Lockstep

from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)


class Steps:
    """A lockstep flight and the window on its driver, advanced together by the test."""

    def __init__(self, lockstep: Lockstep, window) -> None:
        self.lockstep = lockstep
        self.window = window

    @property
    def vehicle(self):
        return self.lockstep.vehicle

    @property
    def autopilot(self):
        return self.lockstep.autopilot

    def tick(self) -> None:
        """One tick of the vehicle; after each step of the driver, the window reads its state and handles its
        events (the answers of commands, signals queued by what it was shown)."""
        self.lockstep.tick()
        if self.lockstep.ticks % DRIVER_EVERY == 0:
            self.window.adapter.poll()
            QApplication.processEvents()

    def run(self, seconds: float) -> None:
        for _ in range(max(1, round(seconds / 0.02))):
            self.tick()

    def take_off(self, altitude: float = 3.0) -> None:
        """What the ``flying`` fixture does over a socket: hovering at ``altitude`` in GUIDED."""
        done = self.vehicle.takeoff(altitude)
        self.until(done.done, 60, "the takeoff")
        assert done.result().ok, str(done.result())

    def until(self, predicate, seconds: float, what: str = "") -> None:
        """Advance until ``predicate()`` holds, at most ``seconds`` of the vehicle's time."""
        for _ in range(max(1, round(seconds / 0.02))):
            if predicate():
                return
            self.tick()
        assert predicate(), f"not within {seconds} s of the vehicle's time: {what or predicate}"


@pytest.fixture
def lockstep_window(window_factory, tmp_path):  # noqa: F811
    """``make(seed, uplink=..., downlink=..., driver={...}, window={...}, **sim)``: a Steps whose window is already
    on the connected vehicle (its first heartbeat and the start of its parameters heard)."""
    made = []

    def make(seed: int = 1, window: dict | None = None, driver: dict | None = None, ready_after: float = 1.0,
             build=None, **options) -> Steps:
        """``build(vehicle)``: the window, if not window_factory's with ``window``'s options."""
        lockstep = Lockstep(seed, driver={"param_cache": str(tmp_path / "params"), **(driver or {})},
                            ready_after=ready_after, **options)
        made.append(lockstep)
        steps = Steps(lockstep, None)
        lockstep.run(0.2)
        steps.window = build(lockstep.vehicle) if build else window_factory(lockstep.vehicle, **(window or {}))
        steps.window.adapter.stop()           # polled by the steps, not by a real-time timer
        steps.until(lambda: steps.vehicle.state().connected, 10, "the first heartbeat")
        return steps

    yield make
    for lockstep in made:
        lockstep.close()
