"""The preflight go/no-go lines: each judged with its reason, from one snapshot."""
from __future__ import annotations

from driver.vehicle.state import (
    Battery, Fence, Gps, LinkHealth, LinkStatus, Message, Readiness, Severity, Signing, SigningStatus,
    VehicleState, replace,
)
from uavviewer.preflight.model import Verdict, overall, preflight

READY = VehicleState(link=LinkHealth(status=LinkStatus.OK, packets_per_s=40.0), mode="GUIDED",
                     readiness=Readiness(prearm_ok=True, ekf_ok=True, gps_ok=True, prearm_reported=True),
                     gps=Gps(3, 12, 0.8), battery=Battery(16.4, cells=4, remaining=95.0),
                     signing=Signing(SigningStatus.SIGNING), gcs_failsafe=1,
                     fence=Fence(enabled=True, types=3, radius=150.0, alt_max=60.0, breached=False))


def lines(s: VehicleState) -> dict[str, tuple[Verdict, str]]:
    return {c.name: (c.verdict, c.reason) for c in preflight(s)}


def test_a_ready_vehicle_is_go_on_every_line():
    found = lines(READY)
    assert list(found) == ["Link", "Pre-arm", "GPS", "EKF", "Battery", "Signing", "GCS failsafe", "Fence"]
    assert all(v is Verdict.GO for v, _ in found.values()), found
    assert found["Fence"][1] == "on: circle 150 m, ceiling 60 m"
    assert overall(preflight(READY)) is Verdict.GO


def test_each_problem_says_why():
    s = replace(READY, readiness=Readiness(prearm_ok=False, ekf_ok=False, gps_ok=False, prearm_reported=True,
                                           reasons=("Compass not calibrated",)),
                gps=Gps(1, 3, 9.9), messages=(Message(1, 0.0, Severity.CRITICAL, "PreArm: Compass not calibrated"),),
                battery=Battery(14.2, cells=4, remaining=20.0),
                signing=Signing(SigningStatus.MISMATCH), gcs_failsafe=0,
                fence=Fence(enabled=True, types=3, radius=150.0, alt_max=60.0, breached=True),
                link=LinkHealth(status=LinkStatus.OK, packets_per_s=10.0, loss_percent=25.0))
    found = lines(s)
    assert found["Pre-arm"] == (Verdict.NO_GO, "Compass not calibrated")   # the vehicle's own words
    assert found["GPS"] == (Verdict.NO_GO, "No fix, 3 satellites, HDOP 9.9")
    assert found["EKF"][0] is Verdict.NO_GO
    assert found["Battery"] == (Verdict.NO_GO, "below the warning threshold: 14.20 V, 3.55 V a cell, 20 %")
    assert found["Signing"][0] is Verdict.NO_GO and "ignores our commands" in found["Signing"][1]
    assert found["GCS failsafe"][0] is Verdict.CAUTION and "hovers on" in found["GCS failsafe"][1]
    assert found["Fence"] == (Verdict.NO_GO, "breached")
    assert found["Link"][0] is Verdict.NO_GO and "25 % lost" in found["Link"][1]
    assert overall(preflight(s)) is Verdict.NO_GO


def test_cautions_and_unknowns():
    s = replace(READY, battery=Battery(), signing=Signing(SigningStatus.OFF), gcs_failsafe=None,
                fence=Fence(enabled=False, types=3, radius=150.0, alt_max=60.0))
    found = lines(s)
    assert found["Battery"][0] is Verdict.UNKNOWN                  # nothing reported yet: not a GO
    assert found["Signing"][0] is Verdict.CAUTION and "anyone" in found["Signing"][1]
    assert found["GCS failsafe"] == (Verdict.UNKNOWN, "FS_GCS_ENABLE not read yet")
    assert found["Fence"] == (Verdict.CAUTION, "off: nothing stops a fly-away")
    assert overall(preflight(s)) is Verdict.CAUTION


def test_without_a_link_nothing_is_go():
    for status, why in ((LinkStatus.WAITING, "no vehicle yet"), (LinkStatus.LOST, "link lost")):
        found = lines(replace(READY, link=LinkHealth(status=status)))
        assert found["Link"] == (Verdict.NO_GO, why)
        assert all(v is Verdict.UNKNOWN for name, (v, _) in found.items() if name != "Link")


def test_a_refused_arming_is_a_caution_while_the_checks_pass():
    """The vehicle's refusal stands (driver.vehicle.prearm) while its checks pass: a caution, in its words; once it
    no longer stands by it (the driver forgot it), GO, whatever Messages still holds."""
    refused = Message(5, 1000.0, Severity.CRITICAL, "Arm: Compass not calibrated")
    found = lines(replace(READY, messages=(refused,),
                          readiness=replace(READY.readiness, reasons=("Compass not calibrated",))))
    assert found["Pre-arm"] == (Verdict.CAUTION, "checks pass, but arming was just refused: Compass not calibrated")
    assert lines(replace(READY, messages=(refused,)))["Pre-arm"][0] is Verdict.GO
