"""The telemetry reducer: one MAVLink message and the current state in, the fields that change out.

Pure: no I/O, no clock, no lock, no memory of its own (what it must remember, such as the battery's cell
count or whether the autopilot reports its pre-arm check, lives in the state itself). That makes it easy
to test and to fuzz, and the driver folds only the newest message of each kind per read.

Values the autopilot cannot have meant (NaN, infinity, angles or positions outside their physical range,
"unknown" markers such as 0xFFFF) never reach the state: an unknown optional value becomes None, and a
message whose core values are invalid is dropped whole (its fields keep their last good value) and counted
in ``rejected_values``, so the pilot sees old-but-real or unknown, never a made-up number.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core import frames
from .state import (
    Attitude, Battery, Boot, Environment, GlobalPosition, Gps, LandedState, LocalPosition, Readiness, Velocity,
)

__all__ = ["TELEMETRY", "fold", "infer_cells", "COPTER_MODE_NAMES"]

COPTER_MODE_NAMES: dict[int, str] = dict(mavutil.mode_mapping_acm)

_PREARM_BIT = mavlink.MAV_SYS_STATUS_PREARM_CHECK
_EKF_NEEDED = (mavlink.EKF_ATTITUDE | mavlink.EKF_VELOCITY_HORIZ | mavlink.EKF_POS_HORIZ_ABS
               | mavlink.EKF_PRED_POS_HORIZ_ABS)
_MAX_RATE = 50.0           # rad/s: no multicopter turns faster
_MAX_ALT = 20000.0         # m: above any copter's ceiling
_MIN_ALT = -1000.0
_MAX_SPEED = 200.0         # m/s
LIPO_CELL_MAX = 4.35       # V, a high-voltage LiPo cell fully charged: the cell count is at least voltage / this


def _ok(*values: float) -> bool:
    return all(isinstance(v, (int, float)) and math.isfinite(v) for v in values)


def _within(value, low: float, high: float) -> bool:
    return _ok(value) and low <= value <= high


def _rejected(view: Mapping) -> dict:
    return {"rejected_values": view["rejected_values"] + 1}


def _airborne(view: Mapping) -> bool:
    """Armed and in the air between its takeoff and its landing (EXTENDED_SYS_STATE IN_AIR, or armed on a firmware
    that does not say): the draw a time left is reckoned at is averaged only then, a climb out being no cruise."""
    return bool(view["armed"]) and view["landed_state"] in (LandedState.IN_AIR, LandedState.UNDEFINED)


def infer_cells(voltage: float) -> int:
    """The fewest LiPo cells that can give ``voltage``: a 12.6 V pack is 3S, 16.8 V 4S, 14.0 V 4S."""
    return max(1, math.ceil(voltage / LIPO_CELL_MAX - 1e-9))


# -- one fold per message type: (view of the current state, message) -> changes ------------------------
def fold_heartbeat(view: Mapping, m) -> dict:
    """The autopilot's HEARTBEAT (the caller has checked it comes from the autopilot)."""
    mode = COPTER_MODE_NAMES.get(m.custom_mode, f"MODE({m.custom_mode})")
    return dict(mode=mode, armed=bool(m.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED), vehicle_type=m.type,
                system_status=m.system_status)


def fold_sys_status(view: Mapping, m) -> dict:
    r: Readiness = view["readiness"]
    reported = r.prearm_reported or bool(m.onboard_control_sensors_present & _PREARM_BIT)
    prearm = bool(m.onboard_control_sensors_health & _PREARM_BIT) if reported else r.ekf_ok and r.gps_ok
    voltage = None if m.voltage_battery in (0, 0xFFFF) else m.voltage_battery / 1000.0
    current = None if m.current_battery < 0 else m.current_battery / 100.0
    remaining = None if not 0 <= m.battery_remaining <= 100 else float(m.battery_remaining)
    b: Battery = view["battery"]
    return dict(readiness=replace(r, prearm_ok=prearm, prearm_reported=reported),
                battery=_battery(b, voltage, current, remaining, b.charge_state, None, at=view["boot"].seconds,
                                 airborne=_airborne(view)))


