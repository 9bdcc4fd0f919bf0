"""Immutable snapshots of the vehicle, passed freely between threads.

The driver's reader thread builds a new :class:`VehicleState` whenever telemetry
changes something and swaps a single reference; readers (the viewer's timer, an
Ice servant, a test) take that reference and never see a half-updated vehicle.

Frames: NED is the autopilot's (x north, y east, z down, yaw clockwise from
north). ENU is JdeRobot's (x east, y north, z up, yaw counter-clockwise from
east). Angles are radians unless a name says ``_deg``.
"""
from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field, replace

from ..core.results import CommandResult, CommandStatus, LinkStatus, Severity
from ..link.signing import Signing, SigningStatus
from ..mission.plan import MissionProgress
from ..params.model import ParameterTable
from ..payload.model import Gimbal, VehicleCamera
from .battery import Battery, BatteryAlarm, BatteryThresholds
from ..setup.banner import Autopilot
from ..setup.model import SetupState
from ..shots.model import ShotState
from ..traffic.model import Traffic

__all__ = [
    "LandedState", "LinkStatus", "Severity", "CommandStatus", "Attitude", "GlobalPosition",
    "LocalPosition", "Velocity", "BatteryAlarm", "BatteryThresholds", "Battery", "Gps", "Readiness", "Boot",
    "LinkHealth", "SigningStatus", "Signing", "Message",
    "CommandResult", "Setpoint", "SequencePhase", "SequenceProgress", "SequenceState", "Environment", "Fence",
    "FENCE_PARAMS",
    "VehicleState", "replace",
]


MAV_STATE_STANDBY = 3        # MAVLink's MAV_STATE values that ArduCopter uses for "landed" and "flying"
MAV_STATE_ACTIVE = 4


class LandedState(enum.IntEnum):
    """EXTENDED_SYS_STATE.landed_state (MAV_LANDED_STATE)."""
    UNDEFINED = 0
    ON_GROUND = 1
    IN_AIR = 2
    TAKEOFF = 3
    LANDING = 4


@dataclass(frozen=True)
class Attitude:
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0             # NED yaw, clockwise from north, in (-pi, pi]
    rollspeed: float = 0.0
    pitchspeed: float = 0.0
    yawspeed: float = 0.0

    @property
    def quaternion(self) -> tuple[float, float, float, float]:
        """(w, x, y, z) rotating body (FRD) to NED, as pymavlink's Quaternion."""
        from pymavlink.quaternion import QuaternionBase
        w, x, y, z = QuaternionBase([self.roll, self.pitch, self.yaw]).q
        return (float(w), float(x), float(y), float(z))

    @property
    def heading_deg(self) -> float:
        return math.degrees(self.yaw) % 360.0


@dataclass(frozen=True)
class GlobalPosition:
    lat: float                   # degrees
    lon: float                   # degrees
    alt: float                   # metres above mean sea level


@dataclass(frozen=True)
class LocalPosition:
    """Metres from home, NED."""
    north: float = 0.0
    east: float = 0.0
    down: float = 0.0

    @property
    def enu(self) -> tuple[float, float, float]:
        return (self.east, self.north, -self.down)


@dataclass(frozen=True)
class Velocity:
    """Metres per second, NED."""
    north: float = 0.0
    east: float = 0.0
    down: float = 0.0

    @property
    def ground_speed(self) -> float:
        return math.hypot(self.north, self.east)

    @property
    def climb(self) -> float:
        return -self.down

    def body(self, yaw: float) -> tuple[float, float, float]:
        """(forward, right, down) relative to a heading ``yaw`` (NED)."""
        c, s = math.cos(yaw), math.sin(yaw)
        return (c * self.north + s * self.east, -s * self.north + c * self.east, self.down)


@dataclass(frozen=True)
class Gps:
    fix_type: int = 0                    # GPS_FIX_TYPE: 0/1 none, 2 2D, 3 3D, 4+ DGPS/RTK
    satellites: int = 0
    hdop: float | None = None

    @property
    def fix_name(self) -> str:
        return {0: "No GPS", 1: "No fix", 2: "2D fix", 3: "3D fix", 4: "DGPS",
                5: "RTK float", 6: "RTK fixed", 7: "Static", 8: "PPP"}.get(self.fix_type, str(self.fix_type))


