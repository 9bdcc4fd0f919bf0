"""What the vehicle says about its setup, as immutable snapshots (VehicleState.setup).

Everything here is what the vehicle reported (RC_CHANNELS, SERVO_OUTPUT_RAW, ACCELCAL_VEHICLE_POS prompts,
MAG_CAL_PROGRESS / MAG_CAL_REPORT), never what was asked for.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass, field

__all__ = ["RcChannels", "ServoOutputs", "AccelStep", "AccelCalState", "CompassProgress", "CompassReport",
           "CompassCalState", "SetupState", "ACCEL_POSITIONS", "ACCEL_SUCCESS", "ACCEL_FAILED"]

ACCEL_SUCCESS = 16777215          # ACCELCAL_VEHICLE_POS_SUCCESS
ACCEL_FAILED = 16777216           # ACCELCAL_VEHICLE_POS_FAILED
#: ACCELCAL_VEHICLE_POS 1..6, in the pilot's words
ACCEL_POSITIONS = {1: "level", 2: "on its left side", 3: "on its right side", 4: "nose down", 5: "nose up",
                   6: "on its back"}


@dataclass(frozen=True)
class RcChannels:
    """RC_CHANNELS (or RC_CHANNELS_RAW on old firmware): microseconds per channel, 0 = not sent."""
    values: tuple[int, ...] = ()
    rssi: int | None = None           # 0..254, None: unknown (255)
    updated: float = 0.0              # wall clock

    def channel(self, number: int) -> int | None:
        """Channel ``number`` (1-based) in microseconds, None when the vehicle did not send it."""
        if 1 <= number <= len(self.values) and self.values[number - 1]:
            return self.values[number - 1]
        return None


@dataclass(frozen=True)
class ServoOutputs:
    """SERVO_OUTPUT_RAW: microseconds per output (1-based: ``values[0]`` is output 1)."""
    values: tuple[int, ...] = ()
    updated: float = 0.0

    def output(self, number: int) -> int | None:
        return self.values[number - 1] if 1 <= number <= len(self.values) else None


class AccelStep(enum.Enum):
    IDLE = "idle"
    STARTING = "starting"             # PREFLIGHT_CALIBRATION sent, no position asked yet
    WAITING = "waiting"               # the vehicle asks for a position
    SUCCESS = "success"
    FAILED = "failed"


@dataclass(frozen=True)
class AccelCalState:
    step: AccelStep = AccelStep.IDLE
    position: int | None = None       # 1..6 asked by the vehicle now
    confirmed: tuple[int, ...] = ()   # positions the pilot confirmed
    texts: tuple[str, ...] = ()       # the vehicle's own words since the start

    @property
    def position_name(self) -> str:
        return ACCEL_POSITIONS.get(self.position, "") if self.position else ""


@dataclass(frozen=True)
class CompassProgress:
    compass: int
    percent: int
    status: int                       # MAG_CAL_STATUS
    attempt: int


@dataclass(frozen=True)
class CompassReport:
    compass: int
    status: int                       # MAG_CAL_STATUS: 4 SUCCESS, 5 FAILED, 6 BAD_ORIENTATION, 7 BAD_RADIUS
    fitness: float                    # mGauss RMS: lower is better
    offsets: tuple[float, float, float]
    autosaved: bool

    @property
    def ok(self) -> bool:
        return self.status == 4


@dataclass(frozen=True)
class CompassCalState:
    running: bool = False
    progress: tuple[CompassProgress, ...] = ()    # one per compass, by compass id
    reports: tuple[CompassReport, ...] = ()
    accepted: bool = False
    cancelled: bool = False

    def percent(self, compass: int) -> int | None:
        for p in self.progress:
            if p.compass == compass:
                return p.percent
        return 100 if any(r.compass == compass for r in self.reports) else None


@dataclass(frozen=True)
class SetupState:
    rc: RcChannels = field(default_factory=RcChannels)
    outputs: ServoOutputs = field(default_factory=ServoOutputs)
    accel: AccelCalState = field(default_factory=AccelCalState)
    compass: CompassCalState = field(default_factory=CompassCalState)
    motor_test_running: bool = False            # our DO_MOTOR_TEST runs: from the vehicle's ACCEPTED to its end
