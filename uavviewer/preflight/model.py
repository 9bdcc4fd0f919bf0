"""Go / no-go before a flight, line by line with the reason, from one snapshot (no Qt).

Each line judges one thing the way a pilot's checklist does: the vehicle's own pre-arm state (with its last
"PreArm:" message), GPS, EKF, the battery against the pilot's thresholds (``Battery.alarm``), the link's
quality, MAVLink signing, the vehicle's GCS failsafe (FS_GCS_ENABLE) and its fence. A NO-GO line means do not
take off; CAUTION means it flies but the pilot should know; UNKNOWN means the vehicle has not told yet.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass

from driver.vehicle.state import BatteryAlarm, LinkStatus, SigningStatus, VehicleState

__all__ = ["Verdict", "Check", "preflight", "overall", "LOSS_CAUTION", "LOSS_NO_GO"]

LOSS_CAUTION = 5.0       # % of frames lost: the link flies, but watch it
LOSS_NO_GO = 20.0        # %: commands and telemetry go missing


class Verdict(enum.IntEnum):
    """Worse is higher."""
    GO = 0
    UNKNOWN = 1
    CAUTION = 2
    NO_GO = 3

    @property
    def label(self) -> str:
        return {Verdict.GO: "GO", Verdict.UNKNOWN: "?", Verdict.CAUTION: "CAUTION", Verdict.NO_GO: "NO GO"}[self]


@dataclass(frozen=True)
class Check:
    name: str
    verdict: Verdict
    reason: str


def preflight(s: VehicleState) -> list[Check]:
    """Every line, in the order a pilot reads them."""
    if s.link.status is not LinkStatus.OK:
        why = {LinkStatus.WAITING: "no vehicle yet", LinkStatus.LOST: "link lost",
               LinkStatus.CLOSED: "not connected"}[s.link.status]
        return [Check("Link", Verdict.NO_GO, why)] + [Check(name, Verdict.UNKNOWN, why) for name in
                                                     ("Pre-arm", "GPS", "EKF", "Battery", "Signing", "GCS failsafe",
                                                      "Fence")]
    return [_link(s), _prearm(s), _gps(s), _ekf(s), _battery(s), _signing(s), _gcs_failsafe(s), _fence(s)]


def overall(checks: list[Check]) -> Verdict:
    return max((c.verdict for c in checks), default=Verdict.UNKNOWN)


def _link(s: VehicleState) -> Check:
    link = s.link
    rate = f"{link.packets_per_s:.0f} packets/s, {link.loss_percent:.0f} % lost"
    if link.loss_percent >= LOSS_NO_GO:
        return Check("Link", Verdict.NO_GO, f"poor: {rate}")
    if link.loss_percent >= LOSS_CAUTION:
        return Check("Link", Verdict.CAUTION, f"lossy: {rate}")
    return Check("Link", Verdict.GO, rate)


def _prearm(s: VehicleState) -> Check:
    if s.armed:
        return Check("Pre-arm", Verdict.GO, "armed")
    if not s.readiness.prearm_reported:
        return Check("Pre-arm", Verdict.UNKNOWN, "the vehicle does not report its pre-arm checks")
    reasons = "; ".join(s.readiness.reasons)          # the vehicle's own words, while it stands by them
    if s.readiness.prearm_ok:
        if reasons:                                    # it passes its checks, yet refused an arming just now
            return Check("Pre-arm", Verdict.CAUTION, f"checks pass, but arming was just refused: {reasons}")
        return Check("Pre-arm", Verdict.GO, "the vehicle's pre-arm checks pass")
    return Check("Pre-arm", Verdict.NO_GO, reasons or "the vehicle's pre-arm checks fail")


def _gps(s: VehicleState) -> Check:
    g = s.gps
    detail = f"{g.fix_name}, {g.satellites} satellites" + (f", HDOP {g.hdop:.1f}" if g.hdop is not None else "")
    if g.fix_type < 3:
        return Check("GPS", Verdict.NO_GO, detail)
    if g.hdop is not None and g.hdop > 2.0 or g.satellites < 6:
        return Check("GPS", Verdict.CAUTION, f"weak: {detail}")
    return Check("GPS", Verdict.GO, detail)


def _ekf(s: VehicleState) -> Check:
    if s.readiness.ekf_ok:
        return Check("EKF", Verdict.GO, "attitude, velocity and position good")
    return Check("EKF", Verdict.NO_GO, "the EKF has no good position yet")


def _battery(s: VehicleState) -> Check:
    b = s.battery
    parts = [f"{b.voltage:.2f} V" if b.voltage is not None else "",
             f"{b.cell_voltage:.2f} V a cell" if b.cell_voltage is not None else "",
             f"{b.remaining:.0f} %" if b.remaining is not None else ""]
    detail = ", ".join(p for p in parts if p) or "no reading"
    if b.alarm is BatteryAlarm.CRITICAL:
        return Check("Battery", Verdict.NO_GO, f"critical: {detail}")
    if b.alarm is BatteryAlarm.WARNING:
        return Check("Battery", Verdict.NO_GO, f"below the warning threshold: {detail}")
    if b.alarm is BatteryAlarm.OK:
        return Check("Battery", Verdict.GO, detail)
    return Check("Battery", Verdict.UNKNOWN, f"no thresholds applied yet: {detail}")


def _signing(s: VehicleState) -> Check:
    status = s.signing.status
    if status is SigningStatus.SIGNING:
        return Check("Signing", Verdict.GO, "the link is signed")
    if status in (SigningStatus.REQUIRED, SigningStatus.MISMATCH):
        return Check("Signing", Verdict.NO_GO, f"{status.value}: the vehicle ignores our commands")
    if status is SigningStatus.SETTING_UP:
        return Check("Signing", Verdict.CAUTION, "setting up")
    return Check("Signing", Verdict.CAUTION, f"{status.value}: anyone on the link can command it")


def _gcs_failsafe(s: VehicleState) -> Check:
    fs = s.gcs_failsafe
    if fs is None:
        return Check("GCS failsafe", Verdict.UNKNOWN, "FS_GCS_ENABLE not read yet")
    if fs == 0:
        return Check("GCS failsafe", Verdict.CAUTION,
                     "off (FS_GCS_ENABLE 0): it hovers on if the link is lost")
    return Check("GCS failsafe", Verdict.GO, f"on (FS_GCS_ENABLE {fs}): it acts on link loss")


def _fence(s: VehicleState) -> Check:
    f = s.fence
    if f.enabled is None:
        return Check("Fence", Verdict.UNKNOWN, "FENCE_ENABLE not read yet")
    if f.breached:
        return Check("Fence", Verdict.NO_GO, "breached")
    if not f.enabled:
        return Check("Fence", Verdict.CAUTION, "off: nothing stops a fly-away")
    parts = [f"circle {f.circle:g} m" if f.circle else "", f"ceiling {f.ceiling:g} m" if f.ceiling else ""]
    return Check("Fence", Verdict.GO, "on: " + (", ".join(p for p in parts if p) or "polygon"))
