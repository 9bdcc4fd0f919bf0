"""Ice servants: JdeRobot's Pose3D, CMDVel, ArDroneExtra, Navdata, a placeholder Camera, and our extension.

Every getter answers at once from the driver's latest snapshot (the 2017 server
slept 50 ms in each); every command hands the driver a job and returns, so an
Ice dispatch thread never waits for the vehicle. Nothing here raises into a
JdeRobot client except the Camera's documented DataNotExistException.

An Ice client is a program on the network, not the pilot at the vehicle: it gets
less than the console. No forced arm (it skips the pre-arm checks), no forced
disarm in flight (the drone falls) except the explicit ``emergencyStop`` when the
server allows it, only the modes of ``ServerSettings.allowed_modes`` (LAND always),
and go-to and takeoff targets within ``max_distance``/``max_altitude`` of home.
Land and Stop are never refused here.
"""
from __future__ import annotations

import logging
import math
import threading
import time
from concurrent.futures import Future
from dataclasses import dataclass

import Ice

from ..vehicle.api import Drone
from ..core.frames import finite
from ..mission.plan import TransferOutcome
from ..vehicle.rules import COPTER_MODES, MAX_ALTITUDE, go_to_problem, takeoff_altitude_problem
from ..vehicle.state import CommandResult, CommandStatus, LandedState
from . import convert, load_slice, plans
from .params import Revisions, table_to_ice
from .payload import PayloadServant

jderobot, mavlinkserver = load_slice()
log = logging.getLogger(__name__)


#: Modes an Ice client may pick by default: those in which ArduCopter flies itself without an RC
#: transmitter (none of rules.THROTTLE_MODES, nor POSHOLD, whose throttle is the stick too), that a
#: ground station without mission upload can use: GUIDED (what our commands fly), LOITER (hold here),
#: BRAKE (stop now), LAND, RTL and SMART_RTL (home by the way it came). Not AUTO (a mission nobody over
#: Ice uploaded), CIRCLE, FLIP, AUTOTUNE, THROW, ...
ICE_MODES = frozenset({"GUIDED", "LOITER", "BRAKE", "LAND", "RTL", "SMART_RTL"})


@dataclass
class ServerSettings:
    """What the servants share; filled from MAVLinkServer.* properties."""
    takeoff_altitude: float = 3.0
    cmdvel_max: tuple[float, float, float, float] = (2.0, 2.0, 1.0, 0.785)   # linearX, linearY, linearZ, angularZ
    cmdvel_refuse_above: float = 100.0     # a value beyond this is garbage, not a command: refuse it
    navdata_vehicle: int = 1               # JdeRobot: 0 ArDrone1, 1 ArDrone2 (10 = simulated)
    max_altitude: float = MAX_ALTITUDE     # m above home: no takeoff or go-to target above it
    max_distance: float = 100.0            # m from home: no go-to target beyond it (the driver's own is 500)
    allowed_modes: frozenset = ICE_MODES   # LAND is always in
    allow_emergency_disarm: bool = False   # emergencyStop may stop the motors in flight

    def go_to_problem(self, north: float, east: float, altitude: float) -> str | None:
        return go_to_problem(north, east, altitude, self.max_altitude, self.max_distance)

    def takeoff_problem(self, altitude: float) -> str | None:
        return takeoff_altitude_problem(altitude, self.max_altitude)


def _resolved(result: CommandResult) -> Future:
    f: Future = Future()
    f.set_result(result)
    return f


def _log_failure(what: str):
    """Done-callback for JdeRobot operations that return nothing.

    The driver logs every command result itself (and the console prints it), so
    only a failure to run the command at all is logged here: once, not twice.
    """
    def done(fut: Future) -> None:
        try:
            fut.result()
        except Exception as exc:                        # the driver failed to run it at all
            log.error("%s: %s", what, exc)
    return done


