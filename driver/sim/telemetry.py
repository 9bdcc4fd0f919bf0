"""What the simulated ArduCopter says: one builder per MAVLink message it sends.

Mixed into :class:`~driver.sim.autopilot.Autopilot`; each ``_msg_<name>`` reads
the vehicle's state and returns a message object (or None when it has nothing
to say, e.g. HOME_POSITION before home is set, LOCAL_POSITION_NED before the EKF
has a position). Streams and requests look the builders up by message name.
What is said when follows the 4.7 recording: nothing streamed before "ArduPilot
Ready", GLOBAL_POSITION_INT at 0, 0 until the GPS has a fix, LOCAL_POSITION_NED
(from the EKF origin) only once the EKF uses GPS.
"""
from __future__ import annotations

import math
import time

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .common import clamp, wrap_lon
from .profiles import speaks_mavlink2

__all__ = ["Telemetry", "EARTH_RADIUS", "METRES_PER_DEG", "GRAVITY", "clamp"]

EARTH_RADIUS = 6378137.0
METRES_PER_DEG = EARTH_RADIUS * math.pi / 180.0     # flat earth, as the driver converts
GRAVITY = 9.80665
# Earth's field near Madrid in milligauss (NED).
MAG_NED = (255.0, -2.0, 370.0)
# Modes whose base_mode carries MAV_MODE_FLAG_GUIDED_ENABLED (GCS_MAVLINK_Copter::base_mode).
GUIDED_FLAG_MODES = {3, 6, 5, 19, 23, 4, 7, 16, 17, 21}
GUIDED = 4

SENSORS_PRESENT = (
    mavlink.MAV_SYS_STATUS_SENSOR_3D_GYRO | mavlink.MAV_SYS_STATUS_SENSOR_3D_ACCEL
    | mavlink.MAV_SYS_STATUS_SENSOR_3D_MAG | mavlink.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE
    | mavlink.MAV_SYS_STATUS_SENSOR_GPS | mavlink.MAV_SYS_STATUS_SENSOR_ANGULAR_RATE_CONTROL
    | mavlink.MAV_SYS_STATUS_SENSOR_ATTITUDE_STABILIZATION | mavlink.MAV_SYS_STATUS_SENSOR_YAW_POSITION
    | mavlink.MAV_SYS_STATUS_SENSOR_Z_ALTITUDE_CONTROL | mavlink.MAV_SYS_STATUS_SENSOR_XY_POSITION_CONTROL
    | mavlink.MAV_SYS_STATUS_SENSOR_MOTOR_OUTPUTS | mavlink.MAV_SYS_STATUS_AHRS
    | mavlink.MAV_SYS_STATUS_LOGGING | mavlink.MAV_SYS_STATUS_SENSOR_BATTERY
    | mavlink.MAV_SYS_STATUS_PREARM_CHECK)
SENSORS_NEED_READY = (mavlink.MAV_SYS_STATUS_SENSOR_GPS | mavlink.MAV_SYS_STATUS_AHRS
                      | mavlink.MAV_SYS_STATUS_PREARM_CHECK)
EKF_GOOD = (mavlink.EKF_ATTITUDE | mavlink.EKF_VELOCITY_HORIZ | mavlink.EKF_VELOCITY_VERT
            | mavlink.EKF_POS_HORIZ_REL | mavlink.EKF_POS_HORIZ_ABS | mavlink.EKF_POS_VERT_ABS
            | mavlink.EKF_PRED_POS_HORIZ_REL | mavlink.EKF_PRED_POS_HORIZ_ABS)
# Recording: 0xa7 while aligning (attitude, velocities, vertical position, constant-position mode).
EKF_ALIGNING = (mavlink.EKF_ATTITUDE | mavlink.EKF_VELOCITY_HORIZ | mavlink.EKF_VELOCITY_VERT
                | mavlink.EKF_POS_VERT_ABS | mavlink.EKF_CONST_POS_MODE)


