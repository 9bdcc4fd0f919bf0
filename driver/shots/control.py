"""The smart shots as a part of the vehicle (``vehicle.shots``): started by the pilot, stepped by the ticker.

:class:`ShotControl` is handed the vehicle's narrow services (driver.core.ports: the clock, the state, the
outbox, the command path) and the payload (to point the camera), never the vehicle. The ticker calls
:meth:`ShotControl.service` each beat, under the state lock, and writes what it returns.

The rules it keeps:

* a shot starts only in the air and ready: link up, armed and airborne (the vehicle says so), no takeoff
  running, home and position known, and not landing or returning; the path checked against the limits first;
* it asks for GUIDED (FOLLOW for ArduCopter's own follow) and flies only once the vehicle's heartbeat shows it;
* Stop, Land, RTL and any mode the pilot picks end it at once (the vehicle's façade tells :meth:`end` first);
  so does any other mode the vehicle reports, a velocity the pilot streams, or the vehicle landing;
* a link lost for LINK_GRACE s ends it and leaves the vehicle to its own failsafe (the guided target stops after
  GUID_TIMEOUT; FS_GCS_ENABLE decides the rest); a shorter silence (a lossy radio) is ridden out;
* a shot that ends by itself, or that the pilot stops, holds where the vehicle is (zero velocity, streamed
  for 3 s as Stop does) and clears the region of interest it set;
* its state is the vehicle's telemetry (each shot's ``report``), published in ``VehicleState.shot``.
"""
from __future__ import annotations

import logging
import math
from concurrent.futures import Future
from dataclasses import replace

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from ..core.results import CommandResult, CommandStatus, Severity
from . import launch
from .api import Shots
from .base import Shot
from .limits import Bounds
from .model import MAX_KEYFRAMES, Keyframe, Look, ShotKind, ShotPhase, ShotState, Sticks
from .setpoint import target_message
from .targets import GivenTarget, TargetSource, open_target

log = logging.getLogger(__name__)

__all__ = ["ShotControl", "SHOT_RATE"]

SHOT_RATE = 10.0             # Hz: targets to the vehicle
GIMBAL_RATE = 5.0            # Hz: gimbal angles, when the shot points it
REPORT_RATE = 5.0            # Hz: the shot's state from telemetry
MODE_WAIT = 10.0             # s for the vehicle to show the shot's mode (or its parameters to be set)
STICK_DEADMAN = 0.5          # s without stick input: centred
LINK_GRACE = 10.0            # s the link may be down (no heartbeat) before the shot ends
RETURNING = ("LAND", "RTL", "SMART_RTL", "AUTO")