@dataclass(frozen=True)
class Readiness:
    """What the autopilot says about being ready to arm (see arducopter.md)."""
    prearm_ok: bool = False              # SYS_STATUS health bit MAV_SYS_STATUS_PREARM_CHECK
    ekf_ok: bool = False                 # EKF_STATUS_REPORT attitude+velocity+position flags
    gps_ok: bool = False                 # GPS_RAW_INT fix_type >= 3
    prearm_reported: bool = False        # the autopilot reports its pre-arm check in SYS_STATUS
    reasons: tuple[str, ...] = ()        # the vehicle's own words for why it will not arm, as its latest
                                         # "PreArm: ..." / "Arm: ..." texts said them (driver.vehicle.prearm)

    @property
    def ready_to_arm(self) -> bool:
        """The vehicle says it may arm: its pre-arm checks pass and no refusal of its own still stands."""
        return self.prearm_ok and self.ekf_ok and self.gps_ok and not self.reasons

    @property
    def missing(self) -> tuple[str, ...]:
        """What the autopilot still lacks before it can arm, in the order it usually arrives; the pre-arm
        checks in the vehicle's own words when it said them ("pre-arm checks: 3D Accel calibration needed")."""
        checks = "pre-arm checks" + (": " + "; ".join(self.reasons) if self.reasons else "")
        return tuple(what for ok, what in ((self.gps_ok, "GPS fix"), (self.ekf_ok, "EKF"),
                                           (self.prearm_ok and not self.reasons, checks)) if not ok)


@dataclass(frozen=True)
class Boot:
    """The vehicle's own clock since it started, and how often it was seen to start again while we listened.

    A restart is the vehicle's clock going back more than 5 s (any ``time_boot_ms``: ATTITUDE,
    GLOBAL_POSITION_INT, SYSTEM_TIME) or its parameter count changing: whatever was known of its plans, its refusals, its
    parameters is then of a vehicle that is no more, and is read again (driver.vehicle.reader)."""
    restarts: int = 0                    # restarts seen since the link opened (0: the boot first heard)
    time_ms: int | None = None           # the newest time_boot_ms heard
    param_count: int | None = None       # PARAM_VALUE.param_count, as last heard

    BACKWARDS_MS = 5000                  # a clock going back further than this is a restart: not the newest of
                                         # two messages folded in one read, one a slow stream's, under loss

    @property
    def seconds(self) -> float | None:
        """The vehicle's time since its boot, in seconds (its own clock: a replay's, a sim's at its speed)."""
        return None if self.time_ms is None else self.time_ms / 1000.0

    def heard_time(self, time_ms: int) -> "Boot":
        """This boot after a message stamped ``time_ms``: a restart when the clock went back."""
        if self.time_ms is not None and time_ms + self.BACKWARDS_MS < self.time_ms:
            return Boot(self.restarts + 1, time_ms, None)
        return self if time_ms == self.time_ms else replace(self, time_ms=max(time_ms, self.time_ms or 0))

    def heard_param_count(self, count: int) -> "Boot":
        """This boot after a PARAM_VALUE counting ``count`` parameters: a restart when the count changed."""
        if self.param_count is not None and count != self.param_count:
            return Boot(self.restarts + 1, None, count)
        return self if count == self.param_count else replace(self, param_count=count)


