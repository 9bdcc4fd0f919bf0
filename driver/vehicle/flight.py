"""Flying: the velocity the pilot streams, a go-to, a heading, and the sequences that run in the one sequence slot
(takeoff, mission start, Land, RTL, Stop: driver.vehicle.sequences). The façade's flight commands do their work
here, each through the one command path and its flight rules (driver.vehicle.command_path, driver.vehicle.safety).

A takeoff or a mission start is exclusive: while it runs only Land, Stop and RTL are taken, and each ends it. Stop
always ends holding (GUIDED at zero velocity, BRAKE if GUIDED is refused) or on the ground disarmed, never in a
mode that needs a throttle stick.
"""
from __future__ import annotations

import logging
from concurrent.futures import Future

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core import frames
from ..core.ports import Ports
from .api import CEILING, Limits
from .command_path import REPLAYING, CommandPath
from .ports import SequencePilot
from .rules import go_to_problem, takeoff_altitude_problem
from .sequences.landing import land_sequence, return_sequence
from .sequences.mission_start import MissionStartSequence
from .sequences.stop import StopSequence
from .sequences.takeoff import TakeoffSequence
from .setpoints import SetpointStreamer
from .state import CommandStatus, Setpoint
from .ticker import MASK_POSITION

log = logging.getLogger("driver.vehicle")

__all__ = ["Flight"]


