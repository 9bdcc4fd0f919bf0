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

import logging
import threading
import time
from concurrent.futures import Future, ThreadPoolExecutor

import Ice

from ..vehicle.api import CEILING, Drone, Limits
from ..vehicle.state import (CommandResult, CommandStatus, Fence, LinkHealth, LinkStatus, Severity, VehicleState,
                             replace)
from ..mission.plan import TransferOutcome
from ..params.model import ParameterTable
from . import convert, load_slice, plans
from .calls import FlightCalls, PlanCalls
from .journal import Journal
from .payload import PayloadClient
from .shots import ShotsClient
from ..payload.model import Gimbal, VehicleCamera
from .server import DEFAULT_PORTS

jderobot, mavlinkserver = load_slice()
log = logging.getLogger(__name__)

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


class IceDrone(FlightCalls, PlanCalls, PayloadClient, Drone):
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
        self._journal = Journal()              # the pilot's messages and results, the server's and our own
        self._last_answer: float | None = None
        self._lost = False
        self._lost_count = 0
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
            self.shots = ShotsClient(proxy("Shots"), self._call_ms, self._command_ms,   # driver.ice.shots
                                     self._journal.result)
        else:                                  # JdeRobot's interfaces only: Pose3D, Navdata, Extra, WP
            self._jde = {name: cast.uncheckedCast(prx.ice_invocationTimeout(self._call_ms))
                         for name, cast in (("Pose3D", jderobot.Pose3DPrx), ("Navdata", jderobot.NavdataPrx),
                                            ("Extra", jderobot.ArDroneExtraPrx), ("WP", jderobot.Pose3DPrx))
                         for prx in (proxy(name),) if prx is not None}
            self._limits = self._clamps(Limits())
            self._journal.note(Severity.NOTICE, "plain JdeRobot server (no mavlinkserver extension): state from "
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
                    journal = self._journal
                    self._answered(self._vehicle.getStatus(journal.server_message, journal.server_result))
                    if (self._subscription is not None
                            and started - max(self._subscribed_at, published or 0.0) > RESUBSCRIBE_AFTER):
                        self._unsubscribe()         # the server answers but its topic no longer reaches us
                                                    # (IceStorm dropped a slow subscriber): subscribe again
                first = False
            except Ice.Exception as exc:
                self._missed(exc)
            self._closing.wait(max(0.0, self._poll - (time.monotonic() - started)))

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
            self._journal.note(Severity.NOTICE, f"server {self._description} answering again")
        self._last_answer = time.monotonic()

    def _answered_jderobot(self, pose, nav) -> None:
        with self._lock:
            self._heard()
            s = convert.state_from_jderobot(pose, nav, tuple(self._journal.messages), tuple(self._journal.results))
            self._state = replace(s, link=replace(s.link, address=self._description, lost_count=self._lost_count))

    def _answered(self, status) -> None:
        with self._lock:
            self._heard()
            journal = self._journal
            journal.take(status)
            s = convert.state_from_status(status, tuple(journal.messages), tuple(journal.results))
            link = replace(s.link, address=f"{s.link.address} via {self._description}",
                           lost_count=s.link.lost_count + self._lost_count)
            gimbal, camera = self._payload
            self._state = replace(s, link=link, fence=self._fence, gimbal=gimbal, camera=camera,
                                  parameters=self._parameters, shot=self.shots.state)

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
                    self._journal.note(Severity.WARNING, f"server {self._description} not answering: "
                                       f"{type(exc).__name__}")
                    self._state = replace(self._state, messages=tuple(self._journal.messages))
                return
            self._lost = True
            self._lost_count += 1
            self._journal.server_lost()                # it may come back restarted, numbering from 1
            self._journal.note(Severity.CRITICAL, f"lost the server {self._description}: {type(exc).__name__}")
            link = self._state.link
            age = None if link.heartbeat_age is None else link.heartbeat_age + (now - since)
            self._state = replace(self._state, messages=tuple(self._journal.messages), link=replace(
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

    def on_status(self, status) -> None:
        """A status published on the vehicle's IceStorm topic (an Ice dispatch thread)."""
        if self._closing.is_set():
            return
        self._last_published = time.monotonic()
        self.publications += 1
        self._answered(status)

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
                    result = TransferOutcome(self._journal.result(outcome.outcome),
                                             plans.plan_from_ice(outcome.plan) if outcome.hasPlan else None)
                else:
                    result = self._journal.result(outcome)
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
            journal = self._journal
            self._vehicle.getStatusAsync(journal.server_message, journal.server_result).add_done_callback(read)
        except Exception:
            future.set_result(result)

    def _local_result(self, name: str, status: CommandStatus, reason: str) -> Future:
        """A result of our own, numbered in our results so the window shows it once."""
        with self._lock:
            result = self._journal.own_result(name, status, reason)
            self._state = replace(self._state, results=tuple(self._journal.results))
        future: Future = Future()
        future.set_result(result)
        return future

    def _no_extension(self, name: str) -> Future:
        return self._local_result(name, CommandStatus.REJECTED,
                                  "not offered by a plain JdeRobot server (no mavlinkserver extension)")



class _Subscriber(mavlinkserver.Telemetry):
    """The IceDrone's servant on its vehicle's topic: the status replaces a poll; the rest is for observers
    that want JdeRobot's shapes (pose, navdata) or only the events."""

    def __init__(self, owner: IceDrone) -> None:
        self._owner = owner

    def status(self, vehicle, status, current=None):
        self._owner.on_status(status)

    def pose(self, vehicle, published, pose, current=None):
        pass

    def navdata(self, vehicle, data, current=None):
        pass

    def event(self, vehicle, e, current=None):
        pass

    def payload(self, vehicle, p, current=None):
        self._owner.on_payload(p)


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