def fold_battery_status(view: Mapping, m) -> dict:
    cells = [v for v in m.voltages if v not in (0xFFFF, 0)]
    b: Battery = view["battery"]
    voltage = sum(cells) / 1000.0 if cells else None
    per_cell = len(cells) if len(cells) > 1 else None          # one entry is the whole pack (ArduPilot)
    if voltage is None or (len(cells) == 1 and b.voltage is not None):
        voltage = b.voltage                                     # SYS_STATUS has the total already
    current = None if m.current_battery < 0 else m.current_battery / 100.0
    remaining = None if not 0 <= m.battery_remaining <= 100 else float(m.battery_remaining)
    charge_state = getattr(m, "charge_state", 0) or b.charge_state   # MAVLink 2 extension: 0 = not sent
    consumed = float(m.current_consumed) if m.current_consumed >= 0 else None
    return dict(battery=_battery(b, voltage, current if current is not None else b.current,
                                 remaining if remaining is not None else b.reported_remaining,
                                 charge_state, per_cell, consumed, at=view["boot"].seconds,
                                 airborne=_airborne(view)))


def _battery(b: Battery, voltage, current, remaining, charge_state: int, cells_reported: int | None,
             consumed_mah: float | None = None, at: float | None = None, airborne: bool = False) -> Battery:
    """The pack as the autopilot reports it; percent estimated from the cell voltage only when it gives none.

    The cell count comes from the vehicle (per-cell voltages) or, failing that, from the first voltage heard
    (a pack is not always a Solo's 4S: ArduPilot SITL's is 3S). "Low" is the autopilot's own battery
    failsafe state when it sends one (BATTERY_STATUS.charge_state), else 20 % or 3.7 V a cell (MAVProxy).
    ``alarm`` (derived) is the pilot's own thresholds (``b.thresholds``), whatever the vehicle's failsafe says;
    ``consumed_mah`` stays what it was unless BATTERY_STATUS says; the averaged draw follows the current at the
    vehicle's time ``at`` (its time_boot_ms, :class:`~driver.vehicle.state.Boot`) while ``airborne``.
    """
    cells, source = b.cells, b.cells_source
    if cells_reported and source != "configured":
        cells, source = cells_reported, "vehicle"
    elif not cells and voltage is not None:
        cells, source = infer_cells(voltage), "inferred"
    estimated = remaining is None and voltage is not None and cells > 0
    shown = round(frames.battery_percent_from_cell(voltage / cells), 1) if estimated else remaining
    if charge_state >= mavlink.MAV_BATTERY_CHARGE_STATE_OK:
        low = charge_state >= mavlink.MAV_BATTERY_CHARGE_STATE_LOW
    else:
        low = (shown is not None and shown < 20.0) or (voltage is not None and cells > 0 and voltage / cells < 3.7)
    drawing = dict(draw=b.draw, draw_at=b.draw_at, draw_weight=b.draw_weight)
    drawing.update(b.drawing(current, at, airborne))
    return Battery(voltage, current, shown, estimated, cells, low, source, charge_state, remaining,
                   consumed_mah=b.consumed_mah if consumed_mah is None else consumed_mah, thresholds=b.thresholds,
                   capacity_mah=b.capacity_mah, **drawing)


def fold_attitude(view: Mapping, m) -> dict:
    if not (_within(m.roll, -math.pi - 0.01, math.pi + 0.01) and _within(m.pitch, -math.pi - 0.01, math.pi + 0.01)
            and _within(m.yaw, -2 * math.pi, 2 * math.pi)
            and all(_within(r, -_MAX_RATE, _MAX_RATE) for r in (m.rollspeed, m.pitchspeed, m.yawspeed))):
        return _rejected(view)
    return dict(attitude=Attitude(m.roll, m.pitch, m.yaw, m.rollspeed, m.pitchspeed, m.yawspeed),
                **_clock(view, m))


def fold_global_position(view: Mapping, m) -> dict:
    lat, lon, alt, rel = m.lat * 1e-7, m.lon * 1e-7, m.alt * 1e-3, m.relative_alt * 1e-3
    if m.lat == 0 and m.lon == 0:                 # ArduPilot's "no position yet" (QGroundControl ignores it too)
        return _clock(view, m)
    if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0 and _MIN_ALT <= alt <= _MAX_ALT
            and _MIN_ALT <= rel <= _MAX_ALT):
        return _rejected(view)
    changes = dict(position=GlobalPosition(lat, lon, alt), altitude=rel,
                   velocity=Velocity(m.vx / 100.0, m.vy / 100.0, m.vz / 100.0), **_clock(view, m))
    if 0 <= m.hdg < 36000:
        changes["heading_deg"] = m.hdg / 100.0
    home: GlobalPosition | None = view["home"]
    if home is not None:                           # positions are from home, never from the EKF origin
        north, east = frames.offset_ned(home.lat, home.lon, lat, lon)
        changes["local"] = LocalPosition(north, east, -rel)
    return changes


def fold_system_time(view: Mapping, m) -> dict:
    return _clock(view, m)