class Flight:
    """One vehicle's flying; ``path`` its command path, ``sequence`` its sequence slot, ``setpoints`` the velocity
    stream the ticker sends (``setpoint_message`` packs one), ``rules`` the flight rules, ``mission_problem`` why the
    held mission is not to be started ("" when it may be)."""

    def __init__(self, config, ports: Ports, path: CommandPath, sequence, setpoints: SetpointStreamer, rules,
                 setpoint_message, mission_problem) -> None:
        self.config = config
        self._store, self._outbox, self._clock = ports.state, ports.outbox, ports.clock
        self._replaying, self._roundtrip = ports.replaying, ports.roundtrip
        self._path, self._sequence, self._setpoints, self._rules = path, sequence, setpoints, rules
        self._setpoint_message, self._mission_problem = setpoint_message, mission_problem
        self.limits = config.limits.within(CEILING)
        self._pilot = SequencePilot(                   # what a sequence is handed (driver.vehicle.sequences.machine)
            state=lambda: self._store.state, airborne=lambda: rules.may_be_airborne(self._store.state),
            mode=path.mode, arm=lambda early=False: path.arming(True, early=early),
            disarm=lambda: path.long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (0, 0), "disarm"),
            long=path.long, retry_interval=lambda: min(config.command_timeout, self._roundtrip.timeout()),
            hold=self.hold, quiet=path.settled)

    def set_limits(self, limits: Limits) -> Limits:
        self.limits = limits.within(CEILING)          # one reference swap: safe from any thread
        return self.limits

    # -- the sticks ----------------------------------------------------------------------------------------
    def set_velocity(self, forward: float, right: float, up: float, yaw_rate: float) -> bool:
        sp = SetpointStreamer.clamp(forward, right, up, yaw_rate, self.limits)
        if sp is None:
            log.warning("velocity refused: not finite (%r, %r, %r, %r)", forward, right, up, yaw_rate)
            return False
        if self._store.state.takeoff.active:
            return False
        with self._store.lock:
            if self._setpoints.demand(sp, self._clock()):
                self._store.set(setpoint=sp)
                self._store.publish()
                self._outbox.wake()
        return True

    def hold(self) -> None:
        """Zero velocity from now (lock held): streamed for ArduCopter's GUID_TIMEOUT, then the sticks fly."""
        self._setpoints.stop(self._clock())
        self._store.set(setpoint=self._setpoints.setpoint)
        self._store.publish()

    def go_to(self, north: float, east: float, altitude: float) -> Future:
        answer = self._path.answer
        if not frames.finite(north, east, altitude):
            return answer("go to", CommandStatus.REJECTED, "coordinates are not finite numbers")
        name = f"go to N{north:.1f} E{east:.1f} alt {altitude:.1f}"
        cfg = self.config
        problem = (go_to_problem(north, east, altitude, cfg.max_altitude, cfg.max_distance)
                   or self._store.state.fence.destination_problem(north, east, altitude))
        if problem:
            return answer(name, CommandStatus.REJECTED, problem)
        busy = self._path.busy(name)
        if busy:
            return busy
        s = self._store.state
        if s.mode != "GUIDED" or not s.flying:
            return answer(name, CommandStatus.REJECTED, f"needs GUIDED and flying (mode {s.mode or '?'})")
        if s.home is None:
            return answer(name, CommandStatus.REJECTED, "the vehicle has not sent its home position yet")
        with self._store.lock:                        # a velocity stream would override the target
            self._setpoints.silence()
            self._store.set(setpoint=self._setpoints.setpoint)
        # latitude/longitude from home, altitude above home: never the EKF origin's frame
        lat, lon = frames.offset_latlon(s.home.lat, s.home.lon, north, east)
        system, component = self._outbox.target()
        self._outbox.post(mavlink.MAVLink_set_position_target_global_int_message(
            0, system, component, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
            MASK_POSITION, int(round(lat * 1e7)), int(round(lon * 1e7)), float(altitude), 0, 0, 0, 0, 0, 0, 0, 0))
        return answer(name, CommandStatus.ACCEPTED, "target sent")

    def set_yaw(self, degrees: float, relative: bool = False, rate_deg_s: float = 30.0) -> Future:
        if not frames.finite(degrees, rate_deg_s):
            return self._path.answer("yaw", CommandStatus.REJECTED, "angle is not a finite number")
        busy = self._path.busy("yaw")
        if busy:
            return busy
        if self._store.state.mode == "GUIDED" and self._setpoints.setpoint.is_zero:
            with self._store.lock:                    # zeros carry a yaw rate of 0, which would cancel the turn
                self._setpoints.silence()
            # ArduCopter ignores yaw after takeoff until a first movement command
            self._outbox.post(self._setpoint_message(Setpoint()))
        direction = (1 if degrees >= 0 else -1) if relative else 0
        angle = abs(degrees) if relative else degrees % 360.0
        return self._path.long(mavlink.MAV_CMD_CONDITION_YAW, (angle, abs(rate_deg_s), direction, 1 if relative else 0),
                               f"yaw {'by' if relative else 'to'} {degrees:g}°")

    # -- the sequences (stepped by the ticker) ----------------------------------------------------------------
    def takeoff(self, altitude: float | None = None) -> Future:
        alt = self.config.takeoff_altitude if altitude is None else altitude
        problem = (takeoff_altitude_problem(alt, self.config.max_altitude) or (REPLAYING if self._replaying else "")
                   or ("already flying" if self._store.state.flying else ""))
        if problem:
            return self._path.answer("takeoff", CommandStatus.REJECTED, problem)
        return self._run(TakeoffSequence(self._pilot, alt, self.config, self._clock()))

    def start_mission(self) -> Future:
        problem = REPLAYING if self._replaying else self._mission_problem(self._store.state)
        if problem:
            return self._path.answer("mission start", CommandStatus.REJECTED, problem)
        return self._run(MissionStartSequence(self._pilot, self.config, self._clock()))

    def land(self) -> Future:
        """LAND, always taken: it ends whatever runs (a takeoff, a mission start, a Stop)."""
        return self._replace(land_sequence(self._pilot, self._clock()), "landing")

    def return_to_launch(self) -> Future:
        """RTL, always taken: it ends whatever runs."""
        return self._replace(return_sequence(self._pilot, self._clock()), "returning home")

    def stop(self) -> Future:
        """Hold position, or end a takeoff that has not lifted anything as if it never ran
        (driver.vehicle.sequences.stop)."""
        if self._replaying:
            return self._path.answer("stop", CommandStatus.REJECTED, REPLAYING)
        with self._store.lock:
            now = self._clock()
            ended = self._sequence.end("stop")
            interrupted = ended if ended is not None and ended.exclusive else None
            s = self._store.state
            airborne = (self._rules.may_be_airborne(s) or (interrupted is not None and interrupted.lifting_sent))
            armed = s.armed or not self._path.settled(mavlink.MAV_CMD_COMPONENT_ARM_DISARM)
            testing = self._rules.motor_test_may_run(s, now)      # the motors may be spinning in a test
            self._setpoints.stop(now)                 # zeros at once, whatever the mode turns out to be
            self._store.set(setpoint=self._setpoints.setpoint)
            seq = StopSequence(self._pilot, now, interrupted, airborne, armed, testing)
            self._sequence.start(seq)
        self._outbox.wake()
        return seq.future

    def end(self, why: str) -> None:
        """End what runs in the sequence slot, cancelling what it asked."""
        with self._store.lock:
            self._sequence.end(why)

    def _replace(self, seq, why: str) -> Future:
        """Start ``seq`` in the slot, ending whatever runs there (Land and RTL win over any sequence)."""
        if self._replaying:
            return self._path.answer(seq.name, CommandStatus.REJECTED, REPLAYING)
        with self._store.lock:
            self._sequence.end(why)
            self._sequence.start(seq)
        self._outbox.wake()
        return seq.future

    def _run(self, seq) -> Future:
        """Start a takeoff or mission start (exclusive: only Land, Stop and RTL meanwhile, and each ends it)."""
        with self._store.lock:                        # check and start as one step: never two
            if not self._sequence.start(seq):
                running = self._sequence.exclusive
                return self._path.answer(seq.name, CommandStatus.REJECTED, f"a {running.name} is already running")
        self._outbox.wake()
        return seq.future