class Telemetry:
    """Message builders; the state they read (n, e, d, yaw, ...) belongs to the Autopilot."""

    def _can_send(self, name: str) -> bool:
        """Whether this vehicle has the message at all (what REQUEST_MESSAGE / SET_MESSAGE_INTERVAL accept)."""
        if name == "EXTENDED_SYS_STATE" and not self.profile.extended_sys_state:
            return False
        return hasattr(self, "_msg_" + name.lower())

    def _local(self) -> tuple[float, float, float]:
        """Where the vehicle is from the EKF origin (NED m): what LOCAL_POSITION_NED reports."""
        on, oe, od = self.origin
        return self.n - on, self.e - oe, self.d - od

    def _msg_heartbeat(self):
        base = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED \
            | mavlink.MAV_MODE_FLAG_MANUAL_INPUT_ENABLED
        if self.mode in GUIDED_FLAG_MODES:
            base |= mavlink.MAV_MODE_FLAG_GUIDED_ENABLED
        if self.armed:
            base |= mavlink.MAV_MODE_FLAG_SAFETY_ARMED
        if not self.initialised:
            status = mavlink.MAV_STATE_BOOT                 # recording: until "ArduPilot Ready"
        elif self.armed and not self.landed:
            status = mavlink.MAV_STATE_ACTIVE
        else:
            status = mavlink.MAV_STATE_STANDBY              # exactly while land_complete
        return self.factory.heartbeat_encode(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
                                             base, self.mode, status, 3)

    def _lat_lon(self) -> tuple[float, float]:
        return self.home_lat + self.n / METRES_PER_DEG, wrap_lon(self.home_lon + self.e / self.m_per_deg_lon)

    def _noise(self, size: float) -> float:
        return self.rng.gauss(0.0, size)

    def _msg_sys_status(self):
        if not self.initialised:
            return None
        health = SENSORS_PRESENT & ~SENSORS_NEED_READY
        stage = self.stage
        if stage.gps_fix:
            health |= mavlink.MAV_SYS_STATUS_SENSOR_GPS
        if stage.ahrs_ok:
            health |= mavlink.MAV_SYS_STATUS_AHRS
        if self.armed or (self.ready and not self.failing_prearm()):
            health |= mavlink.MAV_SYS_STATUS_PREARM_CHECK
        # ArduPilot sets the geofence health bit whenever the fence has not failed, present or not
        # (GCS_MAVLINK::update_sensor_status_flags); without it MAVProxy announces "fence breach".
        health |= mavlink.MAV_SYS_STATUS_GEOFENCE
        enabled = SENSORS_PRESENT
        return self.factory.sys_status_encode(
            SENSORS_PRESENT, enabled, health, 150 + int(self.rng.random() * 20),
            int(self.voltage * 1000), int(self.current * 100), int(round(self.remaining)), 0, 0, 0, 0, 0, 0)

    def _msg_battery_status(self):
        mv = min(int(self.voltage * 1000), 65534)
        voltages = [mv] + [65535] * 9
        return self.factory.battery_status_encode(
            0, mavlink.MAV_BATTERY_FUNCTION_ALL, mavlink.MAV_BATTERY_TYPE_LIPO, 32767, voltages,
            int(self.current * 100), int(self.consumed_mah), -1, int(round(self.remaining)), 0,
            mavlink.MAV_BATTERY_CHARGE_STATE_OK)

    def _msg_power_status(self):
        return self.factory.power_status_encode(5000, 0, mavlink.MAV_POWER_STATUS_BRICK_VALID)

    def _msg_meminfo(self):
        return self.factory.meminfo_encode(0, 65535, 131072)

    def _msg_attitude(self):
        return self.factory.attitude_encode(
            self.time_boot_ms(), self.roll + self._noise(0.0005), self.pitch + self._noise(0.0005), self.yaw,
            self.roll_rate, self.pitch_rate, self.yaw_rate)

    def _msg_global_position_int(self):
        lat, lon = self._lat_lon() if self.stage.gps_fix else (0.0, 0.0)
        hdg = int(round(math.degrees(self.yaw) * 100)) % 36000
        return self.factory.global_position_int_encode(
            self.time_boot_ms(), int(round(lat * 1e7)), int(round(lon * 1e7)),
            int(round((self.home_alt - self.d) * 1000)), int(round(-self.d * 1000)),
            int(round(self.vn * 100)), int(round(self.ve * 100)), int(round(self.vd * 100)), hdg)

    def _msg_fence_status(self):
        """Only while the fence is enabled (Copter::fence_send_mavlink_status)."""
        if not self.params["FENCE_ENABLE"]:
            return None
        kind = (mavlink.FENCE_BREACH_BOUNDARY if self.fence_breaches & 6 else
                mavlink.FENCE_BREACH_MAXALT if self.fence_breaches & 1 else mavlink.FENCE_BREACH_NONE)
        return self.factory.fence_status_encode(int(bool(self.fence_breaches)), self.fence_breach_count, kind,
                                                self.fence_breach_time)

    def _msg_local_position_ned(self):
        if not self.ready:
            return None
        return self.factory.local_position_ned_encode(self.time_boot_ms(), *self._local(), self.vn, self.ve, self.vd)

    def _spinning(self) -> bool:
        """Armed and past the arming delay (ArduCopter holds the motors at minimum for 2 s)."""
        return self.armed and self.t >= self.armed_at + self.profile.arming_delay

    def _throttle(self) -> int:
        if not self.armed:
            return 0
        if self.landed:
            return 0
        return int(clamp(40 - 8 * self.vd + 2 * math.hypot(self.vn, self.ve), 0, 100))

    def _msg_vfr_hud(self):
        speed = math.hypot(self.vn, self.ve)
        return self.factory.vfr_hud_encode(speed, speed, int(math.degrees(self.yaw) % 360.0) % 360,
                                           self._throttle(), self.home_alt - self.d, -self.vd)

    def _msg_gps_raw_int(self):
        usec = int(self.t * 1e6)
        if not self.stage.gps_fix:
            sats = min(4, int(5 * self.boot_seconds / max(self.config.ready_after, 1e-3)))
            return self.factory.gps_raw_int_encode(usec, mavlink.GPS_FIX_TYPE_NO_FIX, 0, 0, 0, 9999, 9999,
                                                   0, 0, sats)
        lat, lon = self._lat_lon()
        speed = math.hypot(self.vn, self.ve)
        cog = int(math.degrees(math.atan2(self.ve, self.vn)) % 360.0 * 100) % 36000 if speed > 0.2 else 0
        return self.factory.gps_raw_int_encode(
            usec, mavlink.GPS_FIX_TYPE_3D_FIX, int(round(lat * 1e7)), int(round(lon * 1e7)),
            int(round((self.home_alt - self.d) * 1000)), 121, 200, int(speed * 100), cog, 10,
            int(round((self.home_alt + 51.0 - self.d) * 1000)), 300, 500, 150, 0, 0)

    def _origin_lat_lon_alt(self) -> tuple[float, float, float]:
        on, oe, od = self.origin
        return self.home_lat + on / METRES_PER_DEG, self.home_lon + oe / self.m_per_deg_lon, self.home_alt - od

    def _msg_home_position(self):
        """Home in the world and from the EKF origin (x, y, z: where home is in LOCAL_POSITION_NED's frame)."""
        if not self.home_set:
            return None
        on, oe, od = self.origin
        return self.factory.home_position_encode(
            int(round(self.home_lat * 1e7)), int(round(self.home_lon * 1e7)), int(round(self.home_alt * 1000)),
            -on, -oe, -od, [1.0, 0.0, 0.0, 0.0], 0.0, 0.0, 0.0, int(self.t * 1e6))

    def _msg_gps_global_origin(self):
        if not self.home_set:
            return None
        lat, lon, alt = self._origin_lat_lon_alt()
        return self.factory.gps_global_origin_encode(int(round(lat * 1e7)), int(round(lon * 1e7)),
                                                     int(round(alt * 1000)), int(self.t * 1e6))

    def _msg_extended_sys_state(self):
        if not self.profile.extended_sys_state:
            return None
        return self.factory.extended_sys_state_encode(mavlink.MAV_VTOL_STATE_UNDEFINED, self.landed_state())

    def _msg_ekf_status_report(self):
        ekf = self.stage.ekf
        if ekf == "good":
            return self.factory.ekf_status_report_encode(EKF_GOOD, 0.02, 0.01, 0.01, 0.02, 0.0)
        if ekf == "aligning":
            return self.factory.ekf_status_report_encode(EKF_ALIGNING, 0.8, 1.0, 0.2, 0.1, 0.0)
        return self.factory.ekf_status_report_encode(mavlink.EKF_UNINITIALIZED if ekf == "uninitialised" else 0,
                                                     0.0, 0.0, 0.0, 0.0, 0.0)

    def _msg_scaled_pressure(self):
        alt = self.home_alt - self.d
        hpa = 1013.25 * (1.0 - 2.25577e-5 * alt) ** 5.25588 + self._noise(0.01)
        temp = 15.0 - 0.0065 * alt + 10.0
        return self.factory.scaled_pressure_encode(self.time_boot_ms(), hpa, 0.0, int(temp * 100))

    def _mag_body(self) -> tuple[int, int, int]:
        cr, sr = math.cos(self.roll), math.sin(self.roll)
        cp, sp = math.cos(self.pitch), math.sin(self.pitch)
        cy, sy = math.cos(self.yaw), math.sin(self.yaw)
        n, e, d = MAG_NED
        # NED → body: transpose of the body→NED direction cosine matrix.
        x = cp * cy * n + cp * sy * e - sp * d
        y = (sr * sp * cy - cr * sy) * n + (sr * sp * sy + cr * cy) * e + sr * cp * d
        z = (cr * sp * cy + sr * sy) * n + (cr * sp * sy - sr * cy) * e + cr * cp * d
        return int(round(x)), int(round(y)), int(round(z))

    def _imu(self) -> tuple[int, ...]:
        """RAW_IMU units: mG, mrad/s, mgauss. In flight the accelerometer feels only thrust (body z)."""
        if self.armed and not self.landed:
            climb_acc = self.acc_body[2] + GRAVITY           # d(vd)/dt, NED
            tilt = max(0.5, math.cos(self.roll) * math.cos(self.pitch))
            ax, ay, az = 0.0, 0.0, -1000.0 * (GRAVITY - climb_acc) / GRAVITY / tilt
        else:
            ax = 1000.0 * math.sin(self.pitch)
            ay = -1000.0 * math.sin(self.roll) * math.cos(self.pitch)
            az = -1000.0 * math.cos(self.roll) * math.cos(self.pitch)
        gx = int(round(self.roll_rate * 1000))
        gy = int(round(self.pitch_rate * 1000))
        gz = int(round(self.yaw_rate * 1000))
        acc = (int(round(a + self._noise(3.0))) for a in (ax, ay, az))
        return (*acc, gx, gy, gz, *self._mag_body())

    def _msg_raw_imu(self):
        return self.factory.raw_imu_encode(int(self.t * 1e6), *self._imu(), 0, 4500)

    def _msg_scaled_imu2(self):
        return self.factory.scaled_imu2_encode(self.time_boot_ms(), *self._imu(), 4500)

    def _msg_wind(self):
        return self.factory.wind_encode(0.0, 0.0, 0.0)

    def _msg_vibration(self):
        level = 0.02 if not self.armed else 3.0 + self.rng.random()
        return self.factory.vibration_encode(int(self.t * 1e6), level, level, level * 1.3, 0, 0, 0)

    def _msg_system_time(self):
        return self.factory.system_time_encode(int(time.time() * 1e6), self.time_boot_ms())

    def _msg_nav_controller_output(self):
        bearing = int(math.degrees(self.yaw)) % 360
        dist, target_bearing, alt_error = 0, bearing, 0.0
        if self.mode == GUIDED and self.guided == "position":
            dn, de = self.pos_target[0] - self.n, self.pos_target[1] - self.e
            dist = int(min(math.hypot(dn, de), 65535))
            target_bearing = int(math.degrees(math.atan2(de, dn))) % 360
            alt_error = self.d - self.pos_target[2]
        return self.factory.nav_controller_output_encode(math.degrees(self.roll), math.degrees(self.pitch),
                                                         bearing, target_bearing, dist, alt_error, 0.0, 0.0)

    def _msg_servo_output_raw(self):
        if not self._spinning():
            pwm = 1000
        elif self.landed:
            pwm = 1150
        else:
            pwm = 1000 + 10 * self._throttle()
        return self.factory.servo_output_raw_encode(int(self.t * 1e6) & 0xFFFFFFFF, 0, pwm, pwm, pwm, pwm,
                                                    0, 0, 0, 0)

    def _msg_rc_channels(self):
        return self.factory.rc_channels_encode(self.time_boot_ms(), 0, *([0] * 18), 0)

    def _msg_autopilot_version(self):
        caps = (mavlink.MAV_PROTOCOL_CAPABILITY_MISSION_FLOAT | mavlink.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT
                | mavlink.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
                | mavlink.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED
                | mavlink.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_GLOBAL_INT
                | mavlink.MAV_PROTOCOL_CAPABILITY_FLIGHT_TERMINATION
                | mavlink.MAV_PROTOCOL_CAPABILITY_COMPASS_CALIBRATION)
        if speaks_mavlink2(self.config):
            caps |= mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2
        if self.profile.mavlink2:          # 4.x: MISSION_ITEM_INT and mission_type (3.3 has neither)
            caps |= (mavlink.MAV_PROTOCOL_CAPABILITY_MISSION_INT | mavlink.MAV_PROTOCOL_CAPABILITY_MISSION_FENCE
                     | mavlink.MAV_PROTOCOL_CAPABILITY_MISSION_RALLY)
        major, minor, patch, kind = self.profile.version
        if major >= 4:
            caps |= mavlink.MAV_PROTOCOL_CAPABILITY_FTP      # @PARAM/param.pck (sim/ftp.py), as 4.6.3 says
        version = (major << 24) | (minor << 16) | (patch << 8) | kind
        # as 4.6.3 SITL (the mission recording): no board id, no USB ids, uid 0, the git hash, uid2 the machine id
        # as ASCII (17 characters and a NUL); 3.3 (GCS_Common.cpp) has no uid2 and sends 0 for the board too
        custom = list(self.profile.git_hash.encode()[:8].ljust(8, b"\0"))
        uid2 = list(self.profile.banner_id.encode()[:17].ljust(18, b"\0")) if self.profile.banner_id_on_list else [0] * 18
        return self.factory.autopilot_version_encode(caps, version, 0, 0, 0, custom, [0] * 8, [0] * 8, 0, 0, 0, uid2)
