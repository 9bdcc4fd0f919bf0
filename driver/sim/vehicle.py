"""SimVehicle: an ArduCopter stand-in that speaks real MAVLink over real sockets.

A clock thread advances the :class:`~driver.sim.autopilot.Autopilot` at
``rate_hz`` steps per sim second, ``speedup`` times faster than real time, and
feeds it what the :class:`~driver.sim.server.LinkServer` received since the
last step (through the uplink's faults); what the vehicle says goes out through
the downlink's faults. The same thread hands on frames the faults held back.
It also checks each frame's MAVLink 2 signature just before the autopilot would
see it (signing.py), so a SETUP_SIGNING governs the very next frame.
"""
from __future__ import annotations

import logging
import queue
import threading
import time
from collections import deque
from dataclasses import dataclass

from .autopilot import Autopilot, SimTruth
from .clock import RealClock
from .components import components_of
from .faults import Faults
from .gimbal import GIMBAL_COMPONENT
from .profiles import profile_of
from .server import LinkServer
from .signing import Signing

log = logging.getLogger(__name__)

__all__ = ["SimConfig", "SimVehicle"]


@dataclass
class SimConfig:
    tcp_host: str = "127.0.0.1"
    tcp_port: int | None = 5760             # 0 = ephemeral (see SimVehicle.tcp_port), None = no TCP; a telemetry
                                            # link (SERIAL1-like): unsigned frames dropped once signing is on
    usb_port: int | None = None             # a TCP port acting as USB (SERIAL0): unsigned frames always accepted;
                                            # 0 = ephemeral (SimVehicle.usb_port), None = none
    udp_out: str | None = None              # "HOST:PORT": push there like the Solo's controller to 14550
    udp_listen: str | None = None           # "HOST:PORT": serve whoever sent last, like SITL's UDP
    speedup: float = 1.0
    ready_after: float = 20.0               # sim seconds until ready to arm
    home: tuple[float, float, float, float] = (40.2839, -3.7940, 664.0, 0.0)   # lat, lon, alt MSL, heading deg
    # Where the EKF origin is from home, NED metres: the origin is set where the vehicle was at GPS lock,
    # home where it armed, so they differ; LOCAL_POSITION_NED and MAV_FRAME_LOCAL_NED targets use the origin.
    origin_offset: tuple[float, float, float] = (3.0, -2.0, 1.5)
    profile: str = "copter-4"               # "copter-4" (ArduCopter 4.x, as recorded) or "solo" (stock 3DR Solo)
    mavlink2: bool = True                   # False: MAVLink 1 only (the "solo" profile implies it)
    gimbal: bool = False                    # a gimbal (component 154) says HEARTBEAT, in MAVLink 2 always
    companion: bool = False                 # a companion computer (component 191) says HEARTBEAT
    camera: bool | str = False              # a camera (CAM1_TYPE): True/"mavlink" or "trigger" (gimbal.py)
    system_id: int = 1
    component_id: int = 1
    battery_cells: int = 4
    battery_capacity_mah: int = 5200
    auto_disarm_after: float = 10.0
    rate_hz: int = 50
    seed: int | None = None
    adsb: int = 0                           # aircraft of simulated ADS-B traffic (SIM_ADSB_COUNT; adsb.py)
    calibration_model: bool = False         # the airframe takes each pose a calibration asks (calibration.py)
    signing_key: bytes | None = None        # 32 bytes: a MAVLink 2 signing key already in storage at power-on
    log_dir: str | None = None              # where the DataFlash logs are kept (None: a temporary folder)
    radio_baud: int | None = None           # a telemetry radio's rate: a parameter list streams only as fast as it
                                            # allows (params.py); None: as fast as the recording's TCP (2,300/s)


