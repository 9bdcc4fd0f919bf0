"""IceDrone: a :class:`~driver.vehicle.api.Drone` on another machine, reached through the MAVLinkServer's Ice interfaces.

The viewer holds it exactly as it holds the embedded driver. No Ice call ever
runs on the caller's thread: a poller thread reads the server's status into an
immutable snapshot, a sender thread carries the newest velocity over JdeRobot's
CMDVel (older ones are dropped, never queued), and a worker thread starts
commands asynchronously, resolving each Future with the vehicle's own answer.
A server that stops answering shows as a LOST link, and recovers by itself.

In a fleet (:meth:`IceDrone.for_vehicle`, docs/fleet.md) the proxies are indirect (``Vehicle@solo-1``, found
through the lab's IceGrid registry) and the status comes from the vehicle's IceStorm topic instead of polling;
the poller only asks the server itself when no publication has arrived for a while (IceStorm gone, the server
stopped), so a lost server still shows as LOST.
"""
from __future__ import annotations

import collections
import logging
import threading
import time
from concurrent.futures import Future, ThreadPoolExecutor

import Ice

from ..vehicle.api import CEILING, Drone, Limits
from ..core.frames import clamp, finite
from ..vehicle.state import (CommandResult, CommandStatus, Fence, LinkHealth, LinkStatus, Message, Severity, VehicleState,
                     replace)
from ..mission.plan import Plan, PlanKind, TransferOutcome
from ..params.metadata import metadata_for
from ..params.model import ParameterTable
from . import convert, load_slice, plans
from .params import table_from_ice
from .payload import PayloadClient
from .shots import ShotsClient
from ..payload.model import Gimbal, VehicleCamera
from .server import DEFAULT_PORTS

jderobot, mavlinkserver = load_slice()
log = logging.getLogger(__name__)

_MAX_MESSAGES = 200
_MAX_RESULTS = 50
FENCE_EVERY = 20                       # polls between reads of the fence (2 s at the default 0.1 s poll)
PARAMS_EVERY = 10                      # polls between looks at the parameters (each poll while they change)
RESUBSCRIBE_AFTER = 5.0                # s without a publication while the server answers: subscribe again
PREFIX = "UAVViewer"
#: KB a reply may have: the largest picture a JdeRobot Camera sends the viewer, 1920x1080 RGB8 (6075 KB),
#: and its header, with ~69 KB to spare. A larger one fails that one call (MemoryLimitException), nothing else.
CLIENT_MESSAGE_KB = 6144


def viewer_properties(config: str | None = None, host: str | None = None, args: list[str] | None = None,
                      prefix: str = PREFIX, certs: str | None = None) -> Ice.Properties:
    """Client properties: a JdeRobot-style file (``UAVViewer.Pose3D.Proxy=...``) and/or a host on default ports.

    ``certs``: a folder made by ``python -m driver certs``: the pilot's certificate, the server's checked
    against our CA and the host dialled; ``host`` is then reached over ``ssl``. A config file's own
    ``IceSSL.*`` keys win (and load the IceSSL plug-in).
    """
    props = Ice.createProperties(list(args or []))
    if config:
        props.load(config)
    if certs:
        from .certs import ssl_properties
        for key, value in ssl_properties(certs, "client").items():
            if not props.getProperty(key):
                props.setProperty(key, value)
    if props.getPropertiesForPrefix("IceSSL.") and not props.getProperty("Ice.Plugin.IceSSL"):
        props.setProperty("Ice.Plugin.IceSSL", "IceSSL:createIceSSL")
    if not props.getProperty("Ice.MessageSizeMax"):
        props.setProperty("Ice.MessageSizeMax", str(CLIENT_MESSAGE_KB))
    transport = "ssl" if certs else "default"
    for name, port in DEFAULT_PORTS.items():
        key = f"{prefix}.{name}.Proxy"
        if host and not props.getProperty(key):
            props.setProperty(key, f"{name}:{transport} -h {host} -p {port}")
    return props


