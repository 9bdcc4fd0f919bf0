"""Issue 21, problem 1: the battery is judged by the pilot's own thresholds (per cell and in percent), whatever
the vehicle's failsafe says; the window shows the alarm in colour, mAh used, a time-left estimate and a flight
timer.

The vehicle's battery failsafe is off by default in ArduPilot: BATTERY_STATUS then says "OK" down to an empty
pack, as in the reproduction (150 mAh pack, 11.40 V on 4 cells, 0 %, green).
"""
from __future__ import annotations

from collections import ChainMap

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.vehicle import telemetry
from driver.vehicle.battery import battery_alarm, time_left
from driver.vehicle.state import Battery, BatteryAlarm, BatteryThresholds, VehicleState
from uavviewer.telemetry.status_strip import ALARM_COLOURS
from uavviewer.telemetry.panel import BAD

from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)

ENC = mavlink.MAVLink(None)


def fold(state: VehicleState, msg) -> VehicleState:
    from dataclasses import replace
    return replace(state, **telemetry.fold(ChainMap({}, state.__dict__), msg))


def status(millivolts: int, remaining: int, consumed: int = -1, charge_state=mavlink.MAV_BATTERY_CHARGE_STATE_OK):
    return ENC.battery_status_encode(0, 0, 0, 2500, [millivolts] + [65535] * 9, 1500, consumed, -1, remaining,
                                     time_remaining=0, charge_state=charge_state)


def test_an_empty_pack_is_critical_though_the_vehicle_says_ok():
    state = VehicleState(battery=Battery(cells=4, cells_source="configured"))
    state = fold(state, ENC.sys_status_encode(0, 0, 0, 0, 11400, 1500, 0, 0, 0, 0, 0, 0, 0))
    state = fold(state, status(11400, 0, consumed=150))
    b = state.battery
    assert b.charge_state == mavlink.MAV_BATTERY_CHARGE_STATE_OK          # the vehicle's failsafe: "OK"
    assert b.alarm is BatteryAlarm.CRITICAL and b.consumed_mah == 150.0


@pytest.mark.parametrize("cell, percent, alarm", [
    (4.00, 80, BatteryAlarm.OK), (3.58, 80, BatteryAlarm.WARNING), (4.00, 25, BatteryAlarm.WARNING),
    (3.45, 80, BatteryAlarm.CRITICAL), (4.00, 10, BatteryAlarm.CRITICAL)])
def test_per_cell_or_percent_whichever_comes_first(cell, percent, alarm):
    b = Battery(voltage=cell * 3, cells=3, remaining=percent, reported_remaining=percent)
    assert battery_alarm(b) is alarm
    assert battery_alarm(Battery()) is BatteryAlarm.UNKNOWN


def test_the_vehicles_own_failsafe_still_counts():
    b = Battery(voltage=16.4, cells=4, remaining=90, charge_state=mavlink.MAV_BATTERY_CHARGE_STATE_CRITICAL)
    assert battery_alarm(b) is BatteryAlarm.CRITICAL


def test_time_left_from_the_charge_used_and_the_draw():
    # 1000 mAh used of a pack now at 50 %: 1000 mAh left, 35 % of it above the 15 % reserve
    b = Battery(current=10.0, reported_remaining=50.0, consumed_mah=1000.0)
    assert time_left(b) == pytest.approx(3.6 * 700.0 / 10.0)
    assert time_left(Battery(current=10.0, reported_remaining=50.0)) is None      # the vehicle counts no mAh


def test_thresholds_are_checked():
    assert BatteryThresholds().problem() is None
    assert BatteryThresholds(warning_cell=3.4, critical_cell=3.5).problem()
    assert BatteryThresholds(critical_percent=float("nan")).problem()


def test_a_small_pack_turns_the_window_red_in_flight(qtbot, sim_factory, vehicle_factory, window_factory):
    sim = sim_factory(battery_capacity_mah=150, speedup=8.0)
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    w = window_factory(vehicle, takeoff_altitude=3.0)
    qtbot.waitUntil(lambda: vehicle.state().battery.alarm is BatteryAlarm.OK, timeout=15000)
    assert vehicle.takeoff(3.0).result(timeout=60).ok
    qtbot.waitUntil(lambda: vehicle.state().battery.alarm is BatteryAlarm.CRITICAL, timeout=30000)
    strip = w.statusStrip
    qtbot.waitUntil(lambda: strip.battery.text().startswith("Battery CRITICAL"), timeout=3000)
    assert strip.colour(strip.battery) == ALARM_COLOURS[BatteryAlarm.CRITICAL]
    assert "mAh" in strip.battery.text()
    assert w.telemetry.color("battery") == BAD
    assert strip.flight_time.text() != "Flight 00:00"              # the timer runs while armed
    vehicle.land()


def test_the_pilots_thresholds_reach_the_driver(qtbot, sim, vehicle, window_factory, viewer_settings):
    from dataclasses import replace
    w = window_factory(vehicle)
    qtbot.waitUntil(lambda: vehicle.state().battery.alarm is BatteryAlarm.OK, timeout=15000)
    w.preferences.settings = replace(w.settings, battery_warning_percent=100.0, battery_critical_percent=99.5)
    w.preferences.apply()
    assert vehicle.state().battery.thresholds.warning_percent == 100.0
    qtbot.waitUntil(lambda: vehicle.state().battery.alarm is not BatteryAlarm.OK, timeout=5000)


def test_the_console_says_the_alarm_and_our_thresholds():
    from driver.console.console import battery_line
    s = VehicleState(battery=Battery(voltage=11.4, cells=4, remaining=0.0, current=15.0, consumed_mah=150.0,
                                     reported_remaining=0.0))
    line = battery_line(s)
    assert "150 mAh used" in line and "CRITICAL: land now" in line and "warning 3.6 V/cell or 30 %" in line
