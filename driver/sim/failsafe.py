"""The simulated ArduCopter's GCS failsafe, as its parameters say (ArduCopter/events.cpp, 4.6).

FS_GCS_ENABLE (default 0: off), FS_GCS_TIMEOUT (5 s) and FS_OPTIONS (16: carry on in a pilot-controlled mode)
decide, as ``Copter::failsafe_gcs_check`` and ``failsafe_gcs_on_event`` do. The clock starts with the first
HEARTBEAT from the ground station whose system id is SYSID_MYGCS; once it has been silent for FS_GCS_TIMEOUT:

* disarmed: only the text "GCS Failsafe";
* armed and landed (``should_disarm_on_failsafe``): disarm, "GCS Failsafe - Disarming";
* landing with FS_OPTIONS bit 3: carry on landing; in AUTO with bit 1: carry on the mission; in a mode the pilot
  flies (not an autopilot mode) with bit 4: carry on;
* else the action FS_GCS_ENABLE names: 1 (and 2, removed in 4.0) RTL, 3 SmartRTL or RTL, 4 SmartRTL or land,
  5 land, 6 DO_LAND_START or RTL, 7 brake or land. The sim keeps no SmartRTL path nor a DO_LAND_START, so those
  fly RTL (or land where ArduCopter would), as ArduCopter does when the path is not there.

Heard again: "GCS Failsafe Cleared"; the mode stays as the failsafe left it.
"""
from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .common import MODES

__all__ = ["GcsFailsafe"]

AUTOPILOT_MODES = {MODES[m] for m in ("AUTO", "GUIDED", "RTL", "LAND", "BRAKE", "SMART_RTL", "CIRCLE", "FOLLOW",
                                      "AVOID_ADSB", "THROW")}
CONTINUE_AUTO = 2            # FS_OPTIONS bits (AP_Param's "Failsafe options bitmask")
CONTINUE_LANDING = 8
CONTINUE_PILOT_CONTROL = 16


class GcsFailsafe:
    """Mixed into the Autopilot: ``_on_heartbeat`` notes the ground station, ``failsafe_step`` checks it."""

    gcs_seen: float | None = None
    gcs_failsafe = False

    def _on_heartbeat(self, msg) -> None:
        if msg.type == mavlink.MAV_TYPE_GCS and msg.get_srcSystem() == int(self.params.get("SYSID_MYGCS", 255)):
            self.gcs_seen = self.t
        super()._on_heartbeat(msg)

    def failsafe_step(self) -> None:
        if not self.params.get("FS_GCS_ENABLE") or self.gcs_seen is None:
            return
        silent = self.t - self.gcs_seen > max(0.0, float(self.params.get("FS_GCS_TIMEOUT", 5.0)))
        if not silent and self.gcs_failsafe:
            self.gcs_failsafe = False
            self._text(mavlink.MAV_SEVERITY_WARNING, "GCS Failsafe Cleared")
        elif silent and not self.gcs_failsafe:
            self.gcs_failsafe = True
            self._gcs_failsafe_action()

    def _gcs_failsafe_action(self) -> None:
        options = int(self.params.get("FS_OPTIONS", 0))
        landing = self.landed_state() == mavlink.MAV_LANDED_STATE_LANDING      # LAND, RTL's or AUTO's landing
        if not self.armed:
            self._text(mavlink.MAV_SEVERITY_WARNING, "GCS Failsafe")
            return
        if self.landed:
            self._text(mavlink.MAV_SEVERITY_WARNING, "GCS Failsafe - Disarming")
            self._disarm()
            return
        if landing and options & CONTINUE_LANDING:
            self._text(mavlink.MAV_SEVERITY_WARNING, "GCS Failsafe - Continuing Landing")
            return
        if self.mode == MODES["AUTO"] and options & CONTINUE_AUTO:
            self._text(mavlink.MAV_SEVERITY_WARNING, "GCS Failsafe - Continuing Auto Mode")
            return
        if options & CONTINUE_PILOT_CONTROL and self.mode not in AUTOPILOT_MODES:
            self._text(mavlink.MAV_SEVERITY_WARNING, "GCS Failsafe - Continuing Pilot Control")
            return
        self._text(mavlink.MAV_SEVERITY_WARNING, "GCS Failsafe")
        action = int(self.params.get("FS_GCS_ENABLE"))
        if action in (4, 5):                              # SmartRTL without a path, or land
            self.set_mode(MODES["LAND"])
        elif action == 7:
            self.set_mode(MODES["BRAKE"]) or self.set_mode(MODES["LAND"])
        elif not self.set_mode(MODES["RTL"]):             # no position: RTL is refused, land instead
            self.set_mode(MODES["LAND"])
