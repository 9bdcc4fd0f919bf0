"""Conversions between the driver's world and JdeRobot's (documented in docs/ice.md).

JdeRobot speaks ENU and FLU (x east, y north, z up; body x forward, y left,
z up, yaw counter-clockwise). The driver speaks NED and FRD like the autopilot.
Everything that crosses between them goes through here, as plain functions the
servants and the client share and the tests check without a network.
"""
from __future__ import annotations

import math
import time

from ..core.frames import clamp, enu_quaternion, finite, wrap_pi
from .plans import mission_from_ice, mission_to_ice, outcome_from_result, result_from_outcome
from ..vehicle.state import (Attitude, Battery, Boot, CommandResult, CommandStatus, Environment, Fence, GlobalPosition, Gps,
                     LandedState, LinkHealth, LinkStatus, LocalPosition, Message, Readiness, SequencePhase,
                     SequenceProgress, SequenceState, Setpoint, Severity, VehicleState, Velocity)

# AR.Drone navdata states, as JdeRobot's Navdata carries them.
NAV_UNKNOWN, NAV_INITED, NAV_LANDED, NAV_FLYING, NAV_HOVERING, NAV_TEST, NAV_TAKING_OFF, NAV_GOTO, NAV_LANDING, \
    NAV_LOOPING = range(10)
_GOTO_MODES = ("AUTO", "RTL", "SMART_RTL", "CIRCLE")


# -- Pose3D -------------------------------------------------------------------------------------
def pose_enu(state: VehicleState) -> tuple[float, float, float, float, float, float, float, float]:
    """(x, y, z, h, q0, q1, q2, q3): metres from home east/north/up and the FLU-in-ENU quaternion."""
    a = state.attitude
    x, y, z = state.local.enu if state.local is not None else (0.0, 0.0, state.altitude)
    q = enu_quaternion(a.roll, a.pitch, a.yaw) if finite(a.roll, a.pitch, a.yaw) else (1.0, 0.0, 0.0, 0.0)
    x, y, z = (v if math.isfinite(v) else 0.0 for v in (x, y, z))
    return (x, y, z, 1.0, *q)


def waypoint_from_enu(x: float, y: float, z: float) -> tuple[float, float, float] | None:
    """(north, east, altitude) for the driver's go_to, or None if a value is not finite."""
    if not finite(x, y, z):
        return None
    return (y, x, z)


# -- CMDVel -------------------------------------------------------------------------------------
def body_from_cmdvel(linear_x: float, linear_y: float, linear_z: float,
                     angular_z: float) -> tuple[float, float, float, float]:
    """JdeRobot FLU (forward, left, up, yaw rate counter-clockwise) → driver (forward, right, up, nose right)."""
    return (linear_x, -linear_y, linear_z, -angular_z)


def cmdvel_from_body(forward: float, right: float, up: float, yaw_rate: float) -> tuple[float, float, float, float]:
    """Driver (forward, right, up, yaw rate nose right) → JdeRobot (linearX, linearY, linearZ, angularZ)."""
    return (forward, -right, up, -yaw_rate)


