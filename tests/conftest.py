"""Shared fixtures: a real simulated ArduCopter on a real TCP socket, and the real driver connected to it."""
from __future__ import annotations

import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from driver.sim import SimConfig, SimVehicle  # noqa: E402
from driver.sim.replay import ReplayVehicle  # noqa: E402
from driver.vehicle import Vehicle, VehicleConfig  # noqa: E402
from patience import patient_waits, stretch_qtbot_waits  # noqa: E402

stretch_qtbot_waits()

#: Simulated seconds per real second in tests: fast, yet slow enough for 20 Hz setpoints to matter.
SPEEDUP = 4.0
#: The pace of a takeoff that only sets a test up (the ``flying`` fixture): 8.7 sim s, 2.2 s at SPEEDUP.
TAKEOFF_SPEEDUP = 16.0
#: The pace of what a test only waits out once it has done all it does to the vehicle (a mission's way home,
#: its landing): what the vehicle did is checked after.
LAST_LEG_SPEEDUP = 32.0
#: A recording replayed (driver/sim/replay.py) at ten times its pace: a 1,392-parameter list in 0.07 s.
REPLAY_SPEEDUP = 10.0
#: s before an unechoed PARAM_SET goes again (MAVProxy's 1 s in flight): the sim on localhost answers in milliseconds,
#: and the sets that are never echoed (10 tries, then 5 reads by name) took 15 s each.
DRIVER_PARAM_RETRY = 0.25


@pytest.fixture(autouse=True, scope="session")
def _own_state_folder(tmp_path_factory):
    """What the program keeps per user (the signing timestamp, the parameter cache) goes to the test run's
    folder, not ~/.local or ~/.cache."""
    os.environ["XDG_STATE_HOME"] = str(tmp_path_factory.mktemp("state"))
    os.environ["XDG_CACHE_HOME"] = str(tmp_path_factory.mktemp("cache"))    # the parameter cache too


@pytest.fixture
def sim_factory():
    """Start simulated vehicles on ephemeral ports; all are stopped after the test."""
    sims = []

    def make(**overrides) -> SimVehicle:
        opts = dict(tcp_port=0, speedup=SPEEDUP, ready_after=1.0, seed=1)
        opts.update(overrides)
        sim = SimVehicle(SimConfig(**opts))
        sim.start()
        sims.append(sim)
        return sim

    yield make
    for sim in sims:
        sim.stop()


@pytest.fixture
def replay_factory():
    """Replay vehicles answering from a recording (tests/recordings.py names them, without ".tlog") on ephemeral
    ports; all are stopped after the test."""
    replays = []

    def make(recording: str, **options) -> ReplayVehicle:
        options.setdefault("speedup", REPLAY_SPEEDUP)
        replay = ReplayVehicle(recording + ".tlog", **options).start()
        replays.append(replay)
        return replay

    yield make
    for replay in replays:
        replay.stop()


@pytest.fixture
def sim(sim_factory) -> SimVehicle:
    return sim_factory()


@pytest.fixture
def vehicle_factory(tmp_path):
    """Start drivers (embedded MAVLinkServer) on given connections; all are closed after the test."""
    vehicles = []

    def make(connection: str, **overrides) -> Vehicle:
        opts = dict(connection=connection, tlog_path=str(tmp_path / f"flight{len(vehicles)}.tlog"),
                    command_timeout=1.0, param_retry=DRIVER_PARAM_RETRY)
        opts.update(overrides)
        v = patient_waits(Vehicle(VehicleConfig(**opts)).start())
        vehicles.append(v)
        return v

    yield make
    for v in vehicles:
        v.close()


@pytest.fixture
def vehicle(sim, vehicle_factory) -> Vehicle:
    """The driver connected to the simulated vehicle, with a heartbeat seen."""
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert v.wait_for(lambda s: s.connected, 10), "no heartbeat from the simulated vehicle"
    return v


@pytest.fixture
def flying(vehicle, sim):
    """The driver with the simulated vehicle hovering at 3 m in GUIDED. The takeoff is only how the test gets there
    (tests of their own fly it at SPEEDUP): the sim flies it at TAKEOFF_SPEEDUP, the test at its own pace again."""
    pace, sim.speedup = sim.speedup, max(sim.speedup, TAKEOFF_SPEEDUP)
    try:
        result = vehicle.takeoff(3.0).result(timeout=60)
    finally:
        sim.speedup = pace
        since = sim.truth().time
    assert result.ok, str(result)
    # Our heartbeat goes once a real second: 16 sim s apart meanwhile, more than FS_GCS_TIMEOUT (5 s). The test
    # starts once the vehicle has heard one at its own pace, so a GCS failsafe it enables counts from there.
    assert vehicle.wait_for(lambda s: any(t > since and kind == "HEARTBEAT" for t, kind, _ in list(sim.received_messages)),
                            10), "the vehicle heard no heartbeat from us after the takeoff"
    return vehicle