class SimVehicle:
    """The simulated copter: ``start()``, fly it over MAVLink, read ``truth()``, ``stop()``.

    ``clock``: real time by default; a :class:`~driver.sim.clock.ManualClock` makes the sim's pace (and the
    link faults' latency and outages) move only when a test says so.
    """

    def __init__(self, config: SimConfig | None = None, clock=None) -> None:
        self.config = config if config is not None else SimConfig()
        if not self.config.speedup > 0 or not self.config.rate_hz > 0:
            raise ValueError("speedup and rate_hz must be positive")
        profile_of(self.config)                          # an unknown profile fails here
        if len(tuple(self.config.origin_offset)) != 3:
            raise ValueError("origin_offset is (north, east, down) in metres")
        usb_port = getattr(self.config, "usb_port", None)
        if usb_port is not None and not 0 <= usb_port <= 65535:
            raise ValueError("usb_port is 0 (any free port) to 65535, or None")
        self.clock = clock if clock is not None else RealClock()
        self.faults = Faults(seed=self.config.seed, clock=self.clock.now)
        self.received_setpoints: deque = deque(maxlen=2000)
        self.received_messages: deque = deque(maxlen=2000)
        self.steps = 0                                   # physics steps taken so far
        self._speedup = float(self.config.speedup)       # now (the config says how it started)
        self.signing = Signing(self.config)              # key (None: off), counters, every link's channel
        self._inbox: queue.SimpleQueue = queue.SimpleQueue()
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.server = LinkServer(self.config, self.faults, self._received, self.signing)
        self._outbox: list = []                          # (message, peer or None for every peer)
        self.autopilot = Autopilot(self.config, self.faults, emit=lambda msg: self._outbox.append((msg, None)),
                                   emit_to=lambda msg, peer: self._outbox.append((msg, peer)))
        self.autopilot.signing = self.signing
        self.components = components_of(self.config)
        self._truth = self.autopilot.truth()
        self._started = False

    # -- lifecycle ---------------------------------------------------------------------------------
    def start(self) -> "SimVehicle":
        if self._started:
            return self
        self._started = True
        self._stop.clear()
        self.server.start()
        self._thread = threading.Thread(target=self._run, name="sim-clock", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the clock, close every socket. Safe to call twice."""
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=1.0)
        self.server.stop()

    def __enter__(self) -> "SimVehicle":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    @property
    def speedup(self) -> float:
        """Sim seconds per real second. It may change while the vehicle runs (from the next step on), as SITL's
        SIM_SPEEDUP: a test flies what it merely sets up (a takeoff) faster than what it checks."""
        return self._speedup

    @speedup.setter
    def speedup(self, value: float) -> None:
        if not value > 0:
            raise ValueError("speedup must be positive")
        self._speedup = float(value)

    @property
    def tcp_port(self) -> int:
        return self.server.tcp_port

    @property
    def udp_port(self) -> int | None:
        return self.server.udp_port

    @property
    def usb_port(self) -> int | None:
        """The USB-like port (SERIAL0) once started, None without one."""
        return self.server.usb_port

    @property
    def clients(self) -> int:
        """TCP ground stations connected now."""
        return self.server.clients

    def truth(self) -> SimTruth:
        return self._truth

    def inject(self, raw: bytes) -> None:
        """Send raw bytes to every connected peer (garbage-flood tests)."""
        self.server.inject(raw)

    def step(self, dt: float | None = None) -> None:
        """Advance one physics step now (for tests that drive the clock themselves)."""
        with self._lock:
            self._step(dt or 1.0 / self.config.rate_hz)

    # -- internals -----------------------------------------------------------------------------------
    def _received(self, msg, version: int, peer=None) -> None:
        self._inbox.put((msg, version, peer))

    def _step(self, dt: float) -> None:
        # what a step says goes out in one write a peer (SITL writes its port's buffer once a loop), not a frame
        # at a time: a system call and a wake-up of the ground station's reader per message is most of the cost
        # of a simulated vehicle at rest
        with self.server.held():
            self._step_held(dt)

    def _step_held(self, dt: float) -> None:
        self.server.pump()                 # uplink frames whose latency is over join the inbox
        autopilot = self.autopilot
        while True:
            try:
                msg, version, peer = self._inbox.get_nowait()
            except queue.Empty:
                break
            if not self.signing.admit(msg, getattr(peer, "channel", None)):
                continue                   # dropped by the link's parser: the autopilot never hears it
            kind = msg.get_type()
            self.received_messages.append((autopilot.t, kind, version))
            if kind == "SET_POSITION_TARGET_LOCAL_NED":
                self.received_setpoints.append((autopilot.t, msg.coordinate_frame, msg.type_mask,
                                                msg.vx, msg.vy, msg.vz, msg.yaw_rate))
            autopilot.sender = peer
            autopilot.handle(msg, version)
        autopilot.sender = None
        autopilot.step(dt)
        if self.signing.enabled and autopilot.stage.gps_fix:
            self.signing.update_timestamp(time.time())   # GPS time (AP_RTC), as SYSTEM_TIME says it
        self.steps += 1
        self._truth = autopilot.truth()
        # only now on the wire: nothing a peer hears is newer than truth()
        for msg, peer in self._outbox:
            self.server.broadcast(msg, to=peer)
        self._outbox.clear()
        for component in self.components:
            for msg in component.step(autopilot.t):
                self.server.broadcast(msg, component.component_id, component.mavlink2)
        for msg in autopilot.take_gimbal_messages():     # the Solo's gimbal (154) and its GoPro (gimbal.py)
            self.server.broadcast(msg, GIMBAL_COMPONENT, True if self.config.gimbal else None)
        self.server.pump()                 # downlink frames whose latency is over

    def _run(self) -> None:
        clock = self.clock
        dt = 1.0 / float(self.config.rate_hz)
        next_time = clock.now()
        while not self._stop.is_set():
            try:
                with self._lock:
                    self._step(dt)
            except Exception:      # keep flying: a bug in one step must not freeze the vehicle
                log.exception("sim step failed")
            next_time += dt / self._speedup                   # read each step: see the speedup property
            delay = next_time - clock.now()
            if delay > 0:
                if clock.wait(self._stop, delay):
                    break
            elif delay < -0.25:    # far behind (machine busy): drop the backlog instead of racing
                next_time = clock.now()
