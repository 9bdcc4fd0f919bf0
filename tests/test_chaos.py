"""Pilot chaos: random sequences of what a pilot does under random link faults, against the simulated ArduCopter, on
the driver's own clock (driver.sim.lockstep), every answer and every flight rule judged against the vehicle's truth
after every tick (driver.sim.chaos).

Hypothesis draws the sequences and, when one breaks a rule, shrinks it to the smallest that still does. This is the
fast profile CI runs, derandomized (the same sequences every run: a suite that never needs a second try);
``bench/chaos.py`` flies thousands.
"""
from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, seed, settings, strategies as st

from driver.sim.chaos import ACTIONS, Action, FaultSet, Flight

#: The faults of the issue: latency up to 2 s, loss up to 40 %, duplicates; outages are an action ("link loss").
faults = st.builds(FaultSet, loss=st.sampled_from((0.0, 0.1, 0.3, 0.4)),
                   latency=st.sampled_from((0.0, 0.2, 1.0, 2.0)), duplicate=st.sampled_from((0.0, 0.1)))
actions = st.lists(st.builds(Action, st.sampled_from(ACTIONS), st.floats(0.0, 1.0), st.floats(0.2, 6.0)),
                   min_size=1, max_size=8)

FAST = settings(max_examples=6, deadline=None, database=None, print_blob=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def fly(seed: int, fault: FaultSet, sequence: list[Action]) -> None:
    flight = Flight(seed, fault)
    violations = flight.fly(sequence)
    told = "\n".join(f"  {a} -> {r}" for a, r in flight.answers)
    assert not violations, (f"{fault}, seed {seed}: {Flight.describe(sequence)}\n{told}\n" +
                            "\n".join(str(v) for v in violations[:10]))


@pytest.mark.parametrize("part", (0, 1))
def test_pilot_chaos_breaks_no_flight_rule_and_every_answer_is_true(part):
    """Two parts of the search, each with a fixed seed of its own (the same sequences every run), run side by side
    by the suite's workers."""
    @seed(20261208 + part)
    @FAST
    @given(vehicle_seed=st.integers(0, 10_000), fault=faults, sequence=actions)
    def check(vehicle_seed, fault, sequence):
        fly(vehicle_seed, fault, sequence)
    check()


def test_stop_during_a_mission_start_on_a_slow_radio_holds_on_the_drivers_clock():
    """The case that once left an airborne copter in STABILIZE, replayed exactly in lockstep."""
    fly(11, FaultSet(latency=1.5), [Action("mode", 0.0, 1.0), Action("mission", 0.0, 3.2), Action("stop", 0.0, 8.0)])


@pytest.mark.parametrize("seed_, fault, sequence", [
    # the radio slows to 2 s after its round trip was learnt: the first Land's late ACKs are counted as its own,
    # never taken for the second Land (which once answered "LAND" while the vehicle sat in GUIDED)
    (0, FaultSet(latency=2.0), [Action("land", 0.0, 1.0), Action("takeoff", 0.0, 2.0), Action("land", 0.0, 1.0)]),
    # a ground station started again after an arm, over the same slow radio: Stop answers from what it can know
    (0, FaultSet(latency=2.0), [Action("arm", 0.0, 1.0), Action("reconnect", 0.0, 2.0), Action("stop", 0.0, 1.0)]),
    # Stop pressed while the motors spin in a test the heartbeat does not show yet: the test is ended
    (0, FaultSet(), [Action("motor test", 0.0, 3.8), Action("motor test", 0.0, 5.1), Action("pause", 0.0, 1.1),
                     Action("stop", 0.0, 0.2), Action("motor test", 0.0, 0.2), Action("stop", 0.0, 3.0)]),
    # a calibration's retry right after a takeoff's arm was ACCEPTED, before the heartbeat showed it armed
    (0, FaultSet(latency=0.1), [Action("calibrate", 0.0, 0.75), Action("calibrate", 0.0, 0.84375),
                                Action("sticks", 0.0, 0.8125), Action("sticks", 1.0, 0.875), Action("takeoff", 0.0, 1.0)]),
], ids=["late-acks-of-a-replaced-land", "stop-after-a-restart", "stop-during-a-motor-test",
        "calibration-after-an-early-arm"])
def test_sequences_the_big_search_found_stay_right(seed_, fault, sequence):
    """Sequences ``bench/chaos.py`` shrank from thousands, kept as they flew."""
    fly(seed_, fault, sequence)
