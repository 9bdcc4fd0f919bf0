"""The remote drone's calls, by what they fly: :class:`FlightCalls` (takeoff to yaw, over the mavlinkserver
extension or, on a plain JdeRobot server, its Extra, CMDVel and WP interfaces) and :class:`PlanCalls` (parameters,
missions, fences and rally points, the extension's only). Mixed into :class:`~driver.ice.client.IceDrone`, whose
worker starts each call and whose poller reads the answer's status (``self._command``, ``self._vehicle``).
"""
from __future__ import annotations

import logging
from concurrent.futures import Future

import Ice

from ..core.frames import clamp, finite
from ..mission.plan import Plan, PlanKind, TransferOutcome
from ..params.metadata import metadata_for
from ..vehicle.state import CommandResult, CommandStatus, Severity, replace
from . import convert, load_slice, plans
from .params import table_from_ice

jderobot, mavlinkserver = load_slice()
log = logging.getLogger("driver.ice.client")

__all__ = ["FlightCalls", "PlanCalls", "FENCE_EVERY", "PARAMS_EVERY"]

FENCE_EVERY = 20                       # polls between reads of the fence (2 s at the default 0.1 s poll)
PARAMS_EVERY = 10                      # polls between looks at the parameters (each poll while they change)


class FlightCalls:
    """:class:`~driver.vehicle.api.Drone`'s flight calls on a MAVLinkServer, or on a plain JdeRobot server."""

    # -- velocity over JdeRobot's CMDVel: the newest only, on a thread of its own ----------------------------
    def set_velocity(self, forward: float, right: float, up: float, yaw_rate: float) -> bool:
        if not finite(forward, right, up, yaw_rate):
            log.warning("velocity refused: not finite (%r, %r, %r, %r)", forward, right, up, yaw_rate)
            return False
        lim = self.limits
        command = (clamp(float(forward), lim.horizontal), clamp(float(right), lim.horizontal),
                   clamp(float(up), lim.vertical), clamp(float(yaw_rate), lim.yaw_rate))
        with self._velocity_ready:
            self._velocity = command
            self._velocity_ready.notify()
        return True

    def _run_sender(self) -> None:
        while True:
            with self._velocity_ready:
                while self._velocity is None and not self._closing.is_set():
                    self._velocity_ready.wait()
                if self._closing.is_set():
                    return
                command, self._velocity = self._velocity, None
            x, y, z, yaw = convert.cmdvel_from_body(*command)
            try:
                answer = self._cmdvel.setCMDVelData(jderobot.CMDVelData(x, y, z, 0.0, 0.0, yaw))
                if answer != 0:
                    log.warning("server refused velocity %s: %d", command, answer)
            except Ice.Exception as exc:
                log.debug("velocity not delivered: %s", exc)

    def _drop_velocity(self) -> None:
        with self._velocity_ready:
            self._velocity = None

    # -- commands -----------------------------------------------------------------------------------------
    def takeoff(self, altitude: float | None = None) -> Future:
        if self._vehicle is None:
            return self._jderobot_command("takeoff", "Extra", lambda p: p.takeoffAsync())
        return self._command("takeoff", lambda p: p.takeoffAsync(0.0 if altitude is None else float(altitude)))

    def land(self) -> Future:
        self._drop_velocity()
        if self._vehicle is None:
            return self._jderobot_command("land", "Extra", lambda p: p.landAsync())
        return self._command("land", lambda p: p.landAsync())

    def stop(self) -> Future:
        self._drop_velocity()
        if self._vehicle is None:                      # zero velocity (an AR.Drone's reset cuts the motors)
            return self._jderobot_command("stop", "CMDVel", lambda p: p.setCMDVelDataAsync(
                jderobot.CMDVelData(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)))
        return self._command("stop", lambda p: p.stopAsync())

    def return_to_launch(self) -> Future:
        self._drop_velocity()
        if self._vehicle is None:
            return self._no_extension("RTL")
        return self._command("RTL", lambda p: p.returnToLaunchAsync())

    def arm(self, force: bool = False) -> Future:
        if self._vehicle is None:
            return self._no_extension("arm")
        return self._command("arm", lambda p: p.armAsync(bool(force)))

    def disarm(self, force: bool = False, emergency: bool = False) -> Future:
        if self._vehicle is None:
            return self._no_extension("disarm")
        if force and emergency:                        # the server's explicit emergencyStop, if it allows it
            return self._command("emergency motor stop", lambda p: p.emergencyStopAsync())
        return self._command("disarm", lambda p: p.disarmAsync(bool(force)))

    def set_mode(self, name: str) -> Future:
        if self._vehicle is None:
            return self._no_extension(f"mode {name}")
        return self._command(f"mode {name}", lambda p: p.setModeAsync(str(name)))

    def go_to(self, north: float, east: float, altitude: float) -> Future:
        if self._vehicle is None:
            if not finite(north, east, altitude):
                return self._local_result("go to", CommandStatus.REJECTED, "coordinates are not finite numbers")
            return self._jderobot_command("go to", "WP", lambda p: p.setPose3DDataAsync(
                jderobot.Pose3DData(float(east), float(north), float(altitude), 1.0, 1.0, 0.0, 0.0, 0.0)))
        return self._command("go to", lambda p: p.goToAsync(float(north), float(east), float(altitude)))

    def set_yaw(self, degrees: float, relative: bool = False, rate_deg_s: float = 30.0) -> Future:
        if self._vehicle is None:
            return self._no_extension("yaw")
        return self._command("yaw", lambda p: p.setYawAsync(float(degrees), bool(relative), float(rate_deg_s)))

    def _jderobot_command(self, name: str, role: str, call,
                          said: str = "JdeRobot servers give no answer") -> Future:
        """``call(proxy)`` on a JdeRobot interface, which says nothing of the vehicle: ACCEPTED once it returns."""
        prx = self._cmdvel if role == "CMDVel" else self._extra if role == "Extra" else self._jde.get(role)
        if prx is None:
            return self._no_extension(name)
        future: Future = Future()

        def answered(ice_future) -> None:
            try:
                ice_future.result()
            except Exception as exc:
                future.set_result(CommandResult(name, CommandStatus.REJECTED,
                                                f"server unreachable: {type(exc).__name__}"))
                return
            future.set_result(self._local_result(name, CommandStatus.ACCEPTED, f"sent through {role}; {said}").result())

        def run() -> None:
            try:
                call(prx).add_done_callback(answered)
            except Exception as exc:
                future.set_result(CommandResult(name, CommandStatus.REJECTED, f"server unreachable: {exc}"))
        try:
            self._worker.submit(run)
        except RuntimeError as exc:                     # closed
            future.set_result(CommandResult(name, CommandStatus.REJECTED, f"closed: {exc}"))
        return future

    def toggle_camera(self) -> Future:
        """JdeRobot's ``Extra.toggleCam``: the server moves its Camera to its next source."""
        if self._extra is None:
            return self._local_result("switch camera", CommandStatus.REJECTED,
                                      f"no {self._prefix}.Extra.Proxy configured")
        return self._jderobot_command("switch camera", "Extra", lambda p: p.toggleCamAsync(),
                                      "the server shows its next camera")


