"""The one small interface through which anything flies the drone.

Both the embedded driver (:class:`driver.vehicle.vehicle.Vehicle`) and the remote Ice
client provide it, so the viewer never knows which it has. Every method returns
at once: commands hand back a :class:`concurrent.futures.Future` that resolves
to a :class:`~driver.vehicle.state.CommandResult`; state is read as an immutable
snapshot. Nothing here blocks on the network.
"""
from __future__ import annotations

import abc
from concurrent.futures import Future
from dataclasses import dataclass

from . import guided
from ..mission.plan import Plan, PlanKind, TransferOutcome
from ..core.results import answered
from ..shots.api import NO_SHOTS, Shots
from .inspector import Inspection
from .state import BatteryThresholds, CommandResult, CommandStatus, VehicleState


@dataclass(frozen=True)
class Limits:
    """Clamps applied to every velocity command before it reaches the wire."""
    horizontal: float = 2.0      # m/s, forward and right each
    vertical: float = 1.0        # m/s
    yaw_rate: float = 0.785      # rad/s (45 deg/s)

    def within(self, ceiling: "Limits") -> "Limits":
        """These limits, none above ``ceiling`` and none negative or NaN."""
        def cap(value: float, top: float) -> float:
            return min(top, value) if value >= 0 else 0.0      # NaN compares false: becomes 0
        return Limits(cap(self.horizontal, ceiling.horizontal), cap(self.vertical, ceiling.vertical),
                      cap(self.yaw_rate, ceiling.yaw_rate))


#: The most a pilot may configure (Preferences); the driver never streams beyond it.
CEILING = Limits(10.0, 5.0, 3.1416)