class Snapshots:
    """What the JdeRobot getters answer, converted once per driver snapshot and shared by every servant.

    The driver publishes a new immutable :class:`~driver.vehicle.state.VehicleState` when telemetry changes; between
    two snapshots every ``getPose3DData``/``getNavdata`` of every client gets the same prepared Ice value, so
    a call costs a lookup, not a conversion. Ice only reads a value it marshals, so sharing one is safe; a
    race between two dispatch threads at most converts the same snapshot twice.
    """

    def __init__(self, vehicle: Drone, settings: ServerSettings | None = None):
        self._vehicle = vehicle
        self._settings = settings if settings is not None else ServerSettings()
        self._started = time.time()
        self._pose: tuple[object, object] = (None, None)        # (snapshot, Pose3DData)
        self._navdata: tuple[object, object] = (None, None)     # (snapshot, NavdataData)

    def pose(self):
        state = self._vehicle.state()
        seen, pose = self._pose
        if seen is not state:
            pose = jderobot.Pose3DData(*convert.pose_enu(state))
            self._pose = (state, pose)
        return pose

    def navdata(self):
        state = self._vehicle.state()
        seen, nav = self._navdata
        if seen is not state:
            clock = max(0.0, state.time - self._started) if state.time else 0.0    # when the snapshot was taken
            nav = jderobot.NavdataData(**convert.navdata_fields(state, self._settings.navdata_vehicle, clock))
            self._navdata = (state, nav)
        return nav


class Pose3DI(jderobot.Pose3D):
    """Pose in ENU from home; set = fly there (both the ``Pose3D`` and the waypoint ``WP`` servant)."""

    def __init__(self, vehicle: Drone, name: str = "Pose3D", settings: ServerSettings | None = None,
                 snapshots: Snapshots | None = None):
        self._vehicle = vehicle
        self._name = name
        self._settings = settings if settings is not None else ServerSettings()
        self._snapshots = snapshots if snapshots is not None else Snapshots(vehicle, self._settings)

    def getPose3DData(self, current=None):
        return self._snapshots.pose()

    def setPose3DData(self, data, current=None):
        target = None if data is None else convert.waypoint_from_enu(data.x, data.y, data.z)
        if target is None:
            log.warning("%s: refused waypoint with a missing or non-finite coordinate", self._name)
            return -1
        north, east, altitude = target
        problem = self._settings.go_to_problem(north, east, altitude)
        if problem:
            log.warning("%s: refused waypoint east %.1f north %.1f up %.1f: %s", self._name, east, north, altitude,
                        problem)
            return -1
        # DEBUG: a client may stream waypoints; the driver records each result ("go to ...") anyway
        log.debug("%s: go to east %.1f north %.1f up %.1f", self._name, east, north, altitude)
        answer = self._vehicle.go_to(north, east, altitude)
        answer.add_done_callback(_log_failure(f"{self._name} waypoint"))
        if answer.done() and not answer.result().ok:    # refused at once (not flying, takeoff running...)
            return -1
        return 0


class CMDVelI(jderobot.CMDVel):
    """Velocity relative to the heading, JdeRobot's FLU convention, into the driver's body command."""

    def __init__(self, vehicle: Drone, settings: ServerSettings):
        self._vehicle = vehicle
        self._settings = settings

    def setCMDVelData(self, data, current=None):
        if data is None:
            return -1
        values = (data.linearX, data.linearY, data.linearZ, data.angularX, data.angularY, data.angularZ)
        if not finite(*values):                           # Ice hands floats; a NaN or inf is refused
            log.warning("CMDVel refused: non-finite value in %s", values)
            return -1
        if max(map(abs, values)) > self._settings.cmdvel_refuse_above:
            log.warning("CMDVel refused: value beyond %g in %s", self._settings.cmdvel_refuse_above, values)
            return -2
        flu = convert.clamp_cmdvel((data.linearX, data.linearY, data.linearZ, data.angularZ),
                                   self._settings.cmdvel_max)
        return 0 if self._vehicle.set_velocity(*convert.body_from_cmdvel(*flu)) else -1


class NavdataI(jderobot.Navdata):
    def __init__(self, vehicle: Drone, settings: ServerSettings, snapshots: Snapshots | None = None):
        self._snapshots = snapshots if snapshots is not None else Snapshots(vehicle, settings)

    def getNavdata(self, current=None):
        return self._snapshots.navdata()