def clamp_cmdvel(values: tuple[float, float, float, float],
                 maxima: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    return tuple(clamp(v, m) for v, m in zip(values, maxima))  # type: ignore[return-value]


# -- Navdata ------------------------------------------------------------------------------------
def navdata_state(state: VehicleState) -> int:
    """The AR.Drone state that best says what the copter is doing."""
    if state.link.status is not LinkStatus.OK or not state.mode:
        return NAV_UNKNOWN
    if state.takeoff.active or (state.armed and state.landed_state is LandedState.TAKEOFF):
        return NAV_TAKING_OFF
    if not state.flying:
        return NAV_LANDED
    if state.landed_state is LandedState.LANDING or state.mode == "LAND":
        return NAV_LANDING
    if state.mode in _GOTO_MODES:
        return NAV_GOTO
    v = state.velocity
    still = v.ground_speed < 0.3 and abs(v.down) < 0.2 and abs(state.attitude.yawspeed) < 0.1
    return NAV_HOVERING if still else NAV_FLYING


def navdata_fields(state: VehicleState, vehicle: int = 1, clock: float = 0.0) -> dict:
    """Keyword arguments for ``jderobot.NavdataData``, every field MAVLink can fill."""
    a, env = state.attitude, state.environment
    forward, right, down = state.velocity.body(a.yaw)
    yaw_enu = math.pi / 2.0 - a.yaw
    fields = dict(
        vehicle=vehicle,
        state=navdata_state(state),
        batteryPercent=float(state.battery.remaining) if state.battery.remaining is not None else 0.0,
        rotX=math.degrees(a.roll),                                   # FLU: roll right positive
        rotY=math.degrees(-a.pitch),                                 # FLU: nose down positive
        rotZ=math.degrees(math.atan2(math.sin(yaw_enu), math.cos(yaw_enu))),   # ENU yaw, as Pose3D's
        altd=_int(state.altitude * 1000.0),
        vx=forward * 1000.0, vy=-right * 1000.0, vz=-down * 1000.0,  # body FLU, mm/s
        tagsCount=0, tagsType=[], tagsXc=[], tagsYc=[], tagsWidth=[], tagsHeight=[],
        tagsOrientation=[], tagsDistance=[],
        tm=float(clock),
        windCompAngle=0.0,
    )
    if env.mag is not None:
        fields.update(magX=_int(env.mag[0]), magY=_int(env.mag[1]), magZ=_int(env.mag[2]))
    else:
        fields.update(magX=0, magY=0, magZ=0)
    if env.accel_g is not None:                                      # IMU FRD → FLU
        fields.update(ax=float(env.accel_g[0]), ay=-float(env.accel_g[1]), az=-float(env.accel_g[2]))
    else:
        fields.update(ax=0.0, ay=0.0, az=0.0)
    fields["pressure"] = _int(env.pressure_hpa * 100.0) if env.pressure_hpa is not None else 0   # Pa
    fields["temp"] = _int(env.temperature_c) if env.temperature_c is not None else 0              # deg C
    fields["windSpeed"] = float(env.wind_speed) if env.wind_speed is not None else 0.0
    fields["windAngle"] = float(env.wind_direction_deg) if env.wind_direction_deg is not None else 0.0
    return {k: (v if not isinstance(v, float) or math.isfinite(v) else 0.0) for k, v in fields.items()}


def _int(value: float) -> int:
    if not math.isfinite(value):
        return 0
    return int(max(-2**31, min(2**31 - 1, round(value))))


# -- a plain JdeRobot server: Pose3D + Navdata -> VehicleState -----------------------------------
def attitude_from_enu_quaternion(q0: float, q1: float, q2: float, q3: float) -> tuple[float, float, float]:
    """NED (roll, pitch, yaw) of a FLU-in-ENU quaternion; inverse of :func:`driver.core.frames.enu_quaternion`."""
    from pymavlink.quaternion import QuaternionBase
    if not finite(q0, q1, q2, q3) or q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3 < 1e-9:
        return (0.0, 0.0, 0.0)
    roll, pitch_enu, yaw_enu = (float(a) for a in QuaternionBase([q0, q1, q2, q3]).euler)
    return (roll, -pitch_enu, wrap_pi(math.pi / 2.0 - yaw_enu))


def state_from_jderobot(pose, nav, messages: tuple[Message, ...] = (),
                        results: tuple[CommandResult, ...] = ()) -> VehicleState:
    """What JdeRobot's Pose3D and Navdata (``nav`` may be None) say, as a driver snapshot.

    Navdata's AR.Drone state stands for armed / landed state / mode; a flying
    vehicle is shown in GUIDED, the mode in which velocity commands are obeyed.
    """
    roll, pitch, yaw = attitude_from_enu_quaternion(pose.q0, pose.q1, pose.q2, pose.q3)
    x, y, z = (v if math.isfinite(v) else 0.0 for v in (pose.x, pose.y, pose.z))
    fields: dict = dict(time=time.time(), attitude=Attitude(roll=roll, pitch=pitch, yaw=yaw),
                        local=LocalPosition(north=y, east=x, down=-z), altitude=z,
                        heading_deg=math.degrees(yaw) % 360.0, messages=messages, results=results,
                        link=LinkHealth(status=LinkStatus.OK), mode="JDEROBOT")
    if nav is not None:
        forward, left, up = (v / 1000.0 if math.isfinite(v) else 0.0 for v in (nav.vx, nav.vy, nav.vz))
        c, s = math.cos(yaw), math.sin(yaw)
        flying = nav.state in (NAV_FLYING, NAV_HOVERING, NAV_GOTO, NAV_TAKING_OFF, NAV_LANDING, NAV_LOOPING)
        landed = {NAV_TAKING_OFF: LandedState.TAKEOFF, NAV_LANDING: LandedState.LANDING,
                  NAV_LANDED: LandedState.ON_GROUND, NAV_INITED: LandedState.ON_GROUND}.get(
            nav.state, LandedState.IN_AIR if flying else LandedState.UNDEFINED)
        fields.update(
            velocity=Velocity(north=c * forward + s * left, east=s * forward - c * left, down=-up),
            battery=Battery(remaining=float(nav.batteryPercent)) if math.isfinite(nav.batteryPercent) else Battery(),
            armed=flying, landed_state=landed,
            mode="LAND" if nav.state == NAV_LANDING else "GUIDED" if flying else "JDEROBOT",
            link=LinkHealth(status=LinkStatus.WAITING if nav.state == NAV_UNKNOWN else LinkStatus.OK))
    return VehicleState(**fields)


# -- mavlinkserver extension: VehicleState <-> VehicleStatus ------------------------------------
def _opt(value) -> tuple[bool, float]:
    return (value is not None, float(value) if value is not None else 0.0)


def fence_to_ice(ms, fence: Fence):
    """The ``mavlinkserver.Fence`` of the driver's fence."""
    has_enabled, enabled = _opt(fence.enabled)
    has_types, types = _opt(fence.types)
    has_radius, radius = _opt(fence.radius)
    has_alt, alt_max = _opt(fence.alt_max)
    return ms.Fence(hasEnabled=has_enabled, enabled=bool(enabled), hasTypes=has_types, types=int(types),
                    hasRadius=has_radius, radius=radius, hasAltMax=has_alt, altMax=alt_max,
                    breached=bool(fence.breached))


def fence_from_ice(f) -> Fence:
    """The driver's fence from a ``mavlinkserver.Fence``; a value that is not finite counts as not read."""
    def known(has: bool, value):
        return value if has and math.isfinite(value) else None
    return Fence(enabled=bool(f.enabled) if f.hasEnabled else None, types=int(f.types) if f.hasTypes else None,
                 radius=known(f.hasRadius, f.radius), alt_max=known(f.hasAltMax, f.altMax),
                 breached=bool(f.breached) if f.hasEnabled and f.enabled else None)


def status_from_state(ms, s: VehicleState, messages_since: int = -1, results_since: int = -1):
    """The ``mavlinkserver.VehicleStatus`` of a snapshot, with only the messages and results after the indices."""
    link, bat, gps, env, a = s.link, s.battery, s.gps, s.environment, s.attitude

    def global_pos(p: GlobalPosition | None):
        return ms.GlobalPosition(valid=p is not None, lat=p.lat if p else 0.0, lon=p.lon if p else 0.0,
                                 alt=p.alt if p else 0.0)

    has_age, age = _opt(link.heartbeat_age)
    has_v, volts = _opt(bat.voltage)
    has_c, amps = _opt(bat.current)
    has_r, remaining = _opt(bat.remaining)
    has_hdop, hdop = _opt(gps.hdop)
    has_p, pressure = _opt(env.pressure_hpa)
    has_t, temperature = _opt(env.temperature_c)
    has_ws, wind_speed = _opt(env.wind_speed)
    has_wd, wind_dir = _opt(env.wind_direction_deg)
    mag = env.mag or (0, 0, 0)
    acc = env.accel_g or (0.0, 0.0, 0.0)
    local = s.local
    return ms.VehicleStatus(
        time=s.time,
        link=ms.LinkHealth(status=link.status.name, address=link.address, hasHeartbeatAge=has_age,
                           heartbeatAge=age, packetsPerSecond=link.packets_per_s, lossPercent=link.loss_percent,
                           packetsReceived=link.packets_received, packetsLost=link.packets_lost,
                           badCrc=link.bad_crc, mavlinkVersion=link.mavlink_version, lostCount=link.lost_count),
        systemId=s.system_id, vehicleType=s.vehicle_type, mode=s.mode, armed=s.armed,
        landedState=int(s.landed_state),
        attitude=ms.Attitude(roll=a.roll, pitch=a.pitch, yaw=a.yaw, rollspeed=a.rollspeed,
                             pitchspeed=a.pitchspeed, yawspeed=a.yawspeed),
        position=global_pos(s.position), home=global_pos(s.home),
        localPosition=ms.LocalPosition(valid=local is not None, north=local.north if local else 0.0,
                               east=local.east if local else 0.0, down=local.down if local else 0.0),
        velocity=ms.Velocity(north=s.velocity.north, east=s.velocity.east, down=s.velocity.down),
        altitude=s.altitude, headingDeg=s.heading_deg, airspeed=s.airspeed,
        battery=ms.Battery(hasVoltage=has_v, voltage=volts, hasCurrent=has_c, current=amps, hasRemaining=has_r,
                           remaining=remaining, remainingEstimated=bat.remaining_estimated, cells=bat.cells,
                           low=bat.low),
        gps=ms.Gps(fixType=gps.fix_type, satellites=gps.satellites, hasHdop=has_hdop, hdop=hdop),
        readiness=ms.Readiness(prearmOk=s.readiness.prearm_ok, ekfOk=s.readiness.ekf_ok,
                               gpsOk=s.readiness.gps_ok, reasons=list(s.readiness.reasons)),
        restarts=s.boot.restarts,
        environment=ms.Environment(hasMag=env.mag is not None, magX=int(mag[0]), magY=int(mag[1]),
                                   magZ=int(mag[2]), hasAccel=env.accel_g is not None, accelX=acc[0],
                                   accelY=acc[1], accelZ=acc[2], hasPressure=has_p, pressureHpa=pressure,
                                   hasTemperature=has_t, temperatureC=temperature, hasWindSpeed=has_ws,
                                   windSpeed=wind_speed, hasWindDirection=has_wd, windDirectionDeg=wind_dir,
                                   hasThrottle=env.throttle is not None, throttle=int(env.throttle or 0)),
        messages=[ms.StatusMessage(index=m.index, time=m.time, severity=int(m.severity), text=m.text,
                                   source=m.source) for m in s.messages_since(messages_since)],
        results=[outcome_from_result(ms, r) for r in s.results_since(results_since)],
        takeoff=ms.TakeoffProgress(phase=s.takeoff.phase.name, detail=s.takeoff.detail,
                                   targetAltitude=s.takeoff.target_altitude),
        setpoint=ms.Setpoint(forward=s.setpoint.forward, right=s.setpoint.right, up=s.setpoint.up,
                             yawRate=s.setpoint.yaw_rate),
        mission=mission_to_ice(ms, s.mission),
        running=ms.SequenceStatus(name=s.sequence.name, state=s.sequence.state, detail=s.sequence.detail),
        mayBeAirborne=s.may_be_airborne,
    )


def message_from_status(m) -> Message:
    try:
        severity = Severity(m.severity)
    except ValueError:
        severity = Severity.INFO
    return Message(index=m.index, time=m.time, severity=severity, text=m.text, source=m.source)


def state_from_status(st, messages: tuple[Message, ...], results: tuple[CommandResult, ...]) -> VehicleState:
    """A driver snapshot from a ``VehicleStatus``; ``messages``/``results`` are the client's accumulated lists."""
    ln, bat, gps, env, a = st.link, st.battery, st.gps, st.environment, st.attitude

    def enum_named(kind, name, default):
        try:
            return kind[name]
        except KeyError:
            return default

    def global_pos(p):
        return GlobalPosition(lat=p.lat, lon=p.lon, alt=p.alt) if p.valid else None

    try:
        landed = LandedState(st.landedState)
    except ValueError:
        landed = LandedState.UNDEFINED
    return VehicleState(
        time=st.time,
        link=LinkHealth(status=enum_named(LinkStatus, ln.status, LinkStatus.WAITING), address=ln.address,
                        heartbeat_age=ln.heartbeatAge if ln.hasHeartbeatAge else None,
                        packets_per_s=ln.packetsPerSecond, loss_percent=ln.lossPercent,
                        packets_received=ln.packetsReceived, packets_lost=ln.packetsLost, bad_crc=ln.badCrc,
                        mavlink_version=ln.mavlinkVersion, lost_count=ln.lostCount),
        system_id=st.systemId, vehicle_type=st.vehicleType, mode=st.mode, armed=st.armed, landed_state=landed,
        attitude=Attitude(roll=a.roll, pitch=a.pitch, yaw=a.yaw, rollspeed=a.rollspeed, pitchspeed=a.pitchspeed,
                          yawspeed=a.yawspeed),
        position=global_pos(st.position), home=global_pos(st.home),
        local=LocalPosition(st.localPosition.north, st.localPosition.east, st.localPosition.down) if st.localPosition.valid else None,
        velocity=Velocity(st.velocity.north, st.velocity.east, st.velocity.down),
        altitude=st.altitude, heading_deg=st.headingDeg, airspeed=st.airspeed,
        battery=Battery(voltage=bat.voltage if bat.hasVoltage else None,      # its alarm: judged here against
                        current=bat.current if bat.hasCurrent else None,      # the default thresholds
                        remaining=bat.remaining if bat.hasRemaining else None,
                        remaining_estimated=bat.remainingEstimated, cells=bat.cells, low=bat.low),
        gps=Gps(fix_type=gps.fixType, satellites=gps.satellites, hdop=gps.hdop if gps.hasHdop else None),
        readiness=Readiness(prearm_ok=st.readiness.prearmOk, ekf_ok=st.readiness.ekfOk, gps_ok=st.readiness.gpsOk,
                            reasons=tuple(st.readiness.reasons)),
        boot=Boot(restarts=st.restarts),
        environment=Environment(
            mag=(env.magX, env.magY, env.magZ) if env.hasMag else None,
            accel_g=(env.accelX, env.accelY, env.accelZ) if env.hasAccel else None,
            pressure_hpa=env.pressureHpa if env.hasPressure else None,
            temperature_c=env.temperatureC if env.hasTemperature else None,
            wind_speed=env.windSpeed if env.hasWindSpeed else None,
            wind_direction_deg=env.windDirectionDeg if env.hasWindDirection else None,
            throttle=env.throttle if env.hasThrottle else None),
        messages=messages, results=results,
        takeoff=SequenceProgress(phase=enum_named(SequencePhase, st.takeoff.phase, SequencePhase.IDLE),
                                 detail=st.takeoff.detail, target_altitude=st.takeoff.targetAltitude),
        setpoint=Setpoint(forward=st.setpoint.forward, right=st.setpoint.right, up=st.setpoint.up,
                          yaw_rate=st.setpoint.yawRate),
        mission=mission_from_ice(st.mission),
        sequence=SequenceState(st.running.name, st.running.state, st.running.detail),
        lifted=st.mayBeAirborne,         # the server's whole view: this side's own derivation can only add to it
    )