class IceDrone(PayloadClient, Drone):
    """The remote vehicle; ``start()`` returns at once, the first status arrives in the background."""

    def __init__(self, properties: Ice.Properties, prefix: str = PREFIX, poll_interval: float = 0.1,
                 loss_timeout: float = 2.0, call_timeout: float = 1.0, command_timeout: float = 120.0,
                 vehicle_name: str = ""):
        self._props = properties
        self._prefix = prefix
        self._poll = poll_interval
        self._loss_timeout = loss_timeout
        self._call_ms = int(call_timeout * 1000)
        self._command_ms = int(command_timeout * 1000)
        self._com: Ice.Communicator | None = None
        self._vehicle = self._cmdvel = self._commands = self._extra = None
        self._jde: dict = {}                   # without the extension: JdeRobot proxies by role
        proxy = properties.getProperty(f"{prefix}.Vehicle.Proxy") or properties.getProperty(f"{prefix}.Pose3D.Proxy")
        self.vehicle_name = vehicle_name     # in a fleet: the name the registry knows, also its IceStorm topic
        self._description = f"Ice {vehicle_name or _host_of(proxy)}"
        self._subscription = None              # (topic, subscriber proxy, adapter) while subscribed
        self._subscribed_at = 0.0
        self._last_published: float | None = None
        self.publications = 0                  # statuses received from IceStorm (tests, the fleet panel)
        self._limits = Limits()
        self._pilot_limits: Limits | None = None

        self._lock = threading.Lock()
        self._state = VehicleState(link=LinkHealth(status=LinkStatus.WAITING, address=self._description))
        self._messages: collections.deque[Message] = collections.deque(maxlen=_MAX_MESSAGES)
        self._results: collections.deque[CommandResult] = collections.deque(maxlen=_MAX_RESULTS)
        self._index = 0                        # our own message numbering (server's + our own lines)
        self._result_offset = 0                # server result index + offset = ours (bumped when it may restart)
        self._result_high = 0
        self._server_message = -1              # the server's last message / result index we have
        self._server_result = -1
        self._last_message_time = 0.0
        self._last_answer: float | None = None
        self._lost = False
        self._lost_count = 0
        self._resync = False                   # after a loss: the server may have restarted its numbering
        self._said_unreachable = False
        self._fence = Fence()
        self._payload = (Gimbal(), VehicleCamera())  # the camera on the vehicle (driver.ice.payload)
        self._fence_polls = 0                  # polls until the fence is read again; None: the server has none
        self._parameters = ParameterTable()
        self._param_revision = -1              # the server's revision of the table we have
        self._param_polls: int | None = 0      # polls until the parameters are looked at; None: the server has none

        self._velocity: tuple[float, float, float, float] | None = None
        self._velocity_ready = threading.Condition(threading.Lock())
        self._closing = threading.Event()
        self._threads: list[threading.Thread] = []
        self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="ice-commands")

    @classmethod
    def from_config(cls, config: str | None = None, host: str | None = None, certs: str | None = None,
                    **kwargs) -> "IceDrone":
        return cls(viewer_properties(config, host, certs=certs), **kwargs)

    @classmethod
    def for_vehicle(cls, registry: str, name: str, certs: str | None = None, subscribe: bool = True,
                    **kwargs) -> "IceDrone":
        """The vehicle ``name`` of the lab whose IceGrid registry is at ``registry`` (``HOST:PORT``)."""
        from . import registry as fleet
        props = fleet_properties(registry, certs)
        for key, value in fleet.client_properties(PREFIX, name).items():
            props.setProperty(key, value)
        if subscribe and not props.getProperty(f"{PREFIX}.TopicManager.Proxy"):
            props.setProperty(f"{PREFIX}.TopicManager.Proxy", fleet.TOPIC_MANAGER)
        return cls(props, vehicle_name=name, **kwargs)

    # -- lifecycle ------------------------------------------------------------------------------
    @property
    def description(self) -> str:
        return self._description

    @property
    def limits(self) -> Limits:
        """The pilot's maximum speeds, never above what the server allows."""
        pilot = self._pilot_limits
        return self._limits if pilot is None else pilot.within(self._limits)

    def set_limits(self, limits: Limits) -> Limits:
        self._pilot_limits = limits.within(CEILING)
        return self.limits

    def start(self) -> "IceDrone":
        init = Ice.InitializationData()
        init.properties = self._props
        self._com = Ice.initialize(init)
        try:
            self._connect()
        except Exception:
            self._com.destroy()
            raise
        for target, name in ((self._run_poller, "ice-status"), (self._run_sender, "ice-cmdvel")):
            t = threading.Thread(target=target, name=name, daemon=True)
            t.start()
            self._threads.append(t)
        threading.Thread(target=lambda: self.parameter_metadata, name="param-metadata", daemon=True).start()
        return self

    def _connect(self) -> None:
        """Proxies from the properties (no network call: the poller finds out whether the server is there)."""
        def proxy(name: str):
            key = f"{self._prefix}.{name}.Proxy"
            return self._com.propertyToProxy(key) if self._props.getProperty(key) else None

        vehicle, cmdvel, pose, extra = proxy("Vehicle"), proxy("CMDVel"), proxy("Pose3D"), proxy("Extra")
        if cmdvel is None or (vehicle is None and pose is None):
            raise ValueError(f"{self._prefix}.CMDVel.Proxy and {self._prefix}.Vehicle.Proxy (or, for a plain "
                             f"JdeRobot server, {self._prefix}.Pose3D.Proxy) must be configured")
        self._cmdvel = jderobot.CMDVelPrx.uncheckedCast(cmdvel.ice_invocationTimeout(self._call_ms))
        if extra is not None:                  # the camera switch, with or without the extension
            self._extra = jderobot.ArDroneExtraPrx.uncheckedCast(extra.ice_invocationTimeout(self._call_ms))
        if vehicle is not None:
            self._vehicle = mavlinkserver.VehiclePrx.uncheckedCast(vehicle.ice_invocationTimeout(self._call_ms))
            self._commands = mavlinkserver.VehiclePrx.uncheckedCast(
                vehicle.ice_invocationTimeout(self._command_ms))
            self.shots = ShotsClient(proxy("Shots"), self._call_ms, self._command_ms, self._result)   # driver.ice.shots
        else:                                  # JdeRobot's interfaces only: Pose3D, Navdata, Extra, WP
            self._jde = {name: cast.uncheckedCast(prx.ice_invocationTimeout(self._call_ms))
                         for name, cast in (("Pose3D", jderobot.Pose3DPrx), ("Navdata", jderobot.NavdataPrx),
                                            ("Extra", jderobot.ArDroneExtraPrx), ("WP", jderobot.Pose3DPrx))
                         for prx in (proxy(name),) if prx is not None}
            self._limits = self._clamps(Limits())
            self._note(Severity.NOTICE, "plain JdeRobot server (no mavlinkserver extension): state from "
                                        "Pose3D and Navdata, takeoff and land through Extra")

    def close(self) -> None:
        if self._closing.is_set():
            return
        self._closing.set()
        with self._velocity_ready:
            self._velocity = None
            self._velocity_ready.notify_all()
        for t in self._threads:
            t.join(timeout=3.0)
        self._unsubscribe()                    # after the poller, which may be subscribing
        self._worker.shutdown(wait=False, cancel_futures=True)
        getattr(self.shots, "close", lambda: None)()
        if self._com is not None:
            self._com.destroy()
        with self._lock:
            self._state = replace(self._state, link=replace(self._state.link, status=LinkStatus.CLOSED))

    # -- state ----------------------------------------------------------------------------------
    def state(self) -> VehicleState:
        return self._state

    def wait_for(self, predicate, timeout: float) -> VehicleState | None:
        """Poll until ``predicate(state)`` holds; for tests and scripts, never the UI thread."""
        deadline = time.monotonic() + timeout
        while not self._closing.is_set():
            s = self._state
            if predicate(s):
                return s
            if time.monotonic() > deadline:
                return None
            self._closing.wait(self._poll / 2)
        return None

    def _note(self, severity: Severity, text: str) -> None:
        """A line of our own for the pilot (caller holds _lock)."""
        self._index += 1
        self._messages.append(Message(self._index, time.time(), severity, text, "driver"))
        (log.warning if severity <= Severity.WARNING else log.info)("%s", text)

    def _run_poller(self) -> None:
        first = True
        next_subscribe = 0.0
        while not self._closing.is_set():
            started = time.monotonic()
            if self._wants_topic() and self._subscription is None and started >= next_subscribe:
                next_subscribe = started + 3.0
                self._subscribe()
            published = self._last_published
            if not first and published is not None and started - published < max(5 * self._poll, 0.5):
                if self._vehicle is not None:       # the fence is not published: asked now and then
                    try:
                        self._read_fence()
                        self._read_parameters()
                    except Ice.Exception:           # the status from IceStorm tells how the link is
                        pass
                self._closing.wait(self._poll)      # IceStorm brings the status: no call to the server
                continue
            try:
                if self._vehicle is None:
                    navdata = self._jde.get("Navdata")
                    pose, nav = self._jde["Pose3D"].getPose3DData(), navdata.getNavdata() if navdata else None
                    self._answered_jderobot(pose, nav)
                else:
                    if first:
                        lim = self._vehicle.getLimits()
                        self._limits = self._clamps(Limits(lim.horizontal, lim.vertical, lim.yawRate))
                    self._read_fence()
                    self._read_parameters()
                    self._read_payload()
                    self.shots.poll()
                    self._answered(self._vehicle.getStatus(self._server_message, self._server_result))
                    if (self._subscription is not None
                            and started - max(self._subscribed_at, published or 0.0) > RESUBSCRIBE_AFTER):
                        self._unsubscribe()         # the server answers but its topic no longer reaches us
                                                    # (IceStorm dropped a slow subscriber): subscribe again
                first = False
            except Ice.Exception as exc:
                self._missed(exc)
            self._closing.wait(max(0.0, self._poll - (time.monotonic() - started)))

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
                self._note(Severity.NOTICE, "this MAVLinkServer does not serve the fence (an older version)")

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

    def _clamps(self, server: Limits) -> Limits:
        """The server's limits, tightened by JdeRobot's optional ``UAVViewer.CMDVel.Xmax/Ymax/Zmax/Yawmax``."""
        def tighter(key: str, value: float) -> float:
            text = self._props.getProperty(f"{self._prefix}.CMDVel.{key}")
            try:
                return min(value, abs(float(text))) if text else value
            except ValueError:
                log.warning("%s.CMDVel.%s=%r is not a number", self._prefix, key, text)
                return value
        return Limits(horizontal=min(tighter("Xmax", server.horizontal), tighter("Ymax", server.horizontal)),
                      vertical=tighter("Zmax", server.vertical), yaw_rate=tighter("Yawmax", server.yaw_rate))

    def _heard(self) -> None:
        """The server answered (caller holds _lock)."""
        if self._lost:
            self._lost = False
            self._note(Severity.NOTICE, f"server {self._description} answering again")
        self._last_answer = time.monotonic()

    def _answered_jderobot(self, pose, nav) -> None:
        with self._lock:
            self._heard()
            s = convert.state_from_jderobot(pose, nav, tuple(self._messages), tuple(self._results))
            self._state = replace(s, link=replace(s.link, address=self._description, lost_count=self._lost_count))

    def _answered(self, status) -> None:
        with self._lock:
            self._heard()
            resync, self._resync = self._resync, False
            for m in status.messages:
                if not resync and m.index <= self._server_message:
                    continue                           # polled, then published as well (or the other way)
                # after a loss we asked for everything: the clock says which lines are new
                if not resync or m.time > self._last_message_time:
                    self._index += 1
                    self._messages.append(replace(convert.message_from_status(m), index=self._index))
                    self._last_message_time = max(self._last_message_time, m.time)
            if status.messages:
                self._server_message = max(self._server_message, status.messages[-1].index)
            if resync:                                 # a restarted server numbers from 1 again
                self._result_offset = self._result_high
            for r in status.results if not resync else ():
                if r.index <= self._server_result:
                    continue
                result = self._result(r)
                self._result_high = max(self._result_high, result.index)
                self._results.append(result)
            if status.results:
                self._server_result = max(self._server_result, status.results[-1].index)
            s = convert.state_from_status(status, tuple(self._messages), tuple(self._results))
            link = replace(s.link, address=f"{s.link.address} via {self._description}",
                           lost_count=s.link.lost_count + self._lost_count)
            gimbal, camera = self._payload
            self._state = replace(s, link=link, fence=self._fence, gimbal=gimbal, camera=camera,
                                  parameters=self._parameters, shot=self.shots.state)

    def _result(self, outcome) -> CommandResult:
        """The server's outcome, numbered as in our results (the window pairs a Future's answer with it)."""
        result = convert.result_from_outcome(outcome)
        return replace(result, index=result.index + self._result_offset) if result.index > 0 else result

    def _missed(self, exc: Exception) -> None:
        with self._lock:
            now = time.monotonic()
            since = self._last_answer if self._last_answer is not None else None
            if self._lost or (since is not None and now - since < self._loss_timeout):
                return
            if since is None and self._state.link.status is LinkStatus.WAITING:
                # never reached: stay WAITING, but say why once
                if not self._said_unreachable:
                    self._said_unreachable = True
                    self._note(Severity.WARNING, f"server {self._description} not answering: {type(exc).__name__}")
                    self._state = replace(self._state, messages=tuple(self._messages))
                return
            self._lost = True
            self._lost_count += 1
            self._server_message = -1                  # a restarted server numbers from 1 again
            self._server_result = -1
            self._resync = True
            self._note(Severity.CRITICAL, f"lost the server {self._description}: {type(exc).__name__}")
            link = self._state.link
            age = None if link.heartbeat_age is None else link.heartbeat_age + (now - since)
            self._state = replace(self._state, messages=tuple(self._messages), link=replace(
                link, status=LinkStatus.LOST, heartbeat_age=age, packets_per_s=0.0,
                lost_count=link.lost_count + 1))

    # -- telemetry from IceStorm (a fleet) -------------------------------------------------------
    def _wants_topic(self) -> bool:
        return bool(self.vehicle_name and self._vehicle is not None
                    and self._props.getProperty(f"{self._prefix}.TopicManager.Proxy"))

    def _subscribe(self) -> None:
        """Subscribe to the vehicle's topic (on the poller thread); a failure is said once, then retried."""
        from .publisher import topic
        adapter = None
        try:
            t = topic(self._com, self._props.getProperty(f"{self._prefix}.TopicManager.Proxy"), self.vehicle_name)
            adapter = self._com.createObjectAdapterWithEndpoints(
                f"Telemetry-{self.vehicle_name}",
                self._props.getProperty(f"{self._prefix}.Telemetry.Endpoints") or "tcp -h 127.0.0.1")
            subscriber = adapter.addWithUUID(_Subscriber(self)).ice_oneway()
            adapter.activate()
            t.subscribeAndGetPublisher({}, subscriber)
            self._subscription = (t, subscriber, adapter)
            self._subscribed_at = time.monotonic()
            log.info("%s: telemetry from IceStorm topic %s", self._description, self.vehicle_name)
        except (Ice.Exception, RuntimeError) as exc:
            log.info("%s: no IceStorm telemetry (%s); polling the server", self._description, exc)
            if adapter is not None:
                adapter.destroy()

    def _unsubscribe(self) -> None:
        sub, self._subscription = self._subscription, None
        if sub is None:
            return
        t, subscriber, adapter = sub
        try:
            t.ice_invocationTimeout(1000).unsubscribe(subscriber)
        except Ice.Exception as exc:
            log.debug("unsubscribing from %s failed: %s", self.vehicle_name, exc)
        adapter.destroy()

    def _published(self, status) -> None:
        """A status from IceStorm (an Ice dispatch thread)."""
        if self._closing.is_set():
            return
        self._last_published = time.monotonic()
        self.publications += 1
        self._answered(status)

    # -- velocity over JdeRobot's CMDVel --------------------------------------------------------
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

    # -- commands: started on the worker, answered by the vehicle --------------------------------
    def _command(self, name: str, start, transfer: bool = False) -> Future:
        """Run ``start(proxy)`` (an Ice ...Async call) on the worker; the Future gets the vehicle's answer (a
        TransferOutcome for a ``transfer``)."""
        future: Future = Future()
        wrap = TransferOutcome if transfer else (lambda result: result)

        def failed(exc: BaseException) -> None:
            status = CommandStatus.TIMED_OUT if isinstance(exc, Ice.TimeoutException) else CommandStatus.REJECTED
            if isinstance(exc, Ice.OperationNotExistException):
                future.set_result(wrap(CommandResult(name, CommandStatus.REJECTED,
                                                     f"this MAVLinkServer has no {exc.operation or name} operation "
                                                     "(an older version)")))
                return
            future.set_result(wrap(CommandResult(name, status, f"server unreachable: {type(exc).__name__}")))

        def answered(ice_future) -> None:
            try:
                outcome = ice_future.result()
            except Exception as exc:
                failed(exc)
                return
            with self._lock:
                if transfer:
                    result = TransferOutcome(self._result(outcome.outcome),
                                             plans.plan_from_ice(outcome.plan) if outcome.hasPlan else None)
                else:
                    result = self._result(outcome)
            self._answer_after_status(future, result)

        def run() -> None:
            try:
                start(self._commands).add_done_callback(answered)
            except Exception as exc:
                failed(exc)
        try:
            self._worker.submit(run)
        except RuntimeError as exc:                     # closed
            failed(exc)
        return future

    def _answer_after_status(self, future: Future, result) -> None:
        """Settle ``future`` once the server's status has been read after its answer: whoever hears the answer
        and reads :meth:`state` finds there what the answer said (the plan uploaded, the mode taken), not a
        poll from before it."""
        def read(status_future) -> None:
            try:
                self._answered(status_future.result())
            except Exception:                           # the answer stands; the poller catches up
                pass
            future.set_result(result)
        try:
            self._vehicle.getStatusAsync(self._server_message, self._server_result).add_done_callback(read)
        except Exception:
            future.set_result(result)

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

    def _local_result(self, name: str, status: CommandStatus, reason: str) -> Future:
        """A result of our own, numbered in our results so the window shows it once."""
        with self._lock:
            self._result_high += 1
            result = CommandResult(name, status, reason, 0, self._result_high)
            self._results.append(result)
            self._state = replace(self._state, results=tuple(self._results))
        future: Future = Future()
        future.set_result(result)
        return future

    def _no_extension(self, name: str) -> Future:
        return self._local_result(name, CommandStatus.REJECTED,
                                  "not offered by a plain JdeRobot server (no mavlinkserver extension)")

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

    # -- parameters: the server's driver reads and writes them (driver.params) ------------------------
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

    # -- missions over the mavlinkserver extension --------------------------------------------------
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

    def toggle_camera(self) -> Future:
        """JdeRobot's ``Extra.toggleCam``: the server moves its Camera to its next source."""
        if self._extra is None:
            return self._local_result("switch camera", CommandStatus.REJECTED,
                                      f"no {self._prefix}.Extra.Proxy configured")
        return self._jderobot_command("switch camera", "Extra", lambda p: p.toggleCamAsync(),
                                      "the server shows its next camera")