class ArDroneExtraI(jderobot.ArDroneExtra):
    """The AR.Drone's extra commands, mapped onto ArduCopter where it has an equivalent."""

    def __init__(self, vehicle: Drone, settings: ServerSettings, camera=None):
        self._vehicle = vehicle
        self._settings = settings
        self._camera = camera

    def _run(self, what: str, call) -> None:
        """Hand the driver a job; the request is noteworthy, its result the driver logs."""
        log.info("Extra.%s", what)
        try:
            call().add_done_callback(_log_failure(f"Extra.{what}"))
        except Exception:                                # never raise into a JdeRobot client
            log.exception("Extra.%s failed", what)

    def takeoff(self, current=None):
        altitude = self._settings.takeoff_altitude
        self._run(f"takeoff to {altitude:g} m", lambda: self._vehicle.takeoff(altitude))

    def land(self, current=None):
        self._run("land", self._vehicle.land)

    def reset(self, current=None):
        """The AR.Drone's emergency reset; on a copter the safe meaning is stop and hold."""
        self._run("reset: stop and hold", self._vehicle.stop)

    def toggleCam(self, current=None):
        toggle = getattr(self._camera, "toggle", None)
        if toggle is None:
            log.warning("Extra.toggleCam: no camera configured; nothing to switch")
            return
        try:
            before = getattr(self._camera, "source", None)
            toggle()                                     # the camera logs the switch
            if before is not None and self._camera.source is before:
                log.warning("Extra.toggleCam: only one camera configured; nothing to switch")
        except Exception:
            log.exception("Extra.toggleCam failed")

    def recordOnUsb(self, record, current=None):
        recorder = getattr(self._camera, "record", None)
        if recorder is None:
            log.warning("Extra.recordOnUsb(%s): no camera to record", record)
            return
        try:
            recorder(bool(record))                       # the camera logs the file it writes
        except Exception:
            log.exception("Extra.recordOnUsb failed")

    def flatTrim(self, current=None):
        s = self._vehicle.state()
        on_ground = not s.armed and s.landed_state in (LandedState.ON_GROUND, LandedState.UNDEFINED) \
            and abs(s.altitude) < 1.0
        calibrate = getattr(self._vehicle, "calibrate_level", None)
        if not on_ground:
            log.warning("Extra.flatTrim refused: level calibration only when disarmed on the ground")
        elif calibrate is None:
            log.warning("Extra.flatTrim: this driver cannot calibrate the level")
        else:
            self._run("flatTrim: level calibration", calibrate)

    def ledAnimation(self, type, duration, req, current=None):
        log.warning("Extra.ledAnimation(%s, %s, %s): not supported on ArduCopter", type, duration, req)

    def flightAnimation(self, type, duration, current=None):
        log.warning("Extra.flightAnimation(%s, %s): not supported on ArduCopter", type, duration)


class NoCameraI(jderobot.Camera):
    """Stands in until a camera source is configured: every image request says why there is none."""

    def __init__(self, reason: str = "no camera source configured yet"):
        self._reason = reason

    def _none(self):
        raise jderobot.DataNotExistException(self._reason)

    def getImageDescription(self, current=None):
        return jderobot.ImageDescription(0, 0, 0, "NONE", "")

    def getImageFormat(self, current=None):
        return []

    def getImageData(self, format, current=None):
        self._none()

    def getCameraDescription(self, current=None):
        return jderobot.CameraDescription(name="none", shortDescription=self._reason)

    def setCameraDescription(self, description, current=None):
        return -1

    def startCameraStreaming(self, current=None):
        return ""

    def stopCameraStreaming(self, current=None):
        pass

    def reset(self, current=None):
        pass


class Answering:
    """AMD answers: each command's Ice future resolved with the driver's CommandResult once the vehicle answered
    (our extension's servants: Vehicle, Shots)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._pending: dict[Ice.Future, str] = {}     # answers still waiting for the vehicle

    def _reply(self, answer: Ice.Future, result: CommandResult) -> None:
        with self._lock:
            if self._pending.pop(answer, None) is None:
                return                                  # already answered (e.g. aborted at shutdown)
        answer.set_result(convert.outcome_from_result(mavlinkserver, result))

    def _answer(self, command: str, call) -> Ice.Future:
        """An Ice future resolved with the driver's CommandResult once the vehicle has answered."""
        answer = Ice.Future()
        with self._lock:
            self._pending[answer] = command

        def done(fut: Future) -> None:
            try:
                result = fut.result()
            except Exception as exc:
                result = CommandResult(command, CommandStatus.REJECTED, f"driver error: {exc}")
            self._reply(answer, result)

        try:
            call().add_done_callback(done)
        except Exception as exc:
            log.exception("%s failed", command)
            self._reply(answer, CommandResult(command, CommandStatus.REJECTED, f"driver error: {exc}"))
        return answer

    def _rejected(self, command: str, reason: str) -> Ice.Future:
        return self._answer(command, lambda: _resolved(CommandResult(command, CommandStatus.REJECTED, reason)))

    def abort_pending(self, reason: str) -> None:
        """Answer every command still waiting (ABORTED), so shutting down never waits for the vehicle."""
        with self._lock:
            pending = list(self._pending.items())
        for answer, command in pending:
            self._reply(answer, CommandResult(command, CommandStatus.ABORTED, reason))


