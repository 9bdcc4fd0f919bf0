"""The driver and the simulated autopilot in lockstep on one hand-driven clock, with a faulty link between them.

No thread, no socket, no real second: :meth:`Lockstep.run` advances the clock by a tick, lets the autopilot hear
what reached it through the uplink's faults, steps it, sends what it said through the downlink's faults into the
driver's reader, and steps the driver's ticker, whose every frame passes the same uplink. The same seed gives the
same flight, loss and latency included, on a loaded machine as on an idle one. It is what the pilot-chaos test and
``bench/chaos.py`` fly, thousands of times over.

The autopilot is the simulator's own (:class:`~driver.sim.autopilot.Autopilot`), the link faults the simulator's
(:class:`~driver.sim.pipe.Pipe` over :class:`~driver.sim.faults.Faults`), the driver the real
:class:`~driver.vehicle.vehicle.Vehicle`, only not started: its ticker is stepped here, its reader fed here.
"""
from __future__ import annotations

import bisect
import random
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..vehicle.vehicle import Vehicle, VehicleConfig
from .autopilot import Autopilot
from .clock import ManualClock
from .faults import Faults, LinkFaults
from .pipe import Pipe
from .vehicle import SimConfig

__all__ = ["Lockstep", "Heard"]

TICK = 0.02                      # s: the autopilot's 50 Hz loop (SimConfig.rate_hz)
DRIVER_EVERY = 2                 # the driver's ticker every 2 ticks: 25 Hz, as its 20 Hz setpoint stream needs


@dataclass(frozen=True)
class Heard:
    """A message the autopilot got from the ground station, what it was doing when it did, and what the driver
    that sent it could know then: the vehicle as its newest heartbeat showed it."""
    t: float                     # the autopilot's time
    msg: object
    armed: bool
    landed: bool
    mode: str
    sent: float                  # when the driver sent it
    known_armed: bool            # the vehicle at the time of the newest heartbeat the driver had heard then
    known_landed: bool


class Lockstep:
    """One autopilot, one driver, one link. ``uplink``/``downlink``: the link's faults each way (times in the
    lockstep clock's seconds, which is the autopilot's time too)."""

    def __init__(self, seed: int, uplink: LinkFaults | None = None, downlink: LinkFaults | None = None,
                 profile: str = "copter-4", ready_after: float = 2.0, driver: dict | None = None, **sim) -> None:
        self.clock = ManualClock(start=1000.0)
        self.seed = seed
        self.sim_config = SimConfig(tcp_port=None, seed=seed, profile=profile, ready_after=ready_after, **sim)
        self.faults = Faults(seed=seed, clock=self.clock.now)
        self.faults.uplink = uplink or LinkFaults()
        self.faults.downlink = downlink or LinkFaults()
        self._said: list = []
        self.autopilot = Autopilot(self.sim_config, self.faults, emit=self._said.append,
                                   emit_to=lambda msg, link: self._said.append(msg))
        rng = random.Random(seed)
        self._up = Pipe(self.faults, lambda: self.faults.uplink, self.faults.counters.uplink,
                        random.Random(rng.random()))
        self._down = Pipe(self.faults, lambda: self.faults.downlink, self.faults.counters.downlink,
                          random.Random(rng.random()))
        self._parser = mavlink.MAVLink(None)
        self._parser.robust_parsing = True
        self._encoder = mavlink.MAVLink(None, srcSystem=self.sim_config.system_id,
                                        srcComponent=self.sim_config.component_id)
        self._mavlink1 = not self.autopilot.profile.mavlink2
        self._driver_options = dict(driver or {})
        self.heard: list[Heard] = []           # everything the autopilot got from us, in order
        self.reported = -1.0                   # the autopilot's time of the newest heartbeat the driver has heard
        self._told: list = []                  # (frame, sent at, type) reaching the driver this tick
        self._history: list = []               # (time, armed, landed) each tick, to say what a driver could know
        self.ticks = 0
        self.vehicle = self._new_vehicle()

    # -- the parts -------------------------------------------------------------------------------------------
    def _new_vehicle(self) -> Vehicle:
        """Each driver with a component id of its own (190, 191, ...): what an earlier one sent, still on its way,
        is told apart from what this one sends, and its answers are not taken for this one's."""
        self.instances = getattr(self, "instances", 0) + 1
        options = dict(connection="udpin:127.0.0.1:0", tlog_path=None, param_cache=None, param_metadata=None,
                       source_component=189 + self.instances)
        options.update(self._driver_options)
        return Vehicle(VehicleConfig(**options), clock=self.clock.now)

    def reconnect(self) -> Vehicle:
        """The ground station starts again (a new driver, knowing nothing) on the same vehicle."""
        self.vehicle.close()
        self.vehicle = self._new_vehicle()
        self.reported = -1.0
        return self.vehicle

    def close(self) -> None:
        self.vehicle.close()

    @property
    def now(self) -> float:
        return self.clock.now()

    # -- time ------------------------------------------------------------------------------------------------
    def run(self, seconds: float, check=None) -> None:
        """Advance ``seconds``, tick by tick; ``check()`` after every tick (an invariant that must always hold)."""
        for _ in range(max(1, round(seconds / TICK))):
            self.tick()
            if check is not None:
                check()

    def tick(self) -> None:
        self.clock.advance(TICK)
        now = self.clock.now()
        ap = self.autopilot
        for item in self._up.due(now):
            self._hear(item)
        ap.step(TICK)
        said, self._said[:] = list(self._said), []
        said += ap.take_gimbal_messages()
        for msg in said:
            if self._mavlink1 and msg.get_msgId() > 255:
                continue
            frame = msg.pack(self._encoder, force_mavlink1=self._mavlink1)
            self._encoder.seq = (self._encoder.seq + 1) % 256
            self._told += self._down.send((frame, ap.t, msg.get_type()), now)
        self._told += self._down.due(now)
        if self._told:                                  # what reached the driver this tick, read at once
            self.vehicle.ingest(b"".join(frame for frame, _, _ in self._told), publish=True)
            self.reported = max([emitted for _, emitted, kind in self._told if kind == "HEARTBEAT"],
                                default=self.reported)
            self._told = []
        self.ticks += 1
        self._history.append((ap.t, ap.armed, ap.landed))
        if self.ticks % DRIVER_EVERY == 0:
            known = self._at(self.reported)
            for frame in self.vehicle.step(frames=True):
                for out in self._up.send((frame, ap.t, known), now):
                    self._hear(out)

    def _at(self, t: float) -> tuple[bool, bool]:
        """(armed, landed) at the autopilot's time ``t`` (unknown before the first tick: disarmed, landed)."""
        history = self._history
        i = bisect.bisect_right(history, (t, True, True)) - 1
        return (history[i][1], history[i][2]) if i >= 0 else (False, True)

    def _hear(self, item) -> None:
        frame, sent, (known_armed, known_landed) = item
        ap = self.autopilot
        for msg in self._parser.parse_buffer(frame) or ():
            kind = msg.get_type()
            if kind == "BAD_DATA" or kind.startswith("UNKNOWN"):
                continue
            version = 2 if msg.get_msgbuf()[0] == mavlink.PROTOCOL_MARKER_V2 else 1
            if version == 2 and self._mavlink1:
                continue                         # a MAVLink 1 autopilot never sees these frames
            self.heard.append(Heard(ap.t, msg, ap.armed, ap.landed, ap.mode_name, sent, known_armed, known_landed))
            ap.sender = None
            ap.handle(msg, version)