class PlanCalls:
    """:class:`~driver.vehicle.api.Drone`'s parameter and plan calls: the server's driver does the transfers; the
    poller reads the fence and the table now and then."""

    def _read_fence(self) -> None:
        """Vehicle.getFence now and then (the fence changes only when someone sets its parameters)."""
        if self._fence_polls is None:
            return
        if self._fence_polls > 0:
            self._fence_polls -= 1
            return
        try:
            self._fence = convert.fence_from_ice(self._vehicle.getFence())
            self._fence_polls = FENCE_EVERY
        except Ice.OperationNotExistException:
            self._fence_polls = None
            with self._lock:
                self._journal.note(Severity.NOTICE, "this MAVLinkServer does not serve the fence (an older version)")

    def _read_parameters(self) -> None:
        """Vehicle.getParameters: the summary only while nothing changed; each poll while the table changes."""
        if self._param_polls is None:
            return
        if self._param_polls > 0:
            self._param_polls -= 1
            return
        try:
            answer = self._vehicle.getParameters("*", self._param_revision)
        except Ice.OperationNotExistException:
            self._param_polls = None
            return
        changed = answer.revision != self._param_revision
        if changed:
            table = table_from_ice(answer)
            with self._lock:
                self._param_revision, self._parameters = answer.revision, table
                self._state = replace(self._state, parameters=table)
        self._param_polls = 0 if changed or answer.downloading else PARAMS_EVERY

    def fetch_parameters(self, refresh: bool = False) -> Future:
        if self._vehicle is None:
            return self._no_extension("parameters")
        return self._parameter_command("parameters", lambda p: p.fetchParametersAsync(bool(refresh)))

    def set_parameter(self, name: str, value: float, allow_out_of_bounds: bool = False) -> Future:
        if self._vehicle is None:
            return self._no_extension(f"param {name}")
        if not finite(value):
            return self._local_result(f"param {name}", CommandStatus.REJECTED, "not a finite number")
        return self._parameter_command(f"param {name}", lambda p: p.setParameterAsync(
            str(name), float(value), bool(allow_out_of_bounds)))

    def _parameter_command(self, name: str, start) -> Future:
        """A command whose answer changes the table: looked at again on the next poll."""
        self._param_polls = 0 if self._param_polls is not None else None
        future = self._command(name, start)
        future.add_done_callback(lambda _: setattr(self, "_param_polls", 0 if self._param_polls is not None else None))
        return future

    @property
    def parameter_metadata(self):
        """ArduPilot's metadata from this machine (the per-user cache's, else the shipped copy)."""
        return metadata_for()[0]

    def upload_plan(self, plan: Plan) -> Future:
        name = f"upload {plan.kind.label}"
        if self._vehicle is None:
            return self._no_extension_outcome(name)
        ice_plan = plans.plan_to_ice(mavlinkserver, plan)
        return self._command(name, lambda p: p.uploadPlanAsync(ice_plan), transfer=True)

    def download_plan(self, kind: PlanKind) -> Future:
        name = f"download {kind.label}"
        if self._vehicle is None:
            return self._no_extension_outcome(name)
        return self._command(name, lambda p: p.downloadPlanAsync(int(kind)), transfer=True)

    def clear_plan(self, kind: PlanKind) -> Future:
        if self._vehicle is None:
            return self._no_extension(f"clear {kind.label}")
        return self._command(f"clear {kind.label}", lambda p: p.clearPlanAsync(int(kind)))

    def cancel_transfer(self, kind: PlanKind) -> None:
        if self._vehicle is not None:
            self._worker.submit(lambda: self._commands.cancelTransferAsync(int(kind)))

    def start_mission(self) -> Future:
        return self._mission_command("mission start", lambda p: p.startMissionAsync())

    def pause_mission(self) -> Future:
        return self._mission_command("mission pause", lambda p: p.pauseMissionAsync())

    def resume_mission(self) -> Future:
        return self._mission_command("mission resume", lambda p: p.resumeMissionAsync())

    def set_mission_item(self, seq: int) -> Future:
        return self._mission_command(f"mission item {seq}", lambda p: p.setMissionItemAsync(int(seq)))

    def _mission_command(self, name: str, start) -> Future:
        return self._no_extension(name) if self._vehicle is None else self._command(name, start)

    def _no_extension_outcome(self, name: str) -> Future:
        future: Future = Future()
        future.set_result(TransferOutcome(self._no_extension(name).result()))
        return future