@dataclass(frozen=True)
class LinkHealth:
    status: LinkStatus = LinkStatus.WAITING
    address: str = ""                    # the connection string
    heartbeat_age: float | None = None   # seconds since the vehicle's last heartbeat
    packets_per_s: float = 0.0
    loss_percent: float = 0.0            # from sequence-number gaps
    packets_received: int = 0
    packets_lost: int = 0
    bad_crc: int = 0
    mavlink_version: int = 1             # what we send: 1 until the vehicle speaks 2
    lost_count: int = 0                  # how many times the link was declared lost
    foreign_packets: int = 0             # UDP datagrams dropped because they did not come from the vehicle
    pinned_to: str = ""                  # UDP: the vehicle's "ip:port", the only address we send to
    replay_ended: bool = False           # a replayed recording has played to its end: CLOSED, nothing was lost
    replay: bool = False                 # the link is a recording played back: nothing on it is live

    @property
    def ended_words(self) -> str:
        """"Replay ended" for a recording played to its end, else "" (its silence is not a lost link)."""
        return "Replay ended" if self.replay_ended else ""


@dataclass(frozen=True)
class Message:
    """A line for the pilot: the autopilot's STATUSTEXT or the driver's own report."""
    index: int                           # increases by one for every message of a session
    time: float                          # wall-clock seconds (time.time())
    severity: Severity
    text: str
    source: str = "vehicle"              # "vehicle" (STATUSTEXT) or "driver"


@dataclass(frozen=True)
class Setpoint:
    """The velocity command the driver is streaming, after clamping."""
    forward: float = 0.0                 # m/s
    right: float = 0.0                   # m/s
    up: float = 0.0                      # m/s
    yaw_rate: float = 0.0                # rad/s, positive = clockwise seen from above (nose right)

    @property
    def is_zero(self) -> bool:
        return self.forward == 0.0 and self.right == 0.0 and self.up == 0.0 and self.yaw_rate == 0.0


class SequencePhase(enum.Enum):
    IDLE = "idle"
    WAITING_READY = "waiting until ready to arm"
    SETTING_GUIDED = "switching to GUIDED"
    ARMING = "arming"
    TAKING_OFF = "taking off"
    CLIMBING = "climbing"
    DONE = "done"
    FAILED = "failed"
    ABORTED = "aborted"


@dataclass(frozen=True)
class SequenceProgress:
    """The takeoff sequence, phase by phase."""
    phase: SequencePhase = SequencePhase.IDLE
    detail: str = ""
    target_altitude: float = 0.0

    @property
    def active(self) -> bool:
        return self.phase in (SequencePhase.WAITING_READY, SequencePhase.SETTING_GUIDED,
                              SequencePhase.ARMING, SequencePhase.TAKING_OFF, SequencePhase.CLIMBING)


@dataclass(frozen=True)
class SequenceState:
    """The sequence the driver runs now (takeoff, mission start, land, RTL, stop) and the state it is in, or the
    last one's end ("done", "failed", "ended"); docs/driver.md draws them."""
    name: str = ""
    state: str = ""
    detail: str = ""


@dataclass(frozen=True)
class Environment:
    """Sensor values JdeRobot's Navdata carries; None where the autopilot sent nothing."""
    mag: tuple[int, int, int] | None = None          # milligauss (SCALED_IMU / RAW_IMU)
    accel_g: tuple[float, float, float] | None = None
    pressure_hpa: float | None = None
    temperature_c: float | None = None
    wind_speed: float | None = None                  # m/s
    wind_direction_deg: float | None = None          # where the wind comes from
    throttle: int | None = None                      # percent (VFR_HUD)


#: The vehicle parameters :class:`Fence` is read from (AC_Fence), in the order the driver asks for them.
FENCE_PARAMS = ("FENCE_ENABLE", "FENCE_TYPE", "FENCE_RADIUS", "FENCE_ALT_MAX")


