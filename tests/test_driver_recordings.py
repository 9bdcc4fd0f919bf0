"""Recordings of a real ArduCopter 4.7 (tests/data/recordings/) replayed through the driver's telemetry path.

Each phase of the flight is checked against the ground station's own timeline (the recording's .events.txt),
not against what the driver makes of it: the mode and arming it shows, the altitude, every STATUSTEXT reason,
the vehicle's system id and home. The replay runs fast, and slower around the short phases (BRAKE lasts 3 s of
the recording) so that each one is seen however busy the machine is: every wait is for the state itself.
"""
from __future__ import annotations

import dataclasses
import math
import re

import pytest

from driver.vehicle import Vehicle, VehicleConfig

from recordings import FLIGHT, SIGNING, played  # noqa: E402

#: Where the recorded SITL vehicle stood (README.md: home -35.363261, 149.165230, 584 m).
HOME = (-35.363261, 149.165230, 584.0)



def statustexts(events: str) -> list[str]:
    """Every STATUSTEXT the ground station received, in order, as the recording's timeline lists them."""
    with open(events + ".events.txt", encoding="utf-8") as f:
        return [m.group(1) for m in re.finditer(r"RECV STATUSTEXT sev=\d '(.*)'$", f.read(), re.MULTILINE)]


def heartbeats(events: str) -> list[tuple[str, bool]]:
    """(mode, armed) of every HEARTBEAT the timeline shows, in order."""
    with open(events + ".events.txt", encoding="utf-8") as f:
        return [(m.group(1), m.group(2) == "True")
                for m in re.finditer(r"RECV HEARTBEAT mode=(\w+) armed=(\w+)", f.read())]


def not_finite(value, path: str = "state"):
    """The paths of every NaN or infinite number in a snapshot (messages and results are text)."""
    if isinstance(value, float):
        if not math.isfinite(value):
            yield path
    elif dataclasses.is_dataclass(value):
        for f in dataclasses.fields(value):
            if f.name not in ("messages", "results"):
                yield from not_finite(getattr(value, f.name), f"{path}.{f.name}")
    elif isinstance(value, tuple):
        for i, item in enumerate(value):
            yield from not_finite(item, f"{path}[{i}]")


@pytest.fixture
def replay_of():
    """A driver replaying a recording at 64x; started by the test, after it has set the speed it wants."""
    vehicles = []

    def make(recording: str) -> Vehicle:
        v = Vehicle(VehicleConfig(connection=recording + ".tlog", replay_speed=64, tlog_path=None))
        vehicles.append(v)
        return v

    yield make
    for v in vehicles:
        v.close()


def missing(expected: list[str], state) -> list[str]:
    """What of ``expected`` the pilot has not been shown (as the vehicle's messages, in that order)."""
    rest = iter([m.text for m in state.messages if m.source == "vehicle"])
    return [text for text in expected if not any(text == shown for shown in rest)]


def first(states, predicate):
    """The first (seconds into the recording, state) of ``states`` for which ``predicate(state)`` holds."""
    for t, _vehicle, s in states:
        if predicate(s):
            return t, s
    raise AssertionError(f"the recording ended first: {predicate}")


