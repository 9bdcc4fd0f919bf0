"""The pack against the pilot's own thresholds, and how long it lasts at the present draw.

Pure functions of a :class:`~driver.vehicle.state.Battery` snapshot. ArduPilot's own battery failsafe is off by
default (BATT_FS_LOW_ACT 0, BATT_LOW_VOLT 0), and then BATTERY_STATUS says "OK" down to an empty pack: the
alarm here never trusts that. It takes the worst of the pilot's thresholds (per cell and in percent) and the
vehicle's own failsafe state.
"""
from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .state import Battery, BatteryAlarm, BatteryThresholds

__all__ = ["battery_alarm", "time_left", "BatteryThresholds"]

_MIN_DRAW = 0.5            # A: below it (disarmed, on the bench) a time left means nothing


def battery_alarm(b: Battery) -> BatteryAlarm:
    """How ``b`` stands against ``b.thresholds`` and the vehicle's own failsafe state: worse is higher."""
    t = b.thresholds
    cell = b.cell_voltage
    if cell is None and b.remaining is None and b.charge_state < mavlink.MAV_BATTERY_CHARGE_STATE_LOW:
        return BatteryAlarm.UNKNOWN
    alarm = BatteryAlarm.OK
    if (cell is not None and cell <= t.warning_cell) or (b.remaining is not None and b.remaining <= t.warning_percent):
        alarm = BatteryAlarm.WARNING
    if (cell is not None and cell <= t.critical_cell) or (b.remaining is not None
                                                          and b.remaining <= t.critical_percent):
        alarm = BatteryAlarm.CRITICAL
    if b.charge_state >= mavlink.MAV_BATTERY_CHARGE_STATE_CRITICAL:      # CRITICAL, EMERGENCY, FAILED, UNHEALTHY
        alarm = BatteryAlarm.CRITICAL
    elif b.charge_state == mavlink.MAV_BATTERY_CHARGE_STATE_LOW:
        alarm = max(alarm, BatteryAlarm.WARNING)
    return alarm


def time_left(b: Battery, reserve_percent: float | None = None) -> float | None:
    """Seconds until the pack is down to ``reserve_percent`` (default: the critical threshold) at the present
    current, or None when the vehicle gives no consumed charge, no current or no percentage of its own.

    ArduPilot's percentage is (capacity - consumed) / capacity, so the charge left is
    consumed * remaining / (100 - remaining) mAh, whatever BATT_CAPACITY is."""
    remaining, consumed, current = b.reported_remaining, b.consumed_mah, b.current
    if remaining is None or consumed is None or current is None or current < _MIN_DRAW:
        return None
    if remaining >= 100.0 or consumed <= 0.0:
        return None
    reserve = b.thresholds.critical_percent if reserve_percent is None else reserve_percent
    usable = max(0.0, remaining - reserve)
    left_mah = consumed * usable / (100.0 - remaining)
    return 3.6 * left_mah / current
