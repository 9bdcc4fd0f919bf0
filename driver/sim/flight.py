"""How the simulated copter flies: a SITL-like point mass behind ArduCopter's mode controllers.

Mixed into :class:`~driver.sim.autopilot.Autopilot`; the state (n, e, d NED from
home, velocities, attitude) and the mode belong to it. First-order velocity
response with limited acceleration, square-root shaped approaches, a takeoff that
stays on the ground while the motors spool up (land_complete), LAND at
LAND_SPEED, RTL's climb-return-loiter-land.
"""
from __future__ import annotations

import logging
import math

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .common import MODES, clamp as _clamp, wrap_pi
from .telemetry import GRAVITY

__all__ = ["Flight", "TAKEOFF_DONE", "LAND_DISARM_DELAY"]

log = logging.getLogger("driver.sim.autopilot")

# Flight dynamics (SITL-like): first-order velocity response, limited acceleration.
VEL_TAU = 0.7            # s, following a velocity command (SITL: body vx 2 m/s for 5 s moved 8.3 m)
POS_TAU = 0.3            # s, under position control (the controller's feed-forward hides the lag)
YAW_RATE_TAU = 0.12      # s
ATT_TAU = 0.15           # s
ACC_XY = 2.5             # m/s², normal manoeuvres (WPNAV_ACCEL)
ACC_XY_BRAKE = 7.5       # m/s², BRAKE mode
ACC_Z = 2.5              # m/s²
KP_XY = 1.0              # 1/s, position error → speed
KP_Z = 1.0
DECEL_XY = 2.0           # m/s², sqrt law when approaching a target
DECEL_Z = 0.5
TAKEOFF_SPEED = 1.5      # m/s (4.7 recording: up to 1.7 m/s, 5 m 4.5 s after leaving the ground)
TAKEOFF_DONE = 0.95      # share of the takeoff altitude at which landed_state turns IN_AIR
LOOK_AHEAD_SPEED = 0.5   # m/s, nose turns to the direction of travel above this
AUTO_YAW_SLEW = math.radians(60.0)
MAX_TILT = math.radians(30.0)
DRAG = 0.15              # 1/s, tilt needed to hold a speed
LAND_DISARM_DELAY = 2.0  # s after touchdown (4.7 recording: "SIM Hit ground" 79.15 s, "Disarming motors" 81.25 s)