@dataclass(frozen=True)
class Fence:
    """ArduPilot's own geofence as its parameters say (AC_Fence); None for what the vehicle has not told yet."""
    CEILING = 1                                      # FENCE_TYPE bits (AC_FENCE_TYPE_*)
    CIRCLE = 2
    POLYGON = 4
    FLOOR = 8

    enabled: bool | None = None                      # FENCE_ENABLE
    types: int | None = None                         # FENCE_TYPE bitmask
    radius: float | None = None                      # FENCE_RADIUS, m around home
    alt_max: float | None = None                     # FENCE_ALT_MAX, m above home
    breached: bool | None = None                     # FENCE_STATUS (sent while it is enabled); None: not told

    @property
    def known(self) -> bool:
        return None not in (self.enabled, self.types, self.radius, self.alt_max)

    @property
    def circle(self) -> float | None:
        """The radius of the circle around home the vehicle will not leave, when that fence is on."""
        return self.radius if self.enabled and self.types and self.types & Fence.CIRCLE and self.radius else None

    @property
    def ceiling(self) -> float | None:
        """The altitude above home the vehicle will not climb past, when that fence is on."""
        return self.alt_max if self.enabled and self.types and self.types & Fence.CEILING and self.alt_max else None

    def with_param(self, name: str, value: float) -> "Fence":
        """This fence with one FENCE_* parameter's value (PARAM_VALUE)."""
        field_name = {"FENCE_ENABLE": "enabled", "FENCE_TYPE": "types", "FENCE_RADIUS": "radius",
                      "FENCE_ALT_MAX": "alt_max"}[name]
        typed = {"enabled": lambda v: bool(int(v)), "types": lambda v: int(v)}.get(field_name, float)
        return replace(self, **{field_name: typed(value)})

    def destination_problem(self, north: float, east: float, altitude: float) -> str | None:
        """Why the vehicle would ignore a go-to target there (AC_Fence::check_destination_within_fence), or None."""
        if self.ceiling is not None and altitude > self.ceiling:
            return f"above the vehicle's fence ceiling (FENCE_ALT_MAX {self.ceiling:g} m)"
        if self.circle is not None and math.hypot(north, east) > self.circle:
            return f"outside the vehicle's fence (FENCE_RADIUS {self.circle:g} m around home)"
        return None