class Drone(abc.ABC):
    """A vehicle the pilot can fly."""

    @abc.abstractmethod
    def state(self) -> VehicleState:
        """The latest snapshot; cheap, never blocks."""

    @property
    @abc.abstractmethod
    def description(self) -> str:
        """Where the vehicle is reached ("tcp:127.0.0.1:5760", "Ice 10.1.1.10")."""

    @property
    def limits(self) -> Limits:
        return Limits()

    def set_limits(self, limits: Limits) -> Limits:
        """Change the velocity clamps (the pilot's maximum speeds), capped at :data:`CEILING`.

        Returns the limits now in force. Thread-safe; takes effect on the next setpoint.
        """
        raise NotImplementedError

    def set_battery_thresholds(self, thresholds: BatteryThresholds) -> BatteryThresholds:
        """The pilot's own battery limits (warning and critical, per cell and in percent) that
        ``state().battery.alarm`` is judged by from now on. Returns those in force."""
        raise NotImplementedError

    @property
    def replay(self):
        """Play/pause/speed control when the 'vehicle' is a recorded flight, else None."""
        return None

    #: the smart shots (driver.shots): orbit, cable cam, selfie, follow, pano; state in ``state().shot``
    shots: Shots = NO_SHOTS

    #: the link's counts by system, component and message (driver.vehicle.inspector.MessageInspector), set by a
    #: drone that reads the link itself (the Vehicle's reader); None: this drone does not see the link
    inspector = None

    #: what only a drone holding the link itself has (the embedded Vehicle), None on one whose server holds it (the
    #: Ice client): its settings (driver.vehicle.vehicle.VehicleConfig), the vehicle's setup (calibrations, motor
    #: test, radio: driver.setup.control.VehicleSetup) and its DataFlash logs (driver.logs.control.LogControl)
    config = None
    setup = None
    logs = None

    def inspection(self) -> Inspection:
        """Every message type from every component with its rate and newest fields; ``available`` False (and
        why) for a drone that does not see the raw link (the Ice client: its server reads it)."""
        if self.inspector is None:
            return Inspection.unavailable("this connection does not carry the raw MAVLink to the viewer "
                                          "(a remote drone: its server reads the link)")
        return self.inspector.snapshot()

    # -- flight ---------------------------------------------------------------------------
    @abc.abstractmethod
    def takeoff(self, altitude: float | None = None) -> Future[CommandResult]:
        """Run the whole sequence: wait until ready, GUIDED, arm, take off, climb.

        Resolves ACCEPTED once the target altitude is reached (or FAILED/ABORTED).
        """

    @abc.abstractmethod
    def land(self) -> Future[CommandResult]:
        """Switch to LAND; aborts a takeoff in progress. Always accepted by the driver."""

    @abc.abstractmethod
    def stop(self) -> Future[CommandResult]:
        """Hold position: zero velocity in GUIDED, else BRAKE. Aborts a takeoff."""

    def cancel_takeoff(self) -> Future[CommandResult]:
        """End a takeoff that has not left the ground and give the vehicle back as it was (its mode, disarmed
        if it was); once NAV_TAKEOFF went out, the same as :meth:`stop`. Never switches to LAND."""
        return self.stop()

    @abc.abstractmethod
    def return_to_launch(self) -> Future[CommandResult]:
        """Switch to RTL."""

    @abc.abstractmethod
    def arm(self, force: bool = False) -> Future[CommandResult]: ...

    @abc.abstractmethod
    def disarm(self, force: bool = False, emergency: bool = False) -> Future[CommandResult]:
        """Stop the motors. ``force`` skips the vehicle's checks; in the air that makes it fall, so a forced
        disarm in flight is refused unless ``emergency`` says the pilot confirmed exactly that."""

    @abc.abstractmethod
    def set_mode(self, name: str) -> Future[CommandResult]:
        """Change flight mode by ArduCopter name ("GUIDED", "LOITER", ...)."""

    @abc.abstractmethod
    def set_velocity(self, forward: float, right: float, up: float, yaw_rate: float) -> bool:
        """Command a velocity relative to the vehicle's heading.

        forward/right/up in m/s, yaw_rate in rad/s (positive turns the nose right).
        Values are clamped to :attr:`limits`; returns False (and sends nothing new)
        if any value is NaN or infinite. The driver keeps streaming it and falls to
        zero when calls stop for the deadman time.
        """

    @abc.abstractmethod
    def go_to(self, north: float, east: float, altitude: float) -> Future[CommandResult]:
        """Fly to a point in metres from home (altitude above home)."""

    @abc.abstractmethod
    def set_yaw(self, degrees: float, relative: bool = False, rate_deg_s: float = 30.0) -> Future[CommandResult]:
        """Turn to a heading (clockwise from north) or by an angle (relative, positive = right)."""

    # -- guided actions (driver.vehicle.guided: built on the calls above, so every Drone has them) --------------
    def change_altitude(self, altitude: float) -> Future[CommandResult]:
        """Climb or descend to ``altitude`` m above home where the vehicle is, in GUIDED."""
        return guided.change_altitude(self, altitude)

    def circle(self, north: float, east: float, radius: float) -> Future[CommandResult]:
        """Circle the point (north, east) m from home at ``radius`` m, the way ArduCopter's CIRCLE mode can."""
        return guided.circle_point(self, north, east, radius)

    def reboot(self) -> Future[CommandResult]:
        """Restart the autopilot (MAV_CMD_PREFLIGHT_REBOOT_SHUTDOWN), e.g. after a new frame; a drone whose server
        holds the link refuses at once."""
        return answered(CommandResult("reboot", CommandStatus.REJECTED, _NO_REBOOT))

    # -- payload --------------------------------------------------------------------------
    def toggle_camera(self) -> Future[CommandResult]:
        """Ask the vehicle to show its next camera; a vehicle with one camera (the default) refuses at once."""
        return answered(CommandResult("switch camera", CommandStatus.REJECTED, "this vehicle has no camera switch"))

    # -- gimbal, region of interest, camera on the vehicle (driver.payload; docs/camera.md) ------------
    # Each resolves on the vehicle's word: a pointing command on its ACK (or, on the Solo, MOUNT_STATUS
    # showing the angle); a picture or a recording only on the camera's own confirmation, never an ACK alone.
    def point_gimbal(self, pitch_deg: float, yaw_deg: float | None = None) -> Future[CommandResult]:
        """Point the gimbal: pitch 0 level, -90 straight down; yaw from the nose where the mount has it."""
        return answered(CommandResult("gimbal", CommandStatus.REJECTED, _NO_PAYLOAD))

    def gimbal_rate(self, pitch_deg_s: float, yaw_deg_s: float = 0.0) -> Future[CommandResult]:
        """Turn the gimbal at a rate (positive pitch rate tilts up) until another command; 0 stops it."""
        return answered(CommandResult("gimbal rate", CommandStatus.REJECTED, _NO_PAYLOAD))

    def look_at(self, lat: float, lon: float, alt: float = 0.0) -> Future[CommandResult]:
        """Region of interest: the vehicle keeps its camera (and nose) on this point, alt above home."""
        return answered(CommandResult("look at", CommandStatus.REJECTED, _NO_PAYLOAD))

    def stop_looking(self) -> Future[CommandResult]:
        """End the region of interest: the mount goes back to its default mode."""
        return answered(CommandResult("stop looking", CommandStatus.REJECTED, _NO_PAYLOAD))

    def take_photo(self) -> Future[CommandResult]:
        """A picture on the vehicle's camera; ACCEPTED only once the camera confirms it."""
        return answered(CommandResult("photo", CommandStatus.REJECTED, _NO_PAYLOAD))

    def record_video(self, on: bool) -> Future[CommandResult]:
        """Start or stop video on the vehicle's camera; ACCEPTED once the camera says it records (or stopped)."""
        return answered(CommandResult(f"record {'on' if on else 'off'}", CommandStatus.REJECTED, _NO_PAYLOAD))

    # -- missions, fences, rally points (driver.mission) ----------------------------------------
    # A transfer resolves only on the vehicle's word: an upload is ACCEPTED once MISSION_ACK accepted it *and*
    # the plan read back matches in meaning; its outcome carries the plan read back. One transfer per kind at a
    # time; progress is in ``state().mission.transfers``.
    def upload_plan(self, plan: Plan) -> Future[TransferOutcome]:
        """Check ``plan`` against the flight limits, write it to the vehicle, read it back and compare."""
        return answered(TransferOutcome(CommandResult(f"upload {plan.kind.label}", CommandStatus.REJECTED,
                                                       _NO_MISSIONS)))

    def download_plan(self, kind: PlanKind) -> Future[TransferOutcome]:
        """Read the vehicle's plan of ``kind``."""
        return answered(TransferOutcome(CommandResult(f"download {kind.label}", CommandStatus.REJECTED,
                                                       _NO_MISSIONS)))

    def clear_plan(self, kind: PlanKind) -> Future[CommandResult]:
        """MISSION_CLEAR_ALL for ``kind``, confirmed by its MISSION_ACK."""
        return answered(CommandResult(f"clear {kind.label}", CommandStatus.REJECTED, _NO_MISSIONS))

    def cancel_transfer(self, kind: PlanKind) -> None:
        """End the transfer of ``kind`` running now (its future resolves ABORTED); nothing when none runs."""

    def start_mission(self) -> Future[CommandResult]:
        """Fly the uploaded mission: AUTO + MISSION_START; from the ground through the takeoff's readiness and
        arming path. Resolves when the heartbeat and MISSION_CURRENT say it runs."""
        return answered(CommandResult("mission start", CommandStatus.REJECTED, _NO_MISSIONS))

    def pause_mission(self) -> Future[CommandResult]:
        """Hold where it is (BRAKE); the current item is kept."""
        return answered(CommandResult("mission pause", CommandStatus.REJECTED, _NO_MISSIONS))

    def resume_mission(self) -> Future[CommandResult]:
        """Back to AUTO: the vehicle flies the current item again."""
        return answered(CommandResult("mission resume", CommandStatus.REJECTED, _NO_MISSIONS))

    def set_mission_item(self, seq: int) -> Future[CommandResult]:
        """Make item ``seq`` (1 = the first flyable item) current: DO_SET_MISSION_CURRENT, else MISSION_SET_CURRENT."""
        return answered(CommandResult(f"mission item {seq}", CommandStatus.REJECTED, _NO_MISSIONS))

    # -- parameters (driver.params) ---------------------------------------------------------------
    # The table is in ``state().parameters``; a set resolves ACCEPTED only on a PARAM_VALUE carrying the new
    # value at the parameter's own precision.
    def fetch_parameters(self, refresh: bool = False) -> Future[CommandResult]:
        """Download every parameter (re-asking missing ones by index); ``refresh`` ignores what is cached."""
        return answered(CommandResult("parameters", CommandStatus.REJECTED, _NO_PARAMETERS))

    def set_parameter(self, name: str, value: float, allow_out_of_bounds: bool = False) -> Future[CommandResult]:
        """PARAM_SET ``name`` to ``value`` in the parameter's own type, confirmed by the vehicle's echo. A value
        outside ArduPilot's documented bounds (:attr:`parameter_metadata`) is REJECTED unless
        ``allow_out_of_bounds`` says the pilot confirmed exactly that: the vehicle itself checks nothing."""
        return answered(CommandResult(f"param {name}", CommandStatus.REJECTED, _NO_PARAMETERS))

    @property
    def parameter_metadata(self):
        """ArduPilot's metadata (:class:`driver.params.metadata.ParamMetadata`: bounds, units, descriptions,
        reboot-required), or None when there is none: editing still works, unchecked."""
        return None

    # -- link security (MAVLink 2 signing; driver.link.signing) -------------------------------------
    # Only a driver that holds the MAVLink link can sign it; a remote one (Ice) is set up on its server.
    @property
    def signing_unavailable(self) -> str:
        """Why this drone's link cannot be signed from here; "" when it can."""
        return _NO_SIGNING

    def use_signing_key(self, key: bytes | None, allow_unsigned: bool | None = None) -> CommandResult:
        """Sign with ``key`` from now on (None: stop), without telling the vehicle."""
        return CommandResult("signing key", CommandStatus.REJECTED, _NO_SIGNING)

    def allow_unsigned(self, on: bool) -> CommandResult:
        """Let the vehicle's unsigned frames in while signing (a vehicle without the key yet), or stop."""
        return CommandResult("signing unsigned", CommandStatus.REJECTED, _NO_SIGNING)

    def setup_signing(self, key: bytes) -> Future[CommandResult]:
        """Give the vehicle ``key`` (SETUP_SIGNING, in clear) and sign with it."""
        return answered(CommandResult("signing setup", CommandStatus.REJECTED, _NO_SIGNING))

    def remove_signing(self) -> Future[CommandResult]:
        """Tell the vehicle to stop signing, then stop here."""
        return answered(CommandResult("signing remove", CommandStatus.REJECTED, _NO_SIGNING))

    @abc.abstractmethod
    def close(self) -> None:
        """Stop streaming and release the link."""