class _Subscriber(mavlinkserver.Telemetry):
    """The IceDrone's servant on its vehicle's topic: the status replaces a poll; the rest is for observers
    that want JdeRobot's shapes (pose, navdata) or only the events."""

    def __init__(self, owner: IceDrone) -> None:
        self._owner = owner

    def status(self, vehicle, status, current=None):
        self._owner._published(status)

    def pose(self, vehicle, published, pose, current=None):
        pass

    def navdata(self, vehicle, data, current=None):
        pass

    def event(self, vehicle, e, current=None):
        pass

    def payload(self, vehicle, p, current=None):
        self._owner._published_payload(p)


def fleet_properties(registry: str, certs: str | None = None) -> Ice.Properties:
    """Client properties for a lab's registry at ``HOST:PORT`` (TLS with ``certs`` off loopback)."""
    from . import registry as fleet
    from .server import is_loopback
    host, port = fleet.registry_address(registry)
    props = viewer_properties(certs=certs)
    loopback = is_loopback(host)
    props.setProperty("Ice.Default.Locator", fleet.locator(host, port, secure=bool(certs)))
    if not props.getProperty(f"{PREFIX}.Telemetry.Endpoints"):      # where IceStorm calls us back
        transport = "ssl" if certs else "tcp"                          # with certificates: IceStorm must show one
        props.setProperty(f"{PREFIX}.Telemetry.Endpoints", f"{transport} -h 127.0.0.1" if loopback else transport)
    return props


def _host_of(proxy: str) -> str:
    """The ``-h`` host of a stringified proxy, for display."""
    parts = proxy.split()
    for i, part in enumerate(parts[:-1]):
        if part == "-h":
            return parts[i + 1]
    return proxy or "?"
