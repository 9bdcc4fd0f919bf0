"""ADS-B traffic: the closest-approach prediction (crossing, head-on, diverging, separated by height), contacts
fading and dropping, and an alert end to end from the simulated vehicle's traffic."""
from __future__ import annotations

import math
from types import SimpleNamespace

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.vehicle.state import GlobalPosition, Velocity
from driver.traffic.approach import AlertLimits, closest_approach
from driver.traffic.tracker import TrafficTracker

T = 30


def test_head_on_at_our_height_conflicts_and_says_when():
    a = closest_approach((2000.0, 0.0, 0.0), (-50.0, 0.0, 0.0))       # 2 km north, closing at 50 m/s
    assert a.conflict and a.conflict_in == pytest.approx(30.0)          # inside 500 m after 1500 m
    assert a.time == pytest.approx(40.0) and a.horizontal == pytest.approx(0.0, abs=1e-6)


def test_crossing_ahead_conflicts_only_when_it_passes_within_the_radius():
    near = closest_approach((1000.0, -1000.0, 0.0), (0.0, 40.0, 0.0))   # crosses 1 km north of us: no
    assert not near.conflict and near.horizontal == pytest.approx(1000.0)
    close = closest_approach((300.0, -1000.0, 50.0), (0.0, 40.0, 0.0))  # 300 m north, 50 m above: yes
    assert close.conflict and close.time == pytest.approx(25.0) and close.horizontal == pytest.approx(300.0)
    assert close.vertical == pytest.approx(50.0)


def test_diverging_and_height_separated_tracks_do_not_alert():
    away = closest_approach((600.0, 0.0, 0.0), (30.0, 0.0, 0.0))
    assert not away.conflict and away.time == 0.0 and away.horizontal == pytest.approx(600.0)
    above = closest_approach((1000.0, 0.0, 400.0), (-50.0, 0.0, 0.0))
    assert not above.conflict and above.horizontal == pytest.approx(0.0, abs=1e-6)
    descending = closest_approach((1000.0, 0.0, 400.0), (-50.0, 0.0, -10.0))   # comes down into our band
    assert descending.conflict


def test_beyond_the_horizon_or_with_other_limits():
    far = closest_approach((5000.0, 0.0, 0.0), (-50.0, 0.0, 0.0))       # would meet in 100 s
    assert not far.conflict and far.time == 60.0
    assert closest_approach((5000.0, 0.0, 0.0), (-50.0, 0.0, 0.0), AlertLimits(horizon=120.0)).conflict
    assert AlertLimits(horizontal=math.nan).problem()


def adsb(icao: int, lat: float, lon: float, alt_m: float, heading: float, speed: float):
    return mavlink.MAVLink_adsb_vehicle_message(icao, int(lat * 1e7), int(lon * 1e7), 0, int(alt_m * 1000),
                                               int(heading * 100), int(speed * 100), 0, f"SIM{icao}".encode(), 1, 1,
                                               511, 1200)


def test_contacts_fade_then_drop_and_stale_ones_never_alert():
    own = SimpleNamespace(position=GlobalPosition(40.0, -3.0, 600.0), velocity=Velocity())
    tracker = TrafficTracker()
    assert tracker.on_adsb_vehicle(adsb(77, 40.01, -3.0, 600.0, 180.0, 50.0), now=100.0)
    first = tracker.snapshot(100.5, own).contact(77)
    assert first.alert and first.callsign == "SIM77" and first.relative_alt == pytest.approx(0.0)
    assert first.bearing_deg == pytest.approx(0.0, abs=0.5) and 1100 < first.distance < 1120
    faded = tracker.snapshot(106.0, own).contact(77)
    assert faded.stale and not faded.alert
    assert tracker.snapshot(121.0, own).contacts == ()


def test_a_head_on_aircraft_from_the_simulator_raises_an_alert_and_a_passing_one_does_not(sim_factory,
                                                                                            vehicle_factory):
    sim = sim_factory()
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    state = v.wait_for(lambda s: s.connected and s.position is not None and s.readiness.prearm_ok, T)
    assert state is not None
    ground = sim.autopilot.home_alt
    sim.autopilot.add_aircraft(4242, north=2500.0, east=0.0, alt=ground + 50.0, heading=180.0, speed=60.0)
    sim.autopilot.add_aircraft(4343, north=-800.0, east=0.0, alt=ground + 50.0, heading=180.0, speed=60.0)
    state = v.wait_for(lambda s: s.traffic.contact(4242) is not None and s.traffic.contact(4343) is not None
                       and s.traffic.contact(4242).alert, T)
    assert state is not None, v.state().traffic
    assert not state.traffic.contact(4343).alert
    assert [c.icao for c in state.traffic.alerts] == [4242]
    assert v.wait_for(lambda s: any(m.text.startswith("Traffic SIM4242: ") and "metres above, closest" in m.text
                                    for m in s.messages), T)


def test_a_contacts_age_counts_from_when_the_receiver_last_heard_it():
    """ADSB_VEHICLE's tslc: the autopilot forwards what its receiver heard tslc seconds ago."""
    own = SimpleNamespace(position=GlobalPosition(40.0, -3.0, 600.0), velocity=Velocity())
    tracker = TrafficTracker()
    old = adsb(78, 40.01, -3.0, 600.0, 180.0, 50.0)
    old.tslc = 8
    assert tracker.on_adsb_vehicle(old, now=100.0)
    contact = tracker.snapshot(100.5, own).contact(78)
    assert contact.age == pytest.approx(8.5) and contact.stale and not contact.alert
    assert tracker.snapshot(112.5, own).contacts == ()            # 20.5 s since heard: dropped