class Fleet(abc.ABC):
    """Several vehicles, each a :class:`Drone`, known by name (a lab's registry: docs/fleet.md).

    Nothing here blocks: the names are a snapshot kept fresh in the background.
    """

    @property
    @abc.abstractmethod
    def description(self) -> str:
        """Where the fleet is known ("registry 10.1.1.5:4061")."""

    @abc.abstractmethod
    def names(self) -> tuple[str, ...]:
        """The vehicles known now, sorted."""

    @property
    def problem(self) -> str:
        """Why the list may be out of date (the registry does not answer), or ""."""
        return ""

    @property
    def closed(self) -> bool:
        """True once :meth:`close` was called: no drone is made any more."""
        return False

    @abc.abstractmethod
    def drone(self, name: str) -> Drone:
        """The vehicle ``name``: made (and started) on first use, the same one afterwards."""

    @abc.abstractmethod
    def close(self) -> None:
        """Close every drone made and stop following the list."""


_NO_MISSIONS = "this vehicle connection cannot transfer or fly plans"
_NO_PARAMETERS = "this vehicle connection cannot read or write parameters"
_NO_PAYLOAD = "this vehicle connection cannot point a gimbal or trigger a camera"
_NO_REBOOT = "this vehicle connection cannot restart the autopilot: its server holds the link"
_NO_SIGNING = "the MAVLink link is signed where it is held: set signing up on the MAVLinkServer"
