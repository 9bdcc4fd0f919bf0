"""The pack against the pilot's own thresholds, and how long it lasts at the present draw.

Pure functions of a :class:`~driver.vehicle.state.Battery` snapshot. ArduPilot's own battery failsafe is off by
default (BATT_FS_LOW_ACT 0, BATT_LOW_VOLT 0), and then BATTERY_STATUS says "OK" down to an empty pack: the
alarm here never trusts that. It takes the worst of the pilot's thresholds (per cell and in percent) and the
vehicle's own failsafe state.
"""
from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import ardupilotmega as mavlink

__all__ = ["Battery", "BatteryAlarm", "BatteryThresholds", "battery_alarm", "time_left"]

class BatteryAlarm(enum.IntEnum):
    """How the pack stands against the pilot's own thresholds (and the vehicle's failsafe): worse is higher."""
    UNKNOWN = 0          # nothing to judge by yet
    OK = 1
    WARNING = 2
    CRITICAL = 3


@dataclass(frozen=True)
class BatteryThresholds:
    """The pilot's own battery limits, per cell (loaded voltage) and in percent: whichever is crossed first
    counts. Judged by the driver (driver.vehicle.battery) whatever the vehicle's own battery failsafe says."""
    warning_cell: float = 3.6            # V a cell
    critical_cell: float = 3.5           # V a cell
    warning_percent: float = 30.0        # % remaining
    critical_percent: float = 15.0       # % remaining

    def problem(self) -> str | None:
        """Why these thresholds cannot be used, or None."""
        values = (self.warning_cell, self.critical_cell, self.warning_percent, self.critical_percent)
        if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in values):
            return "battery thresholds must be finite numbers"
        if not 2.5 <= self.critical_cell <= self.warning_cell <= 4.4:
            return "battery cell thresholds: 2.5 V <= critical <= warning <= 4.4 V"
        if not 0.0 <= self.critical_percent <= self.warning_percent <= 100.0:
            return "battery percent thresholds: 0 <= critical <= warning <= 100 %"
        return None


@dataclass(frozen=True)
class Battery:
    voltage: float | None = None         # V
    current: float | None = None         # A
    remaining: float | None = None       # percent 0..100
    remaining_estimated: bool = False    # True when derived from cell voltage
    cells: int = 0                       # 0: not known yet
    low: bool = False                    # the autopilot's battery failsafe state, else under 20 % or 3.7 V a cell
    cells_source: str = ""               # "configured", "vehicle" (per-cell voltages) or "inferred" (from voltage)
    charge_state: int = 0                # MAV_BATTERY_CHARGE_STATE from the autopilot, 0 when it sends none
    reported_remaining: float | None = None   # the autopilot's own percentage, None when it gives none
    consumed_mah: float | None = None    # BATTERY_STATUS.current_consumed, None when the vehicle does not count it
    thresholds: BatteryThresholds = field(default_factory=BatteryThresholds)   # what ``alarm`` is judged by
    capacity_mah: float | None = None    # the vehicle's BATT_CAPACITY, None until read (or 0: not set)
    draw: float | None = None            # A: the current averaged since liftoff, over DRAW_SMOOTHING s at most
    draw_at: float | None = None         # the vehicle's time (s since boot) of the draw's last sample
    draw_weight: float = 0.0             # s of flight the average stands for (up to about DRAW_SMOOTHING)

    def drawing(self, current: float | None, at: float | None, airborne: bool) -> dict:
        """The draw after a current of ``current`` A at the vehicle's time ``at``, as a pilot reads a fuel gauge:
        the average since the takeoff's climb ended, then over the last DRAW_SMOOTHING s or so (exponentially
        weighted), so one sample, a gust or a climb, moves it little. Not ``airborne`` (on the ground, taking off,
        landing) it follows the current; a restart (the clock going back) starts it again."""
        if current is None or not math.isfinite(current):
            return {}
        if not airborne or self.draw is None or at is None or self.draw_at is None or at < self.draw_at:
            return dict(draw=current, draw_at=at, draw_weight=DRAW_SEED)
        dt = at - self.draw_at
        past_weight = self.draw_weight * math.exp(-dt / DRAW_SMOOTHING)   # what the earlier draw still counts
        weight = past_weight + dt
        return dict(draw=(self.draw * past_weight + current * dt) / weight if weight > 0 else self.draw, draw_at=at,
                    draw_weight=weight)

    @property
    def cell_voltage(self) -> float | None:
        return None if self.voltage is None or self.cells <= 0 else self.voltage / self.cells

    @property
    def alarm(self) -> BatteryAlarm:
        """Against the pilot's thresholds, whatever the vehicle's failsafe says (driver.vehicle.battery)."""
        return battery_alarm(self)


_MIN_DRAW = 0.5            # A: below it (disarmed, on the bench) a time left means nothing
DRAW_SMOOTHING = 30.0      # s: the draw a time left is reckoned at is the current averaged over about this long
DRAW_SEED = 0.1            # s the first sample in the air stands for: the next seconds outweigh it


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
    """Seconds until the pack is down to ``reserve_percent`` (default: the critical threshold) at the smoothed
    draw (:attr:`Battery.draw`), or None when the vehicle gives no consumed charge, no current or no percentage.

    ArduPilot's percentage is (capacity - consumed) / capacity. With BATT_CAPACITY known the charge left is
    capacity * (1 - reserve) - consumed, which moves smoothly as the vehicle counts its mAh; without it,
    consumed * remaining / (100 - remaining), whose whole percent steps make it jump early in a flight."""
    remaining, consumed = b.reported_remaining, b.consumed_mah
    draw = b.draw if b.draw is not None else b.current
    if remaining is None or consumed is None or draw is None or draw < _MIN_DRAW:
        return None
    reserve = b.thresholds.critical_percent if reserve_percent is None else reserve_percent
    if b.capacity_mah:
        left_mah = b.capacity_mah * (1.0 - reserve / 100.0) - consumed
    elif remaining >= 100.0 or consumed <= 0.0:
        return None
    else:
        left_mah = consumed * max(0.0, remaining - reserve) / (100.0 - remaining)
    return 3.6 * max(0.0, left_mah) / draw