@dataclass(frozen=True)
class VehicleState:
    """Everything known about the vehicle at one instant."""
    time: float = 0.0                                # wall clock of the last change
    link: LinkHealth = field(default_factory=LinkHealth)
    system_id: int = 0
    vehicle_type: int = 0                            # MAV_TYPE
    mode: str = ""                                   # ArduCopter mode name, "" before the first heartbeat
    armed: bool = False
    landed_state: LandedState = LandedState.UNDEFINED  # EXTENDED_SYS_STATE; UNDEFINED on firmware without it
    system_status: int | None = None                 # HEARTBEAT.system_status (MAV_STATE) of the autopilot
    attitude: Attitude = field(default_factory=Attitude)
    position: GlobalPosition | None = None
    home: GlobalPosition | None = None
    local: LocalPosition | None = None               # from home, NED
    velocity: Velocity = field(default_factory=Velocity)
    altitude: float = 0.0                            # above home, m
    heading_deg: float = 0.0                         # 0..360, clockwise from north
    airspeed: float = 0.0
    battery: Battery = field(default_factory=Battery)
    gps: Gps = field(default_factory=Gps)
    readiness: Readiness = field(default_factory=Readiness)
    boot: Boot = field(default_factory=Boot)         # the vehicle's clock and its restarts (reboots) heard
    environment: Environment = field(default_factory=Environment)
    messages: tuple[Message, ...] = ()               # the most recent, oldest first
    results: tuple[CommandResult, ...] = ()          # the most recent command results, oldest first
    takeoff: SequenceProgress = field(default_factory=SequenceProgress)
    sequence: SequenceState = field(default_factory=SequenceState)
    lifted: bool = False                             # a message that can lift it went out, and it has not been
                                                     # seen landed and disarmed since (driver.vehicle.safety)
    setpoint: Setpoint = field(default_factory=Setpoint)
    rejected_values: int = 0                         # telemetry messages dropped for impossible values
    gcs_failsafe: int | None = None                  # the vehicle's FS_GCS_ENABLE, None until read
    firmware: str = ""                               # AUTOPILOT_VERSION's flight software, "3.3.1"; "" until known
    autopilot: Autopilot = field(default_factory=Autopilot)   # driver.setup.banner: its banner, its board
    signing: Signing = field(default_factory=Signing)
    fence: Fence = field(default_factory=Fence)      # FENCE_* parameters, as they are read
    mission: MissionProgress = field(default_factory=MissionProgress)   # driver.mission: progress, transfers
    parameters: ParameterTable = field(default_factory=ParameterTable)  # driver.params: every value reported
    gimbal: Gimbal = field(default_factory=Gimbal)   # driver.payload: as the vehicle reports it, unknown until then
    camera: VehicleCamera = field(default_factory=VehicleCamera)   # the vehicle's camera (not the window's video)
    setup: SetupState = field(default_factory=SetupState)          # driver.setup: radio, outputs, calibrations
    traffic: Traffic = field(default_factory=Traffic)              # driver.traffic: ADS-B contacts, alerts
    shot: ShotState = field(default_factory=ShotState)             # driver.shots: the smart shot, from telemetry

    # -- derived views -----------------------------------------------------------------------
    @property
    def connected(self) -> bool:
        return self.link.status is LinkStatus.OK

    @property
    def in_air(self) -> bool | None:
        """Whether the autopilot says it is off the ground; None when it does not say.

        EXTENDED_SYS_STATE when the firmware sends it, and the HEARTBEAT's system status, which ArduCopter sets
        to STANDBY exactly while it counts as landed (GCS_MAVLINK_Copter::vehicle_system_status) and to CRITICAL in
        a failsafe (then it does not tell). Both say the same flag (land_complete) at their own rates: when they
        disagree, one of them is older, and the cautious one wins (in the air). Never a guess from the barometer.
        """
        heartbeat = (False if self.system_status == MAV_STATE_STANDBY else
                     self.armed if self.system_status == MAV_STATE_ACTIVE else None)
        if self.landed_state is not LandedState.UNDEFINED:
            return self.landed_state is not LandedState.ON_GROUND or heartbeat is True
        return heartbeat

    @property
    def may_be_airborne(self) -> bool:
        """The flight rules' cautious view (driver.vehicle.safety): not known to be on the ground (unknown counts
        as airborne), armed in AUTO (the first MISSION_START lifts it), or lifted by a message of ours and not seen
        landed and disarmed since. What the driver will not command in the air follows it."""
        return self.lifted or self.in_air is not False or (self.armed and self.mode == "AUTO")

    @property
    def flying(self) -> bool:
        """Armed and not known to be on the ground (taking off, flying, landing, or the autopilot does not
        say): the cautious reading for every decision that must not be taken in the air."""
        return self.armed and self.in_air is not False

    @property
    def can_fly_velocity(self) -> bool:
        """Velocity setpoints are obeyed: link up, GUIDED, armed and airborne, takeoff finished."""
        return (self.link.status is LinkStatus.OK and self.mode == "GUIDED" and self.flying
                and not self.takeoff.active
                and self.landed_state in (LandedState.IN_AIR, LandedState.UNDEFINED))

    @property
    def velocity_blocker(self) -> str:
        """Why velocity setpoints would not fly the vehicle now: "" (they would), "no link", "taking off",
        "on the ground", "landing" or "not GUIDED"; each front end words it its own way."""
        if self.can_fly_velocity:
            return ""
        if self.link.status is not LinkStatus.OK:
            return "no link"
        if self.takeoff.active:
            return "taking off"
        if not self.flying:
            return "on the ground"
        if self.landed_state is LandedState.LANDING or self.mode == "LAND":
            return "landing"
        if self.landed_state is LandedState.TAKEOFF and self.mode == "GUIDED":
            return "taking off"     # in another mode the mode is what stops velocity, whatever the last
        return "not GUIDED"         # EXTENDED_SYS_STATE (slower than the heartbeat) still says

    @property
    def distance_from_home(self) -> float | None:
        return None if self.local is None else math.hypot(self.local.north, self.local.east)

    def messages_since(self, index: int) -> tuple[Message, ...]:
        return tuple(m for m in self.messages if m.index > index)

    def results_since(self, index: int) -> tuple[CommandResult, ...]:
        return tuple(r for r in self.results if r.index > index)