class VehicleI(PayloadServant, Answering, mavlinkserver.Vehicle):
    """Our extension: status and commands with the vehicle's own answer."""

    def __init__(self, vehicle: Drone, settings: ServerSettings):
        super().__init__()
        self._vehicle = vehicle
        self._settings = settings
        self.status_calls = 0                         # getStatus dispatches: what polling observers cost
        self._revisions = Revisions()                 # of the parameter tables served

    def getStatus(self, messagesSince, resultsSince, current=None):
        self.status_calls += 1
        return convert.status_from_state(mavlinkserver, self._vehicle.state(), messagesSince, resultsSince)

    def getFence(self, current=None):
        return convert.fence_to_ice(mavlinkserver, self._vehicle.state().fence)

    def getLimits(self, current=None):
        lim = self._vehicle.limits
        return mavlinkserver.Limits(horizontal=lim.horizontal, vertical=lim.vertical, yawRate=lim.yaw_rate)

    def getDescription(self, current=None):
        return self._vehicle.description

    def setMode(self, name, current=None):
        mode = str(name).strip().upper()
        allowed = self._settings.allowed_modes
        if mode in COPTER_MODES and mode not in allowed:        # an unknown name: the driver says so
            log.warning("Vehicle.setMode %s refused: not allowed over Ice", mode)
            return self._rejected(f"mode {mode}", f"not allowed over Ice (allowed: {', '.join(sorted(allowed))}; "
                                                  "MAVLinkServer.Modes)")
        return self._answer(f"mode {name}", lambda: self._vehicle.set_mode(name))

    def arm(self, force, current=None):
        if force:
            log.warning("Vehicle.arm(force) refused: not over Ice")
            return self._rejected("arm (forced)", "a forced arm skips the vehicle's pre-arm checks: not over Ice; "
                                                  "arm normally, or force it at the vehicle's own console")
        return self._answer("arm", lambda: self._vehicle.arm(False))

    def disarm(self, force, current=None):
        if force and self._vehicle.state().flying:
            log.warning("Vehicle.disarm(force) refused: flying")
            return self._rejected("disarm (forced)", "a forced disarm in flight stops the motors and the drone falls: "
                                                     "not over Ice (land, or emergencyStop if the server allows it)")
        return self._answer("disarm", lambda: self._vehicle.disarm(bool(force)))

    def emergencyStop(self, current=None):
        """Motors off now, even in the air: only when the server was started to allow it."""
        if not self._settings.allow_emergency_disarm:
            log.warning("Vehicle.emergencyStop refused: not allowed by this server")
            return self._rejected("emergency motor stop", "not allowed by this server (start it with "
                                                          "--allow-emergency-disarm); land instead")
        log.critical("Vehicle.emergencyStop: stopping the motors at an Ice client's request")
        return self._answer("emergency motor stop", lambda: self._vehicle.disarm(force=True, emergency=True))

    def takeoff(self, altitude, current=None):
        if not math.isfinite(altitude):
            return self._rejected("takeoff", f"altitude {altitude} is not a number")
        target = altitude if altitude > 0 else self._settings.takeoff_altitude
        problem = self._settings.takeoff_problem(target)
        if problem:
            return self._rejected("takeoff", problem)
        return self._answer("takeoff", lambda: self._vehicle.takeoff(target))

    def land(self, current=None):
        return self._answer("land", self._vehicle.land)

    def stop(self, current=None):
        return self._answer("stop", self._vehicle.stop)

    def returnToLaunch(self, current=None):
        if "RTL" not in self._settings.allowed_modes:            # the same mode as setMode("RTL")
            return self._rejected("RTL", "RTL is not allowed over Ice (MAVLinkServer.Modes)")
        return self._answer("RTL", self._vehicle.return_to_launch)

    def goTo(self, north, east, altitude, current=None):
        problem = self._settings.go_to_problem(north, east, altitude)
        if problem:
            log.warning("Vehicle.goTo N%.1f E%.1f alt %.1f refused: %s", north, east, altitude, problem)
            return self._rejected("go to", problem)
        return self._answer("go to", lambda: self._vehicle.go_to(north, east, altitude))

    def setYaw(self, degrees, relative, rateDegS, current=None):
        if not finite(degrees, rateDegS):
            return self._rejected("yaw", "non-finite angle or rate")
        return self._answer("yaw", lambda: self._vehicle.set_yaw(degrees, relative, rateDegS))

    # -- parameters (driver.params; driver.ice.params) ------------------------------------------------
    def getParameters(self, pattern, knownRevision, current=None):
        table = self._vehicle.state().parameters
        return table_to_ice(mavlinkserver, table, self._revisions.of(table), pattern, knownRevision)

    def fetchParameters(self, refresh, current=None):
        return self._answer("parameters", lambda: self._vehicle.fetch_parameters(bool(refresh)))

    def setParameter(self, name, value, allowOutOfBounds, current=None):
        if allowOutOfBounds:
            log.warning("Vehicle.setParameter %s=%g: an Ice client confirmed a value outside the bounds", name, value)
        return self._answer(f"param {name}", lambda: self._vehicle.set_parameter(str(name), float(value),
                                                                                 bool(allowOutOfBounds)))

    # -- missions (driver.mission) -------------------------------------------------------------------
    def _transfer(self, command: str, call) -> Ice.Future:
        """An Ice future resolved with the TransferOutcome once the vehicle has answered."""
        answer = Ice.Future()

        def done(fut: Future) -> None:
            try:
                outcome = fut.result()
            except Exception as exc:
                outcome = TransferOutcome(CommandResult(command, CommandStatus.REJECTED, f"driver error: {exc}"))
            answer.set_result(plans.outcome_to_ice(mavlinkserver, outcome))
        try:
            call().add_done_callback(done)
        except Exception as exc:
            log.exception("%s failed", command)
            done(_resolved(TransferOutcome(CommandResult(command, CommandStatus.REJECTED, f"driver error: {exc}"))))
        return answer

    def uploadPlan(self, plan, current=None):
        try:
            model = plans.plan_from_ice(plan)
        except ValueError as exc:
            why = str(exc)                  # (exc is gone once the except block ends: the lambda runs later)
            return self._transfer("upload", lambda: _resolved(TransferOutcome(
                CommandResult("upload", CommandStatus.REJECTED, why))))
        return self._transfer(f"upload {model.kind.label}", lambda: self._vehicle.upload_plan(model))

    def downloadPlan(self, kind, current=None):
        model = plans.kind_of(kind)
        if model is None:
            return self._transfer("download", lambda: _resolved(TransferOutcome(
                CommandResult("download", CommandStatus.REJECTED, f"no plan kind {kind}"))))
        return self._transfer(f"download {model.label}", lambda: self._vehicle.download_plan(model))

    def clearPlan(self, kind, current=None):
        model = plans.kind_of(kind)
        if model is None:
            return self._rejected("clear", f"no plan kind {kind}")
        return self._answer(f"clear {model.label}", lambda: self._vehicle.clear_plan(model))

    def cancelTransfer(self, kind, current=None):
        model = plans.kind_of(kind)
        if model is not None:
            self._vehicle.cancel_transfer(model)

    def startMission(self, current=None):
        return self._answer("mission start", self._vehicle.start_mission)

    def pauseMission(self, current=None):
        return self._answer("mission pause", self._vehicle.pause_mission)

    def resumeMission(self, current=None):
        return self._answer("mission resume", self._vehicle.resume_mission)

    def setMissionItem(self, seq, current=None):
        return self._answer(f"mission item {seq}", lambda: self._vehicle.set_mission_item(int(seq)))

    def getTakeoffAltitude(self, current=None):
        return self._settings.takeoff_altitude

    def setTakeoffAltitude(self, altitude, current=None):
        if self._settings.takeoff_problem(altitude):
            return -1
        self._settings.takeoff_altitude = float(altitude)
        log.info("takeoff altitude set to %.1f m", altitude)
        return 0