class ShotControl(Shots):
    """One vehicle's smart shots; thread-safe (every call takes the state lock)."""

    def __init__(self, ports, payload, setpoints, config, set_parameter):
        self._clock, self._store, self._outbox = ports.clock, ports.state, ports.outbox
        self._commands, self._settler = ports.commands, ports.settler
        self._payload, self._setpoints, self._config, self._set_parameter = payload, setpoints, config, set_parameter
        self._shot: Shot | None = None
        self._mode = "GUIDED"
        self._running = False                      # the vehicle showed the shot's mode
        self._waits: list[Future] = []             # mode and parameter requests before the shot flies
        self._started_at = 0.0
        self._start: tuple[str, Future] | None = None
        self._last_step: float | None = None
        self._next_gimbal = self._next_report = 0.0
        self._roi = False
        self._sticks, self._sticks_at = Sticks(), -math.inf
        self._given = GivenTarget(self._clock, "given positions")
        self._source: TargetSource | None = None    # a stream of fixes, kept open once asked for
        self._mode_asked = False
        self._first_phase = ShotPhase.FLYING
        self._lost_since: float | None = None
        self._fix_sent: float | None = None
        self._follow_setup: list[tuple[str, float]] = []

    # -- the pilot's calls --------------------------------------------------------------------------------
    def orbit(self, lat=None, lon=None, alt=0.0, radius=None, speed=0.0, roi=False) -> Future:
        return self._begin("orbit", lambda s, b: launch.make_orbit(s, b, lat, lon, alt, radius, speed, roi))

    def cable(self, speed=0.0, attach=None) -> Future:
        return self._begin("cable", lambda s, b: launch.make_cable(s, b, s.shot.keyframes, speed, attach))

    def selfie(self, distance=30.0, rise=15.0, speed=3.0, pilot=None) -> Future:
        return self._begin("selfie", lambda s, b: launch.make_selfie(s, b, distance, rise, speed, pilot))

    def follow(self, source="given", engine="auto") -> Future:
        try:
            latest = self._target(source)
        except (ValueError, OSError) as exc:
            return self._answer("follow", CommandStatus.REJECTED, str(exc))

        def make(s, b):
            chosen, note = launch.follow_engine(s, engine)
            shot = launch.make_follow(s, b, latest, chosen, self._clock())
            shot.detail = note
            self._follow_setup = launch.follow_params(shot, self._config.source_system) if chosen == "FOLLOW" else []
            return shot
        return self._begin("follow", make)

    def _target(self, source: str):
        """The ``latest`` of the position source named: the given positions, or a stream opened on first use and
        kept open (its first fixes take a moment: a follow asked before them is refused, and may be asked again)."""
        if source in ("", "given", "api", "ice"):
            return self._given
        with self._store.lock:
            if self._source is None or self._source.name != source:
                if self._source is not None:
                    self._source.close()
                self._source = open_target(source, self._clock)
            return self._source

    def follow_position(self, lat, lon, alt=None, vn=None, ve=None, vd=0.0) -> bool:
        return self._given.put(lat, lon, alt, vn, ve, vd)

    def pano(self, shape="cylinder", fov=360.0, lens=74.0, pitch=0.0) -> Future:
        return self._begin("pano", lambda s, b: launch.make_pano(s, b, shape, fov, lens, pitch,
                                                                 self._payload.take_photo))

    def sticks(self, forward, right, up, yaw) -> bool:
        sticks = Sticks.checked(forward, right, up, yaw)
        with self._store.lock:
            if sticks is None or self._shot is None or not self._shot.phase.active:
                return False
            self._sticks, self._sticks_at = sticks, self._clock()
        return True

    def pause(self) -> Future:
        return self._button("shot pause", lambda shot: shot.pause())

    def resume(self) -> Future:
        return self._button("shot resume", lambda shot: shot.resume())

    def reverse(self) -> Future:
        return self._button("shot reverse", lambda shot: shot.reverse())

    def set_cruise(self, speed) -> Future:
        if not math.isfinite(speed):
            return self._answer("shot speed", CommandStatus.REJECTED, "not a finite number")
        return self._button("shot speed", lambda shot: shot.set_cruise(speed))

    def stop(self) -> Future:
        with self._store.lock:
            if self._shot is None or not self._shot.phase.active:
                return self._answer("shot stop", CommandStatus.REJECTED, "no shot is running")
            self._finish(ShotPhase.ENDED, "stopped by the pilot: holding where it is", hold=True)
        return self._answer("shot stop", CommandStatus.ACCEPTED, "holding where it is")

    def end(self, why: str) -> None:
        """Stop, Land, RTL or a mode the pilot picked (the vehicle's façade): the shot ends at once, sending
        nothing more; what the pilot asked does the rest."""
        with self._store.lock:
            if self._shot is not None and self._shot.phase.active:
                self._finish(ShotPhase.ENDED, f"{why}: the pilot took over")

    # -- keyframes ----------------------------------------------------------------------------------------
    def keyframes(self) -> tuple[Keyframe, ...]:
        return self._store.state.shot.keyframes

    def record_keyframe(self) -> Future:
        with self._store.lock:
            s = self._store.view()
            state = self._store.state
            if state.home is None or state.local is None:
                return self._answer("record keyframe", CommandStatus.REJECTED, "the vehicle's position is not known yet")
            if self._shot is not None and self._shot.phase.active and self._shot.kind is ShotKind.CABLE:
                return self._answer("record keyframe", CommandStatus.REJECTED, "the cable is playing: stop it first")
            key, note = launch.keyframe_here(state)
            keys = list(s["shot"].keyframes)
            if keys and launch.too_close(keys[-1], key):
                keys[-1], what = key, f"keyframe {len(keys)} moved here (within 1 m of it)"
            elif len(keys) >= MAX_KEYFRAMES:
                return self._answer("record keyframe", CommandStatus.REJECTED, f"a cable has at most {MAX_KEYFRAMES}")
            else:
                keys.append(key)
                what = f"keyframe {len(keys)}: {key.alt:.1f} m up, camera {key.pitch:.0f}° at {key.yaw:.0f}°"
            self._set_state(keyframes=tuple(keys))
        return self._answer("record keyframe", CommandStatus.ACCEPTED, what + (f" ({note})" if note else ""))

    def set_keyframes(self, keyframes) -> Future:
        keys = tuple(keyframes)
        if len(keys) > MAX_KEYFRAMES or not all(isinstance(k, Keyframe) and k.finite() for k in keys):
            return self._answer("keyframes", CommandStatus.REJECTED, f"at most {MAX_KEYFRAMES} places on Earth")
        with self._store.lock:
            if self._shot is not None and self._shot.phase.active and self._shot.kind is ShotKind.CABLE:
                return self._answer("keyframes", CommandStatus.REJECTED, "the cable is playing: stop it first")
            self._set_state(keyframes=keys)
        return self._answer("keyframes", CommandStatus.ACCEPTED, f"{len(keys)} keyframes" if keys else "cleared")

    # -- starting ------------------------------------------------------------------------------------------
    def _ready_problem(self, s) -> str | None:
        if not s.connected:
            return "no vehicle connected"
        if s.home is None or s.local is None:
            return "the vehicle has not sent its home and position yet"
        if not s.armed or s.in_air is not True:
            return "a shot starts in the air: take off first"
        if s.takeoff.active:
            return "the takeoff is still running"
        if s.mode in RETURNING:
            return f"the vehicle is in {s.mode}: a shot starts from a hover"
        if not s.readiness.ekf_ok:
            return "the vehicle has no position estimate (EKF): GUIDED is not possible"
        if self._shot is not None and self._shot.phase.active:
            return f"a {self._shot.kind.value} is running: stop it first"
        return None

    def _begin(self, name: str, make) -> Future:
        with self._store.lock:
            s = self._store.state
            problem = self._ready_problem(s)
            if problem:
                return self._answer(name, CommandStatus.REJECTED, problem)
            bounds = Bounds(s, self._config.max_altitude, self._config.max_distance)
            try:
                shot = make(s, bounds)
                problem = bounds.path_problem(shot.path_points(), f"the {name}") \
                    if hasattr(shot, "path_points") else bounds.problem(*launch.here(s))
            except ValueError as exc:
                return self._answer(name, CommandStatus.REJECTED, str(exc))
            if problem:
                return self._answer(name, CommandStatus.REJECTED, problem)
            now = self._clock()
            self._shot, self._mode, self._running = shot, shot.engine, False
            self._first_phase, shot.phase = shot.phase, ShotPhase.STARTING
            self._started_at, self._last_step, self._fix_sent = now, None, None
            self._sticks_at = -math.inf
            self._setpoints.silence()                # a velocity stream would fight the shot's targets
            self._store.set(setpoint=self._setpoints.setpoint)
            future: Future = Future()
            self._start = (name, future)
            self._waits = [self._set_parameter(p, v) for p, v in self._follow_setup] if shot.engine == "FOLLOW" else []
            self._follow_setup, self._mode_asked = [], False
            if not self._waits:
                self._ask_mode(s)
            self._roi = shot.roi is not None
            if self._roi:
                self._payload.look_at(*launch.latlon_of(s, shot.roi))
            self._set_state(**self._fresh_state(s, shot))
            self._store.publish()
            self._outbox.wake()
        return future

    def _ask_mode(self, s) -> None:
        self._mode_asked = True
        self._started_at = self._clock()             # MODE_WAIT counts from here, after the FOLLOW parameters
        if s.mode != self._mode:
            self._waits.append(self._commands.mode(self._mode))

    def _fresh_state(self, s, shot: Shot) -> dict:
        path, looks = shot.drawing() if hasattr(shot, "drawing") else ([], [])
        centre = getattr(shot, "roi", None) or getattr(shot, "centre", None)
        return {"shot": ShotState(
            shot.kind, ShotPhase.STARTING, f"asking for {self._mode}", self._mode, s.shot.keyframes,
            tuple(launch.latlon_of(s, p) for p in path),
            tuple(Look(*launch.latlon_of(s, (n, e, 0.0))[:2], yaw, pitch) for n, e, yaw, pitch in looks),
            centre=launch.latlon_of(s, centre) if centre is not None else None,
            radius_wanted=getattr(shot, "radius_wanted", None), cruise=shot.cruise)}

    # -- the ticker's beat ---------------------------------------------------------------------------------
    def service(self, now: float, state) -> list:
        """What the shot sends now (state lock held by the ticker)."""
        shot = self._shot
        if shot is None or not shot.phase.active:
            return []
        why = self._gone(state, now)
        if why:
            self._finish(ShotPhase.ENDED, why)
            return []
        out = self._follow_fix(now, state) if shot.engine == "FOLLOW" else []
        if not self._running:
            if not self._started(now, state):
                return out
        if self._last_step is None or now - self._last_step >= 1.0 / SHOT_RATE - 0.005:
            out += self._beat(now, state, shot)
        if now >= self._next_report and shot.phase.active:
            self._next_report = now + 1.0 / REPORT_RATE
            fields = shot.report(state)
            centre = getattr(shot, "last_fix", None)
            if centre is not None:
                fields["centre"] = (centre.lat, centre.lon, (centre.alt - state.home.alt) if centre.alt is not None
                                    else 0.0)
                fields["target_age"] = now - centre.time
            self._set_state(phase=shot.phase, detail=shot.detail, cruise=shot.cruise, **fields)
        return out

    def _gone(self, s, now: float) -> str:
        """Why the shot cannot go on, from the vehicle's own reports ("" when it can). A link silent for a few
        heartbeats (a lossy radio) is ridden out: the targets go on (those that arrive keep the shot smooth, and
        without them ArduCopter stops the target after GUID_TIMEOUT); silent for LINK_GRACE s it ends the shot,
        and the vehicle's own failsafe decides."""
        if not s.connected:
            self._lost_since = now if self._lost_since is None else self._lost_since
            if now - self._lost_since > LINK_GRACE:
                return f"the link is down ({LINK_GRACE:g} s): the vehicle's own failsafe decides"
        else:
            self._lost_since = None
        if not s.armed or s.in_air is False:
            return "the vehicle is no longer flying"
        if not s.setpoint.is_zero:
            return "the pilot's velocity commands took over"
        if self._running and s.mode != self._mode:
            return f"the vehicle switched to {s.mode or '?'}: the pilot took over"
        return ""

    def _started(self, now: float, state) -> bool:
        failed = next((f.result() for f in self._waits if f.done() and not f.result().ok), None)
        if failed is not None:
            self._finish(ShotPhase.ENDED, f"{failed.command}: {failed.reason or failed.status.value}",
                         status=failed.status)
            return False
        if not self._mode_asked and all(f.done() for f in self._waits):
            self._ask_mode(state)                    # the FOLLOW parameters are set: now the mode
        if state.mode == self._mode:
            self._running = True
            self._shot.phase = self._first_phase
            self._shot.detail = self._shot.detail or f"flying in {self._mode}"
            name, future = self._start
            self._settle(future, name, CommandStatus.ACCEPTED, f"{name} started in {self._mode}")
            self._set_state(phase=self._shot.phase, detail=self._shot.detail)
            self._store.publish()
            return True
        if self._mode_asked and now - self._started_at > MODE_WAIT:
            self._finish(ShotPhase.ENDED, f"the vehicle did not switch to {self._mode} in {MODE_WAIT:g} s",
                         status=CommandStatus.TIMED_OUT)
        return False

    def _beat(self, now: float, state, shot: Shot) -> list:
        dt = min(max(now - self._last_step, 0.02), 0.3) if self._last_step is not None else 1.0 / SHOT_RATE
        self._last_step = now
        sticks = self._sticks if now - self._sticks_at <= STICK_DEADMAN else Sticks()
        target = shot.step(now, dt, state, sticks)
        failure = getattr(shot, "failure", "")
        if failure:
            self._finish(ShotPhase.ENDED, failure, hold=True)
            return []
        out = []
        if target is not None:
            if shot.engine == "GUIDED":
                msg = target_message(target, state.home, *self._outbox.target())
                if msg is None:
                    self._finish(ShotPhase.ENDED, "a target was not a finite number: holding", hold=True)
                    return []
                out.append(msg)
            if target.pitch is not None and now >= self._next_gimbal:
                self._next_gimbal = now + 1.0 / GIMBAL_RATE
                out.append(self._payload.angle_message(target.pitch, 0.0, state))
        if shot.phase is ShotPhase.DONE:
            self._finish(ShotPhase.DONE, shot.detail or "done", hold=True)
        return out

    def _follow_fix(self, now: float, state) -> list:
        """ArduCopter's FOLLOW: each new fix as FOLLOW_TARGET (position and velocity; AP_Follow's est_capabilities)."""
        fix = self._shot.latest()
        if fix is None or fix.time == self._fix_sent:
            return []
        self._fix_sent = fix.time
        alt = fix.alt if fix.alt is not None else state.home.alt
        return [mavlink.MAVLink_follow_target_message(
            int(fix.time * 1000) & 0xFFFFFFFFFFFFFFFF, 3, int(round(fix.lat * 1e7)), int(round(fix.lon * 1e7)),
            float(alt), [fix.vn, fix.ve, fix.vd], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0], 0)]

    # -- ending ----------------------------------------------------------------------------------------------
    def _finish(self, phase: ShotPhase, detail: str, hold: bool = False,
                status: CommandStatus = CommandStatus.ABORTED) -> None:
        """End the shot (lock held): say why, answer a start still waiting, hold if asked, let go of the ROI."""
        shot = self._shot
        shot.phase, shot.detail = phase, detail
        if self._start is not None and not self._start[1].done():
            self._settle(self._start[1], self._start[0], status, detail)
        if hold and self._running:
            if self._mode == "GUIDED":
                self._setpoints.stop(self._clock())        # zero velocity, streamed for 3 s as Stop does
                self._store.set(setpoint=self._setpoints.setpoint)
            else:
                self._commands.mode("GUIDED")             # out of FOLLOW: GUIDED holds at its stopping point
        if self._roi:
            self._roi = False
            self._payload.stop_looking()
        self._running = False
        state = self._store.state
        fields = shot.report(state) if state.home is not None else {}   # the last word is the telemetry's too
        self._set_state(phase=phase, detail=detail, **fields)
        self._store.add_message_locked(Severity.INFO if phase is ShotPhase.DONE else Severity.NOTICE,
                                       f"{shot.kind.value.capitalize()} {phase.value}: {detail}")
        self._store.publish()
        self._outbox.wake()

    # -- helpers -------------------------------------------------------------------------------------------
    def _button(self, name: str, press) -> Future:
        with self._store.lock:
            shot = self._shot
            if shot is None or not shot.phase.active:
                return self._answer(name, CommandStatus.REJECTED, "no shot is running")
            text = press(shot)
            self._set_state(phase=shot.phase, cruise=shot.cruise)
            self._store.publish()
        return self._answer(name, CommandStatus.ACCEPTED, text)

    def _set_state(self, shot: ShotState | None = None, **fields) -> None:
        if shot is None:
            shot = replace(self._store.view()["shot"], **fields)
        self._store.set(shot=shot)

    def _answer(self, name: str, status: CommandStatus, reason: str) -> Future:
        return self._commands.answer(name, status, reason)

    def _settle(self, future: Future, name: str, status: CommandStatus, reason: str) -> None:
        self._settler.settle(future, self._store.record_locked(name, status, reason))
