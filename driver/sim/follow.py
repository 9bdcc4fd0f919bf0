"""ArduCopter's FOLLOW mode for the simulated vehicle: mode_follow.cpp over AP_Follow, as 4.6.3 flies it.

AP_Follow hears the lead's FOLLOW_TARGET (position, and velocity when est_capabilities says so) or
GLOBAL_POSITION_INT from any other system (the first one heard when FOLL_SYSID is 0, which it then keeps), with
altitudes above home (FOLL_ALT_TYPE 1) or above sea level. Entering FOLLOW needs FOLL_ENABLE 1 ("Set FOLL_ENABLE
= 1" otherwise). The mode wants the velocity FOLL_POS_P × (distance to the lead + FOLL_OFS_*), slowed as it
closes in (AC_Avoid::limit_velocity_2D with half the acceleration) plus the lead's own velocity, within
WPNAV_SPEED and the climb rates, flown by Guided's velocity controller; the lead is dead-reckoned from its last
fix with its velocity, and forgotten 3 s after it (AP_FOLLOW_TIMEOUT_MS): the velocity is then zero. Offsets all
zero are loaded from where the lead is when first heard in the mode ("N-E-D follow offset loaded") and cleared on
leaving it. FOLL_YAW_BEHAVE 1 turns the nose to the lead (not within a metre).
"""
from __future__ import annotations

import math

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .common import MODES, clamp

__all__ = ["FollowMode", "FOLLOW_TIMEOUT"]

FOLLOW_TIMEOUT = 3.0         # s (AP_FOLLOW_TIMEOUT_MS)
POS_XY_P = 1.0               # PSC_POSXY_P
POS_Z_P = 1.0                # PSC_POSZ_P


class FollowMode:
    """The lead as AP_Follow last heard it; the state belongs to the Autopilot."""

    def _follow_init(self) -> None:
        self.follow_lead: tuple | None = None          # (north, east, up, vn, ve, vd, heard at t)
        self.follow_offsets_loaded = False

    def _follow_accepts(self, msg) -> bool:
        """AP_Follow::should_handle_message: enabled, not our own system, the followed one if set."""
        if not self.params.get("FOLL_ENABLE"):
            return False
        src = msg.get_srcSystem()
        sysid = int(self.params.get("FOLL_SYSID", 0))
        return src != self.config.system_id and sysid in (0, src)

    def _heard_lead(self, msg, lat: float, lon: float, up: float, vel) -> None:
        north, east = self.ned_from(lat, lon)
        self.follow_lead = (north, east, up, *vel, self.t)
        if not int(self.params.get("FOLL_SYSID", 0)):
            self.params["FOLL_SYSID"] = msg.get_srcSystem()      # _automatic_sysid

    def _on_follow_target(self, msg) -> None:
        if not self._follow_accepts(msg) or (msg.lat == 0 and msg.lon == 0) or not msg.est_capabilities & 1:
            return
        vel = tuple(msg.vel[:3]) if msg.est_capabilities & 2 else (0.0, 0.0, 0.0)
        self._heard_lead(msg, msg.lat / 1e7, msg.lon / 1e7, msg.alt - self.home_alt, vel)

    def _on_global_position_int(self, msg) -> None:
        if not self._follow_accepts(msg) or (msg.lat == 0 and msg.lon == 0):
            return
        relative = int(self.params.get("FOLL_ALT_TYPE", 1)) == 1
        up = msg.relative_alt / 1000.0 if relative else msg.alt / 1000.0 - self.home_alt
        self._heard_lead(msg, msg.lat / 1e7, msg.lon / 1e7, up, (msg.vx / 100.0, msg.vy / 100.0, msg.vz / 100.0))

    def follow_truth(self) -> tuple | None:
        """(north, east, up) of the lead as AP_Follow estimates it now, None when it has none."""
        lead = self.follow_lead
        if lead is None or self.t - lead[6] > FOLLOW_TIMEOUT:
            return None
        dt = self.t - lead[6]
        return lead[0] + lead[3] * dt, lead[1] + lead[4] * dt, lead[2] - lead[5] * dt

    def _follow_entered(self) -> bool:
        """ModeFollow::init: refused without FOLL_ENABLE, else Guided's init (hold)."""
        if not self.params.get("FOLL_ENABLE"):
            self._text(mavlink.MAV_SEVERITY_WARNING, "Set FOLL_ENABLE = 1")
            return False
        return True

    def _follow_left(self) -> None:
        """ModeFollow::exit: offsets loaded on entering go back to zero."""
        if self.follow_offsets_loaded:
            for axis in "XYZ":
                self.params[f"FOLL_OFS_{axis}"] = 0.0
            self.follow_offsets_loaded = False

    def _follow(self) -> tuple[float, float, float]:
        """ModeFollow::run: the NED velocity wanted now (zero without a lead)."""
        lead = self.follow_truth()
        if lead is None:
            return 0.0, 0.0, 0.0
        vn, ve, vd = self.follow_lead[3:6]
        dist = (lead[0] - self.n, lead[1] - self.e, -(lead[2] + self.d))      # NED from the vehicle to the lead
        max_dist = float(self.params.get("FOLL_DIST_MAX", 100.0))
        if max_dist > 0 and math.sqrt(sum(v * v for v in dist)) > max_dist:
            return 0.0, 0.0, 0.0
        offsets = [float(self.params.get(f"FOLL_OFS_{axis}", 0.0)) for axis in "XYZ"]
        if not any(offsets):                              # init_offsets_if_required
            offsets = [-v for v in dist]
            for axis, value in zip("XYZ", offsets):
                self.params[f"FOLL_OFS_{axis}"] = value
            self.follow_offsets_loaded = True
            self._text(mavlink.MAV_SEVERITY_INFO, "N-E-D follow offset loaded")
        off = [d + o for d, o in zip(dist, offsets)]
        kp = float(self.params.get("FOLL_POS_P", 0.1))
        want_n, want_e, want_d = (kp * v for v in off)
        horizontal = math.hypot(off[0], off[1])
        accel = max(0.5, float(self.params["WPNAV_ACCEL"]) / 100.0) * 0.5
        closing = min(POS_XY_P * horizontal, math.sqrt(2.0 * accel * horizontal))     # limit_velocity_2D
        speed = math.hypot(want_n, want_e)
        if speed > closing > 0:
            want_n, want_e = want_n * closing / speed, want_e * closing / speed
        vertical = min(POS_Z_P * abs(off[2]), math.sqrt(2.0 * 0.5 * 2.5 * abs(off[2])))
        want_d = clamp(want_d, -vertical, vertical)
        want_n, want_e, want_d = want_n + vn, want_e + ve, want_d + vd
        top = self.wp_speed()
        speed = math.hypot(want_n, want_e)
        if speed > top:
            want_n, want_e = want_n * top / speed, want_e * top / speed
        want_d = clamp(want_d, -self._speed_up(), self._speed_dn())
        if int(self.params.get("FOLL_YAW_BEHAVE", 1)) == 1 and dist[0] ** 2 + dist[1] ** 2 > 1.0:
            self.yaw_mode, self.yaw_rate_cmd = "angle_rate", 0.0
            self.yaw_target = math.atan2(dist[1], dist[0])
        return want_n, want_e, want_d