def test_flight_recording_phase_by_phase():
    """Every state the driver made of the recording, message by message on its own clock: the short phases
    (BRAKE lasts 3 s) are seen however busy the machine is."""
    # the timeline this test follows, as the ground station recorded it
    assert heartbeats(FLIGHT) == [("STABILIZE", False), ("GUIDED", False), ("GUIDED", True), ("BRAKE", True),
                                  ("LAND", True), ("LAND", False)]
    states = played(FLIGHT + ".tlog")

    _, s = first(states, lambda s: s.connected and s.mode)
    assert (s.mode, s.armed, s.system_id) == ("STABILIZE", False, 1), s

    _, s = first(states, lambda s: s.mode != "STABILIZE")               # GUIDED, disarmed: 35 s of refusals
    assert (s.mode, s.armed) == ("GUIDED", False), s

    t, s = first(states, lambda s: s.armed)
    assert s.mode == "GUIDED", s
    assert t > 40.0, t                                                    # armed after ~42 s, not before
    texts = [m.text for m in s.messages if m.source == "vehicle"]
    # every refusal reached the pilot with the vehicle's own reason
    for reason in ("Arm: Accels inconsistent", "Arm: AHRS: waiting for home", "Arm: Need Position Estimate",
                   "PreArm: Need Position Estimate"):
        assert reason in texts, texts
    assert s.home is not None, "HOME_POSITION came at 19 s"
    assert s.home.lat == pytest.approx(HOME[0], abs=1e-5) and s.home.lon == pytest.approx(HOME[1], abs=1e-5)
    assert s.home.alt == pytest.approx(HOME[2], abs=1.0)

    _, s = first(states, lambda s: s.altitude > 4.5)                     # the hover at 5 m, then 3 s of BRAKE
    assert s.mode == "GUIDED" and s.armed and s.flying, s
    assert s.altitude == pytest.approx(5.0, abs=0.5)
    _, s = first(states, lambda s: s.mode != "GUIDED")
    assert (s.mode, s.armed) == ("BRAKE", True), s
    assert s.flying and s.altitude == pytest.approx(5.0, abs=0.5), s
    _, s = first(states, lambda s: s.mode != "BRAKE")
    assert (s.mode, s.armed) == ("LAND", True), s

    _, s = first(states, lambda s: not s.armed)
    assert s.mode == "LAND", s
    for _, _, s in states:                                               # to the end of the recording
        pass
    expected = statustexts(FLIGHT)
    assert not missing(expected, s), missing(expected, s)
    assert (s.mode, s.armed, s.flying, s.system_id) == ("LAND", False, False, 1), s
    assert s.altitude == pytest.approx(0.0, abs=0.3)
    assert list(not_finite(s)) == []
    # the recorded vehicle is SITL's 3S pack, full (12.6 V, 100 %): 4.2 V a cell, nothing is low
    assert s.battery.voltage == pytest.approx(12.6, abs=0.05)
    assert s.battery.cells == 3 and s.battery.cell_voltage == pytest.approx(4.2, abs=0.02), s.battery
    assert not s.battery.low, s.battery


def test_signing_recording_modes_messages_and_no_position_before_a_fix(replay_of):
    """MAVLink 2 with signing: signed DO_SET_MODE changed the mode (GUIDED, then LOITER), the unsigned ones
    did nothing; the GPS never came up, so there is no position, whatever zeros the vehicle sent."""
    assert heartbeats(SIGNING) == [("STABILIZE", False), ("GUIDED", False), ("LOITER", False)]
    replay = replay_of(SIGNING)
    replay.replay.speed = 8
    replay.start()
    s = replay.wait_for(lambda s: s.connected and s.mode, 10)
    assert s is not None and (s.mode, s.armed, s.system_id) == ("STABILIZE", False, 1), s
    s = replay.wait_for(lambda s: s.mode != "STABILIZE", 10)
    assert s is not None and s.mode == "GUIDED", s
    s = replay.wait_for(lambda s: s.mode != "GUIDED", 10)
    assert s is not None and s.mode == "LOITER", s
    replay.replay.speed = 64
    expected = statustexts(SIGNING)
    # the end: every message shown, and home (HOME_POSITION came 1 s before the end)
    s = replay.wait_for(lambda s: replay.replay.finished and not missing(expected, s) and s.home is not None, 10)
    assert s is not None, (missing(expected, replay.state()), replay.state().home)
    assert (s.mode, s.armed, s.system_id) == ("LOITER", False, 1), s   # the last unsigned GUIDED was ignored
    assert s.link.mavlink_version == 2
    assert s.home.lat == pytest.approx(HOME[0], abs=1e-5) and s.home.lon == pytest.approx(HOME[1], abs=1e-5)
    assert s.gps.fix_type < 2
    # ArduPilot sends GLOBAL_POSITION_INT with lat = lon = 0 until it has a position (QGroundControl ignores
    # those): the pilot must not see the vehicle at 0° N 0° E
    assert s.position is None or (s.position.lat, s.position.lon) != (0.0, 0.0), s.position
    assert list(not_finite(s)) == []
