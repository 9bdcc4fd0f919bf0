"""The Summary page's lines: per area, done / needs attention (why) / not applicable, from what the vehicle
reported (its parameters and its radio), never from what was asked."""
from __future__ import annotations

from dataclasses import dataclass

from driver.setup.availability import unavailable

from .failsafe_words import failsafes
from .radio_calibration import throttle_channel

__all__ = ["Line", "summary", "DONE", "ATTENTION", "NOT_APPLICABLE", "UNKNOWN"]

DONE, ATTENTION, NOT_APPLICABLE, UNKNOWN = "done", "needs attention", "not applicable", "not known yet"


@dataclass(frozen=True)
class Line:
    area: str
    verdict: str
    why: str = ""


def _param(s, name: str) -> float | None:
    p = s.parameters.get(name)
    return None if p is None else float(p.value)


def _calibrated(s, area: str, names: tuple[str, ...], what: str) -> Line:
    values = [_param(s, n) for n in names]
    if any(v is None for v in values):
        return Line(area, UNKNOWN, "parameters not read yet" if not s.parameters.complete else f"no {names[0]}")
    if all(v == 0 for v in values):
        return Line(area, ATTENTION, f"{what} never calibrated ({', '.join(names)} are 0)")
    return Line(area, DONE, f"{what} calibrated")


def summary(s, no_setup: str = "") -> list[Line]:
    """One line per setup area for the state ``s`` (a VehicleState); ``no_setup``: why this connection has no
    vehicle setup (its radio, traffic and motor test are then not applicable, with that reason)."""
    lines = []
    frame = _param(s, "FRAME_CLASS")
    lines.append(Line("Frame", UNKNOWN, "parameters not read yet") if frame is None else
                 Line("Frame", ATTENTION, "no frame class set (FRAME_CLASS 0)") if frame == 0 else
                 Line("Frame", DONE, f"FRAME_CLASS {frame:g}, FRAME_TYPE {_param(s, 'FRAME_TYPE') or 0:g}"))
    lines.append(_calibrated(s, "Accelerometer", ("INS_ACCOFFS_X", "INS_ACCOFFS_Y", "INS_ACCOFFS_Z"),
                             "accelerometer"))
    lines.append(_calibrated(s, "Compass", ("COMPASS_OFS_X", "COMPASS_OFS_Y", "COMPASS_OFS_Z"), "compass"))
    rc = s.setup.rc
    if no_setup:
        lines.append(Line("Radio", NOT_APPLICABLE, no_setup))
    elif rc.channel(throttle_channel(s)) is None:
        lines.append(Line("Radio", ATTENTION, "no RC channels received from the vehicle (transmitter off, or no "
                                              "receiver)" if rc.updated else "RC channels not received yet"))
    else:
        lines.append(Line("Radio", DONE, f"{len([v for v in rc.values if v])} channels received"))
    fs = failsafes(s)                        # the Failsafes page's own model: the two never disagree
    lines.append(Line("Failsafes", UNKNOWN, f"not read yet: {', '.join(fs.unread)}") if fs.unread else
                 Line("Failsafes", ATTENTION if fs.missing else DONE, fs.summary))
    batt = _param(s, "BATT_MONITOR")
    lines.append(Line("Power", UNKNOWN, "parameters not read yet") if batt is None else
                 Line("Power", ATTENTION, "no battery monitor (BATT_MONITOR 0)") if batt == 0 else
                 Line("Power", DONE, f"battery monitor {batt:g}, capacity {_param(s, 'BATT_CAPACITY') or 0:g} mAh"))
    why = no_setup or unavailable("adsb", s.firmware)
    lines.append(Line("Traffic (ADS-B)", NOT_APPLICABLE, why) if why else
                 Line("Traffic (ADS-B)", DONE, f"{len(s.traffic.contacts)} aircraft heard"))
    lines.append(Line("Motors", NOT_APPLICABLE, no_setup) if no_setup else
                 Line("Motors", NOT_APPLICABLE, "armed: the motor test is for a disarmed vehicle on the ground")
                 if s.armed else Line("Motors", DONE, "motor test available (disarmed, propellers off)"))
    return lines
