"""The vehicle's own reasons for refusing to arm, as it says them, for as long as it says them.

ArduPilot runs its pre-arm checks once a second (AP_Arming::update). A failing run clears the SYS_STATUS
health bit MAV_SYS_STATUS_PREARM_CHECK at once and says every failing check as "PreArm: <why>" at the next run
(at most every 4 s) and then every 30 s while they fail (PREARM_DISPLAY_PERIOD); an arming refused
says its reasons as "Arm: <why>" (tests/data/recordings/arducopter-4.6-sitl-calib: "PreArm: Accels calibrated
requires reboot" at 64 s and again at 94 s; -setup: "Arm: 3D Accel calibration needed" after a failed accel
calibration). QGroundControl shows the latest of them and forgets it 35 s after it was said; here every reason
of the latest round is kept (a round: the texts said together), and they go when:

* the vehicle says its checks pass: the health bit set in a SYS_STATUS sent after a check run that followed the
  texts (a second after them, :data:`FRESH_RUN`), or it is armed;
* a new round replaces them (the checks that still fail are said again; the others passed);
* nothing is said again for :data:`FORGET_AFTER` s (firmware without the health bit, a vehicle that stopped
  repeating).

Time is the driver's clock (a test's manual one); a vehicle restart forgets them. No I/O, no lock.
"""
from __future__ import annotations

__all__ = ["PreArmReasons", "reason_in", "FORGET_AFTER", "ROUND", "FRESH_RUN"]

PREFIXES = ("PreArm: ", "Arm: ")
ROUND = 1.0                 # s: the texts of one run (or one refusal) come together
FRESH_RUN = 1.5             # s after the texts: a check run (1 Hz) has run again since, and SYS_STATUS told it
FORGET_AFTER = 35.0         # s without the vehicle saying it again (it repeats every 30 s while it fails)


def reason_in(text: str) -> str:
    """The reason a "PreArm: ..." or "Arm: ..." text gives ("" for any other text)."""
    for prefix in PREFIXES:
        if text.startswith(prefix):
            return text[len(prefix):].strip()
    return ""


class PreArmReasons:
    """The reasons standing now (:attr:`reasons`); each method returns whether they changed."""

    def __init__(self) -> None:
        self.reasons: tuple[str, ...] = ()
        self._round_at: float | None = None      # the vehicle's time the current round began
        self._said_at: float | None = None       # ... and when its last text came

    def heard(self, text: str, now: float) -> bool:
        """A STATUSTEXT at the vehicle's time ``now`` (s)."""
        reason = reason_in(text)
        if not reason:
            return False
        before = self.reasons
        if self._round_at is None or now - self._round_at > ROUND or now < self._round_at:
            self._round_at, self.reasons = now, ()            # a new round: what it does not say again passed
        if reason not in self.reasons:
            self.reasons += (reason,)
        self._said_at = now
        return self.reasons != before

    def checked(self, healthy: bool | None, armed: bool, now: float) -> bool:
        """What the vehicle says now: its pre-arm bit (None when it does not report one), whether it is armed."""
        if not self.reasons:
            return False
        said = self._said_at if self._said_at is not None else now
        passed = healthy is True and now - said >= FRESH_RUN
        if armed or passed or now - said > FORGET_AFTER or now < said:
            self.forget()
            return True
        return False

    def forget(self) -> None:
        """Nothing stands (the vehicle armed, restarted, or another vehicle is flown)."""
        self.reasons, self._round_at, self._said_at = (), None, None
