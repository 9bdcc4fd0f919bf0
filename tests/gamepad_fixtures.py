"""Fixtures for gamepad tests: SDL's virtual joysticks (real SDL devices, no hardware, no display needed)."""
from __future__ import annotations

import pytest

from uavviewer.input.gamepad import VirtualPad


@pytest.fixture
def pad_factory():
    """Plug in virtual pads; each still attached is unplugged after the test."""
    pads = []

    def make(name: str = "Virtual gamepad", **kw) -> VirtualPad:
        p = VirtualPad(name, **kw)
        pads.append(p)
        return p

    yield make
    for p in pads:
        p.detach()


@pytest.fixture
def pad(pad_factory) -> VirtualPad:
    """A virtual game controller (SDL gives it the standard layout)."""
    return pad_factory("Virtual gamepad")


def setpoints_since(sim, n: int) -> list[tuple]:
    """SET_POSITION_TARGET_LOCAL_NED the simulated vehicle received after the first ``n``:
    (t, frame, mask, forward, right, down, yaw_rate)."""
    return list(sim.received_setpoints)[n:]


def reached(sim, n: int, forward=None, right=None, up=None, yaw_rate=None, tol: float = 2e-3) -> bool:
    """A setpoint with these values (body frame; ``up`` is -down) reached the vehicle after the first ``n``."""
    want = [(3, forward), (4, right), (5, None if up is None else -up), (6, yaw_rate)]
    return any(all(v is None or abs(r[i] - v) <= tol for i, v in want) for r in setpoints_since(sim, n))