def _clock(view: Mapping, m) -> dict:
    """The vehicle's own clock from a message's ``time_boot_ms``: a restart when it went back (:class:`Boot`)."""
    boot: Boot = view["boot"]
    time_ms = m.time_boot_ms
    if not isinstance(time_ms, int) or time_ms < 0:
        return {}
    heard = boot.heard_time(time_ms)
    return {} if heard is boot else dict(boot=heard)


def fold_home_position(view: Mapping, m) -> dict:
    lat, lon, alt = m.latitude * 1e-7, m.longitude * 1e-7, m.altitude * 1e-3
    if m.latitude == 0 and m.longitude == 0:      # no home yet
        return {}
    if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0 and _MIN_ALT <= alt <= _MAX_ALT):
        return _rejected(view)
    return dict(home=GlobalPosition(lat, lon, alt))


def fold_vfr_hud(view: Mapping, m) -> dict:
    env: Environment = view["environment"]
    changes = dict(environment=_env(env, throttle=int(m.throttle) if 0 <= m.throttle <= 100 else None))
    if _within(m.airspeed, -_MAX_SPEED, _MAX_SPEED):
        changes["airspeed"] = float(m.airspeed)
    else:
        changes.update(_rejected(view))
    if 0 <= m.heading <= 360:
        changes["heading_deg"] = float(m.heading % 360)
    return changes


def fold_gps_raw(view: Mapping, m) -> dict:
    r: Readiness = view["readiness"]
    hdop = None if m.eph == 0xFFFF else m.eph / 100.0
    satellites = m.satellites_visible if m.satellites_visible != 255 else 0
    return dict(gps=Gps(m.fix_type, satellites, hdop),
                readiness=replace(r, gps_ok=m.fix_type >= 3))


def fold_ekf_status(view: Mapping, m) -> dict:
    r: Readiness = view["readiness"]
    ok = (m.flags & _EKF_NEEDED) == _EKF_NEEDED and not (m.flags & mavlink.EKF_UNINITIALIZED)
    return dict(readiness=replace(r, ekf_ok=ok))


def fold_extended_sys_state(view: Mapping, m) -> dict:
    try:
        return dict(landed_state=LandedState(m.landed_state))
    except ValueError:
        return _rejected(view)


def fold_scaled_pressure(view: Mapping, m) -> dict:
    env: Environment = view["environment"]
    pressure = float(m.press_abs) if _within(m.press_abs, 1.0, 2000.0) else None
    temperature = m.temperature / 100.0 if -8000 <= m.temperature <= 15000 else None
    return dict(environment=_env(env, pressure_hpa=pressure, temperature_c=temperature))


def fold_imu(view: Mapping, m) -> dict:
    env: Environment = view["environment"]
    # ArduPilot sends RAW_IMU/SCALED_IMU accelerations in milli-g and magnetometer in milligauss
    return dict(environment=_env(env, mag=(int(m.xmag), int(m.ymag), int(m.zmag)),
                                 accel_g=(m.xacc / 1000.0, m.yacc / 1000.0, m.zacc / 1000.0)))


def fold_wind(view: Mapping, m) -> dict:
    env: Environment = view["environment"]
    if not (_within(m.speed, 0.0, _MAX_SPEED) and _ok(m.direction)):
        return dict(environment=_env(env, wind_speed=None, wind_direction_deg=None), **_rejected(view))
    return dict(environment=_env(env, wind_speed=float(m.speed), wind_direction_deg=float(m.direction) % 360))


def _env(env: Environment, **changes) -> Environment:
    return Environment(**{**env.__dict__, **changes})


#: Pure telemetry: the state follows the newest message of each type, so a read folds only the last one.
TELEMETRY = {
    "SYS_STATUS": fold_sys_status,
    "BATTERY_STATUS": fold_battery_status,
    "ATTITUDE": fold_attitude,
    "GLOBAL_POSITION_INT": fold_global_position,
    "HOME_POSITION": fold_home_position,
    "VFR_HUD": fold_vfr_hud,
    "GPS_RAW_INT": fold_gps_raw,
    "EKF_STATUS_REPORT": fold_ekf_status,
    "EXTENDED_SYS_STATE": fold_extended_sys_state,
    "SCALED_PRESSURE": fold_scaled_pressure,
    "RAW_IMU": fold_imu,
    "SCALED_IMU": fold_imu,
    "SCALED_IMU2": fold_imu,
    "WIND": fold_wind,
    "SYSTEM_TIME": fold_system_time,
}


def fold(view: Mapping, msg) -> dict:
    """The changes one telemetry message makes ({} for a type the reducer does not read)."""
    reducer = TELEMETRY.get(msg.get_type())
    return reducer(view, msg) if reducer is not None else {}