class Flight:
    """Physics and the per-mode controllers."""

    def _physics(self, dt: float) -> None:
        old = (self.vn, self.ve, self.vd)
        if self.armed:
            self._tau = POS_TAU
            want_n, want_e, want_d, acc_xy = self._controller()
            gain = min(1.0, dt / self._tau)
            dvn, dve = (want_n - self.vn) * gain, (want_e - self.ve) * gain
            limit = acc_xy * dt
            size = math.hypot(dvn, dve)
            if size > limit:
                dvn, dve = dvn * limit / size, dve * limit / size
            dvd = _clamp((want_d - self.vd) * gain, -ACC_Z * dt, ACC_Z * dt)
            self.vn, self.ve, self.vd = self.vn + dvn, self.ve + dve, self.vd + dvd
            if self.landed:
                if want_d < -0.05:           # climbing away: no longer landed
                    self.landed = False
                    self.touchdown_at = None
                    self.liftoff_at = None
                else:
                    self.vn = self.ve = self.vd = 0.0
            self._yaw(dt)
        else:
            # Motors off: fall (under a canopy once the parachute is out), drift to a stop.
            drag = 0.6 if self.chute_released else 0.045
            self.vd += (GRAVITY - drag * self.vd * abs(self.vd)) * dt
            self.vn -= self.vn * min(1.0, 0.5 * dt)
            self.ve -= self.ve * min(1.0, 0.5 * dt)
            self.yaw_rate -= self.yaw_rate * min(1.0, dt / 0.5)
            self.yaw = wrap_pi(self.yaw + self.yaw_rate * dt)
        self.n += self.vn * dt
        self.e += self.ve * dt
        self.d += self.vd * dt
        if self.guided == "takeoff" and self.takeoff_alt is not None and -self.d >= TAKEOFF_DONE * self.takeoff_alt:
            # ArduCopter ends the takeoff when its climb target arrives; the vehicle is then ~95 % up
            self.guided = "hold"
            self.hold_point = (self.hold_point or (self.n, self.e))[:2] + (-self.takeoff_alt,)
            log.info("takeoff complete at %.2f m", -self.d)
        if self.d >= 0.0:
            self.d = 0.0
            if self.vd > 0.0 or self.landed or not self.armed:
                if self.armed and not self.landed and self.vd >= 0.0:
                    self._touchdown()
                self.vd = 0.0
                self.vn = self.ve = 0.0
                if not self.armed:
                    self.chute_released = False
        self._attitude(dt, old)

    def _touchdown(self) -> None:
        """ArduCopter says nothing on landing (no "Land complete"); SITL's physics reports the impact."""
        if self.profile.sitl_texts:
            self._text(mavlink.MAV_SEVERITY_INFO, f"SIM Hit ground at {max(self.vd, 0.0):.6f} m/s")
        self.landed = True
        self.touchdown_at = self.t
        self.takeoff_alt = None
        self.hold_point = None
        log.info("touchdown at %.1f, %.1f", self.n, self.e)

    def _attitude(self, dt: float, old: tuple[float, float, float]) -> None:
        an = (self.vn - old[0]) / dt + DRAG * self.vn
        ae = (self.ve - old[1]) / dt + DRAG * self.ve
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        fwd, right = c * an + s * ae, -s * an + c * ae
        if self.armed and not self.landed:
            pitch_t = _clamp(-math.atan2(fwd, GRAVITY), -MAX_TILT, MAX_TILT)
            roll_t = _clamp(math.atan2(right * math.cos(pitch_t), GRAVITY), -MAX_TILT, MAX_TILT)
        else:
            pitch_t = roll_t = 0.0
        gain = min(1.0, dt / ATT_TAU)
        roll = self.roll + (roll_t - self.roll) * gain
        pitch = self.pitch + (pitch_t - self.pitch) * gain
        self.roll_rate, self.pitch_rate = (roll - self.roll) / dt, (pitch - self.pitch) / dt
        self.roll, self.pitch = roll, pitch
        az = (self.vd - old[2]) / dt
        self.acc_body = (fwd - DRAG * (c * self.vn + s * self.ve), right, az - GRAVITY)

    def _yaw(self, dt: float) -> None:
        fixed = self.yaw_mode == "fixed"
        if self.landed:
            target = 0.0
        elif self.yaw_mode == "rate":
            target = self.yaw_rate_cmd
        elif fixed:
            rem = self.yaw_remaining
            target = math.copysign(min(self.yaw_slew, abs(rem) * 3.0), rem) if abs(rem) > 1e-4 else 0.0
        elif self.yaw_mode == "angle_rate":
            self.yaw_target = wrap_pi(self.yaw_target + self.yaw_rate_cmd * dt)
            target = self.yaw_rate_cmd + _clamp(3.0 * wrap_pi(self.yaw_target - self.yaw), -AUTO_YAW_SLEW, AUTO_YAW_SLEW)
        elif self.yaw_mode == "look_ahead" and math.hypot(self.vn, self.ve) > LOOK_AHEAD_SPEED:
            error = wrap_pi(math.atan2(self.ve, self.vn) - self.yaw)
            target = _clamp(error * 3.0, -AUTO_YAW_SLEW, AUTO_YAW_SLEW)
        else:
            target = 0.0
        rate = self.yaw_rate + (target - self.yaw_rate) * min(1.0, dt / YAW_RATE_TAU)
        turn = rate * dt
        if fixed and not self.landed:
            rem = self.yaw_remaining
            if (rem >= 0 and turn > rem) or (rem <= 0 and turn < rem):
                turn = rem
            self.yaw_remaining = rem - turn
        self.yaw_rate = turn / dt
        self.yaw = wrap_pi(self.yaw + turn)

    def _pos_ctrl(self, target, speed_xy: float, speed_up: float, speed_dn: float,
                  decel_z: float = DECEL_Z) -> tuple[float, float, float]:
        """Velocity toward a point: proportional, square-root shaped so it stops on it."""
        dn, de, dd = target[0] - self.n, target[1] - self.e, target[2] - self.d
        dist = math.hypot(dn, de)
        vn = ve = 0.0
        if dist > 1e-6:
            speed = min(speed_xy, KP_XY * dist, math.sqrt(2.0 * DECEL_XY * dist))
            vn, ve = speed * dn / dist, speed * de / dist
        speed = min(KP_Z * abs(dd), math.sqrt(2.0 * decel_z * abs(dd)))
        vd = _clamp(math.copysign(speed, dd), -speed_up, speed_dn)
        return vn, ve, vd

    def _hold(self, keep_down: float | None = None) -> tuple[float, float, float]:
        """Brake, then hold the point where the vehicle stopped."""
        if self.hold_point is None:
            if math.hypot(self.vn, self.ve) < 0.2 and abs(self.vd) < 0.2:
                self.hold_point = (self.n, self.e, self.d if keep_down is None else keep_down)
            else:
                return 0.0, 0.0, 0.0
        return self._pos_ctrl(self.hold_point, self.wp_speed(), self._speed_up(), self._speed_dn())

    def wp_speed(self) -> float:
        """m/s the vehicle flies to a waypoint: WPNAV_SPEED, or DO_CHANGE_SPEED's while it holds."""
        if self.speed_override:
            return self.speed_override
        return max(0.5, float(self.params["WPNAV_SPEED"]) / 100.0)

    def _speed_up(self) -> float:
        return max(0.1, float(self.params["WPNAV_SPEED_UP"]) / 100.0)

    def _speed_dn(self) -> float:
        return max(0.1, float(self.params["WPNAV_SPEED_DN"]) / 100.0)

    def _land_speed(self) -> float:
        if -self.d > 10.0:
            high = float(self.params["LAND_SPEED_HIGH"]) / 100.0
            return high if high > 0 else self._speed_dn()
        return max(0.1, float(self.params["LAND_SPEED"]) / 100.0)

    def _controller(self) -> tuple[float, float, float, float]:
        """Desired NED velocity for the current mode, and the acceleration limit."""
        if self.landed and self.liftoff_at is not None and self.t < self.liftoff_at:
            return 0.0, 0.0, 0.0, ACC_XY     # arming delay and spool-up: still landed (land_complete)
        if self.landed and not (self.mode == MODES["GUIDED"] and self.guided == "takeoff") \
                and not self._auto_climbing():
            manual = self._manual()
            if manual is not None and manual[2] < -0.3 and self.mode not in (MODES["GUIDED"], MODES["LAND"],
                                                                            MODES["RTL"], MODES["AUTO"]):
                return 0.0, 0.0, manual[2], ACC_XY
            return 0.0, 0.0, 0.0, ACC_XY
        mode = self.mode
        if mode == MODES["GUIDED"]:
            return (*self._guided(), ACC_XY)
        if mode == MODES["LAND"]:
            vn, ve, _ = self._hold(keep_down=self.d)
            return vn, ve, self._land_speed(), ACC_XY
        if mode == MODES["RTL"]:
            return (*self._rtl(), ACC_XY)
        if mode == MODES["BRAKE"]:
            return (*self._hold(), ACC_XY_BRAKE)
        if mode == MODES["CIRCLE"] and self.circle is not None:
            vn, ve, vd, self.yaw_rate_cmd = self.circle.step(self.n, self.e, self.d, self.yaw, self.t)
            return vn, ve, vd, ACC_XY
        if mode == MODES["AUTO"]:
            return (*self._auto(), self._auto_acceleration())
        if mode == MODES["FOLLOW"]:                  # follow.py: Guided's velocity controller
            self._tau = VEL_TAU
            return (*self._follow(), ACC_XY)
        # LOITER, POSHOLD, ALT_HOLD and the rest: hold, nudged by MANUAL_CONTROL sticks.
        manual = self._manual()
        if manual is not None and any(abs(v) > 1e-3 for v in manual):
            fwd, right, down, yaw_rate = manual
            self.yaw_mode, self.yaw_rate_cmd = "rate", yaw_rate
            if abs(fwd) > 1e-3 or abs(right) > 1e-3 or abs(down) > 1e-3:
                c, s = math.cos(self.yaw), math.sin(self.yaw)
                self.hold_point = None
                self._tau = VEL_TAU
                return c * fwd - s * right, s * fwd + c * right, down, ACC_XY
        elif self.yaw_mode == "rate":
            self.yaw_mode = "hold"
        return (*self._hold(), ACC_XY)

    def _manual(self) -> tuple[float, float, float, float] | None:
        """MANUAL_CONTROL sticks as (forward, right, down m/s, yaw rate rad/s), None when stale."""
        if self.manual is None or self.t - self.manual[4] > 1.0:
            return None
        x, y, z, r, _ = self.manual
        dead = lambda v: 0.0 if abs(v) < 0.1 else v  # noqa: E731
        speed = 5.0
        climb = (z - 0.5) * 2.0
        climb = 0.0 if abs(climb) < 0.2 else climb
        down = -climb * self._speed_up() if climb > 0 else -climb * self._speed_dn()
        return dead(x) * speed, dead(y) * speed, down, dead(r) * math.radians(90.0)

    def _guided(self) -> tuple[float, float, float]:
        if self.guided == "takeoff":
            target = self.hold_point or (self.n, self.e, 0.0)
            return self._pos_ctrl((target[0], target[1], -self.takeoff_alt), 2.0, TAKEOFF_SPEED,
                                  self._speed_dn())
        if self.guided == "velocity":
            if self.t - self.vel_time > float(self.params["GUID_TIMEOUT"]):
                self.guided = "hold"
                self.hold_point = None
                if self.yaw_mode == "rate":
                    self.yaw_mode, self.yaw_rate_cmd = "hold", 0.0
                return self._hold()
            self._tau = VEL_TAU
            return self.vel_target
        if self.guided == "position":
            return self._pos_ctrl(self.pos_target, self.wp_speed(), self._speed_up(), self._speed_dn())
        if self.guided == "posvel":
            return self._posvel()
        return self._hold()

    def _posvel(self) -> tuple[float, float, float]:
        """ModeGuided::posvelaccel_control_run: the target moves on with its velocity (AC_PosControl's
        input_pos_vel_accel_xy/z integrate it each loop), the velocity is fed forward and the position error
        corrected (sqrt-shaped far off); GUID_TIMEOUT without a new target zeroes the velocity (the target stops
        where it got to) and a turning yaw holds."""
        dt = self.t - self.posvel_time
        self.posvel_time = self.t
        if self.t - self.vel_time > float(self.params["GUID_TIMEOUT"]):
            self.vel_target = (0.0, 0.0, 0.0)
            if self.yaw_mode in ("rate", "angle_rate"):
                self.yaw_mode, self.yaw_rate_cmd = "hold", 0.0
        vn, ve, vd = self.vel_target
        tn, te, td = self.pos_target
        self.pos_target = (tn + vn * dt, te + ve * dt, min(td + vd * dt, 0.0))
        cn, ce, cd = self._pos_ctrl(self.pos_target, 20.0, 20.0, 20.0, DECEL_XY)
        return vn + cn, ve + ce, vd + cd

    def _fence_check(self) -> None:
        """Copter::fence_check with AC_Fence::check: a new breach of the ceiling, of the circle around home or
        of the polygon fence uploaded (FENCE_TYPE bit 4, missions.py) sends FENCE_STATUS at once (AC_Fence::record_breach) and, armed, turns the vehicle back: FENCE_ACTION 1
        RTL (LAND if RTL cannot be set or it is more than 100 m out), 2 LAND; on the ground it disarms."""
        breaches = 0
        if self.params["FENCE_ENABLE"]:
            types = int(self.params["FENCE_TYPE"])
            over = -self.d - float(self.params["FENCE_ALT_MAX"])
            out = math.hypot(self.n, self.e) - float(self.params["FENCE_RADIUS"])
            breaches = (1 if types & 1 and over >= 0 else 0) | (2 if types & 2 and out >= 0 else 0) \
                | (4 if types & 4 and self.polygon_fence_breach(self.n, self.e) else 0)    # missions.py
        new = breaches & ~self.fence_breaches
        self.fence_breaches = breaches
        if not new:
            return
        self.fence_breach_count += 1
        self.fence_breach_time = self.time_boot_ms()
        self._send_now("FENCE_STATUS")
        action = int(self.params["FENCE_ACTION"])
        if not self.armed or action == 0:
            return
        if self.landed:
            self._disarm("Disarming motors" if self.profile.arm_texts else None)
        elif action == 2 or max(over if new & 1 else 0.0, out if new & 2 else 0.0) > 100.0 \
                or not self.set_mode(MODES["RTL"]):
            self.set_mode(MODES["LAND"])

    def _rtl(self) -> tuple[float, float, float]:
        rtl_alt = max(float(self.params["RTL_ALT"]) / 100.0, 1.0)
        if self.rtl_phase == "climb":
            if self.hold_point is None:
                self._hold()
                if self.hold_point is None:
                    return 0.0, 0.0, 0.0
            self.rtl_alt = max(rtl_alt, -self.d)
            target = (self.hold_point[0], self.hold_point[1], -self.rtl_alt)
            if -self.d >= self.rtl_alt - 0.2:
                self.rtl_phase = "return"
                self.yaw_mode = "look_ahead"
            return self._pos_ctrl(target, self.wp_speed(), self._speed_up(), self._speed_dn())
        if self.rtl_phase == "return":
            speed = float(self.params["RTL_SPEED"]) / 100.0 or self.wp_speed()
            target = (0.0, 0.0, -self.rtl_alt)
            if math.hypot(self.n, self.e) < 0.3 and math.hypot(self.vn, self.ve) < 0.3:
                self.rtl_phase = "loiter"
                self.rtl_loiter_until = self.t + float(self.params["RTL_LOIT_TIME"]) / 1000.0
                self.yaw_mode = "hold"
            return self._pos_ctrl(target, speed, self._speed_up(), self._speed_dn())
        if self.rtl_phase == "loiter":
            if self.t >= self.rtl_loiter_until:
                self.rtl_phase = "land"
                self.hold_point = None
            return self._pos_ctrl((0.0, 0.0, -self.rtl_alt), self.wp_speed(), self._speed_up(), self._speed_dn())
        # final descent
        vn, ve, _ = self._hold(keep_down=self.d)
        return vn, ve, self._land_speed()

    def _battery(self, dt: float) -> None:
        if not self.armed:
            current = 0.5
        elif self.landed:
            current = 2.0
        else:
            current = 15.0 + 0.6 * math.hypot(self.vn, self.ve) + 3.0 * max(0.0, -self.vd)
        self.current = current
        self.consumed_mah += current * dt / 3.6
        cells = self.config.battery_cells
        self.voltage = max(0.0, cells * self._ocv(self.remaining / 100.0) - current * 0.01 * cells)

    @property
    def remaining(self) -> float:
        return _clamp(100.0 * (1.0 - self.consumed_mah / max(1.0, float(self.params["BATT_CAPACITY"]))), 0.0, 100.0)

    @staticmethod
    def _ocv(charge: float) -> float:
        """Open-circuit LiPo cell voltage for a state of charge 0..1."""
        table = ((0.0, 3.0), (0.05, 3.3), (0.17, 3.81), (0.5, 3.93), (0.9, 4.1), (1.0, 4.2))
        charge = _clamp(charge, 0.0, 1.0)
        for (c0, v0), (c1, v1) in zip(table, table[1:]):
            if charge <= c1:
                return v0 + (v1 - v0) * (charge - c0) / (c1 - c0)
        return table[-1][1]
