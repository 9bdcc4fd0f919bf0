"""The smart shots over Ice: ``mavlinkserver.Shots`` served (:class:`ShotsI`) and called (:class:`ShotsClient`).

The client is the :class:`~driver.shots.api.Shots` an :class:`~driver.ice.client.IceDrone` offers as
``drone.shots``, so the viewer flies shots the same way embedded or remote. An Ice client is a program on the
network: it may not make the server open a port or a device, so over Ice the follow target's fixes are given
(``followPosition``): a follow from a GPS stream opens that stream here, on the client's machine (the pilot's
laptop), and sends its fixes on. Every other rule is the driver's own, on the server.
"""
from __future__ import annotations

import logging
import math
import threading
from concurrent.futures import Future, ThreadPoolExecutor

import Ice

from ..core.frames import finite
from ..core.results import CommandResult, CommandStatus, answered
from ..shots.api import Shots
from ..shots.model import Keyframe, Look, ShotKind, ShotPhase, ShotState
from ..shots.targets import TargetSource, open_target
from . import load_slice
from .servants import Answering

jderobot, mavlinkserver = load_slice()
log = logging.getLogger(__name__)

__all__ = ["ShotsI", "ShotsClient", "shot_to_ice", "shot_from_ice"]

_KINDS = {k.value: k for k in ShotKind}
_PHASES = {p.value: p for p in ShotPhase}
FORWARD_EVERY = 0.1          # s between looks at a local GPS stream for new fixes to send


def _opt(value) -> tuple[bool, float]:
    return (value is not None and math.isfinite(value)), float(value) if value is not None else 0.0


def shot_to_ice(ms, s: ShotState):
    fields = {}
    for name, ice in (("progress", "Progress"), ("speed", "Speed"), ("radius", "Radius"),
                      ("radius_wanted", "RadiusWanted"), ("angle", "Angle"), ("aim_error", "AimError"),
                      ("target_distance", "TargetDistance"), ("target_age", "TargetAge")):
        has, value = _opt(getattr(s, name))
        fields[f"has{ice}"], fields[ice[0].lower() + ice[1:]] = has, value
    c = s.centre
    return ms.ShotStatus(
        kind=s.kind.value, phase=s.phase.value, detail=s.detail, engine=s.engine,
        keyframes=[ms.ShotKeyframe(k.lat, k.lon, k.alt, k.pitch, k.yaw) for k in s.keyframes],
        path=[ms.ShotPoint(*p) for p in s.path], looks=[ms.ShotLook(k.lat, k.lon, k.yaw, k.pitch) for k in s.looks],
        hasCentre=c is not None, centreLat=c[0] if c else 0.0, centreLon=c[1] if c else 0.0,
        centreAlt=c[2] if c else 0.0, photos=s.photos, photosTotal=s.photos_total, cruise=s.cruise, **fields)


def shot_from_ice(p) -> ShotState:
    """The driver's value of a ``ShotStatus``; a number that is not finite counts as not measured."""
    def known(has: bool, value: float):
        return float(value) if has and math.isfinite(value) else None
    keys = tuple(k for k in (Keyframe(x.lat, x.lon, x.alt, x.pitch, x.yaw) for x in p.keyframes) if k.finite())
    centre = (p.centreLat, p.centreLon, p.centreAlt) if p.hasCentre and finite(p.centreLat, p.centreLon,
                                                                                p.centreAlt) else None
    return ShotState(
        _KINDS.get(p.kind, ShotKind.NONE), _PHASES.get(p.phase, ShotPhase.IDLE), p.detail, p.engine, keys,
        tuple((x.lat, x.lon, x.alt) for x in p.path if finite(x.lat, x.lon, x.alt)),
        tuple(Look(x.lat, x.lon, x.yaw, x.pitch) for x in p.looks if finite(x.lat, x.lon, x.yaw, x.pitch)),
        progress=known(p.hasProgress, p.progress), speed=known(p.hasSpeed, p.speed), centre=centre,
        radius=known(p.hasRadius, p.radius), radius_wanted=known(p.hasRadiusWanted, p.radiusWanted),
        angle=known(p.hasAngle, p.angle), aim_error=known(p.hasAimError, p.aimError),
        target_distance=known(p.hasTargetDistance, p.targetDistance), target_age=known(p.hasTargetAge, p.targetAge),
        photos=max(0, int(p.photos)), photos_total=max(0, int(p.photosTotal)),
        cruise=float(p.cruise) if math.isfinite(p.cruise) else 0.0)


class ShotsI(Answering, mavlinkserver.Shots):
    """The server's side: each operation is the driver's ``drone.shots`` call, answered when it answers."""

    def __init__(self, vehicle) -> None:
        super().__init__()
        self._vehicle = vehicle

    @property
    def _shots(self) -> Shots:
        return self._vehicle.shots

    def getState(self, current=None):
        return shot_to_ice(mavlinkserver, self._vehicle.state().shot)

    def orbit(self, hasCentre, lat, lon, alt, hasRadius, radius, speed, roi, current=None):
        return self._answer("orbit", lambda: self._shots.orbit(lat if hasCentre else None, lon if hasCentre else None,
                                                               alt, radius if hasRadius else None, speed, bool(roi)))

    def cable(self, speed, attach, current=None):
        return self._answer("cable", lambda: self._shots.cable(speed, attach if attach >= 0 else None))

    def selfie(self, distance, rise, speed, hasPilot, lat, lon, current=None):
        return self._answer("selfie", lambda: self._shots.selfie(distance, rise, speed,
                                                                 (lat, lon) if hasPilot else None))

    def follow(self, engine, current=None):
        return self._answer("follow", lambda: self._shots.follow("given", engine))

    def followPosition(self, lat, lon, hasAlt, alt, hasVelocity, vn, ve, vd, current=None):
        return self._shots.follow_position(lat, lon, alt if hasAlt else None, vn if hasVelocity else None,
                                           ve if hasVelocity else None, vd if hasVelocity else 0.0)

    def pano(self, shape, fov, lens, pitch, current=None):
        return self._answer("pano", lambda: self._shots.pano(shape, fov, lens, pitch))

    def sticks(self, forward, right, up, yaw, current=None):
        return self._shots.sticks(forward, right, up, yaw)

    def pause(self, current=None):
        return self._answer("shot pause", self._shots.pause)

    def resume(self, current=None):
        return self._answer("shot resume", self._shots.resume)

    def reverse(self, current=None):
        return self._answer("shot reverse", self._shots.reverse)

    def setCruise(self, speed, current=None):
        return self._answer("shot speed", lambda: self._shots.set_cruise(speed))

    def stop(self, current=None):
        return self._answer("shot stop", self._shots.stop)

    def recordKeyframe(self, current=None):
        return self._answer("record keyframe", self._shots.record_keyframe)

    def setKeyframes(self, keyframes, current=None):
        keys = tuple(Keyframe(k.lat, k.lon, k.alt, k.pitch, k.yaw) for k in keyframes)
        return self._answer("keyframes", lambda: self._shots.set_keyframes(keys))


class ShotsClient(Shots):
    """The client's side, on a ``mavlinkserver.Shots`` proxy (None: the server serves no shots). Calls run on a
    thread of their own, never the caller's; the state is read by the drone's poller (:meth:`poll`)."""

    def __init__(self, proxy, call_ms: int, command_ms: int, result) -> None:
        self._state = ShotState()
        self._result = result                   # the drone's numbering of a server's CommandOutcome
        self._missing = proxy is None
        self._reader = mavlinkserver.ShotsPrx.uncheckedCast(proxy.ice_invocationTimeout(call_ms)) if proxy else None
        self._commands = (mavlinkserver.ShotsPrx.uncheckedCast(proxy.ice_invocationTimeout(command_ms))
                          if proxy else None)
        self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="ice-shots")
        self._sticks_pending: tuple | None = None
        self._sticks_lock = threading.Lock()
        self._local: TargetSource | None = None
        self._forwarding = threading.Event()
        if proxy is None:
            self.unavailable = "this MAVLinkServer serves no smart shots"

    @property
    def state(self) -> ShotState:
        return self._state

    def poll(self) -> None:
        """Shots.getState, with the drone's poll (an older server has none: asked once)."""
        if self._missing:
            return
        try:
            self._state = shot_from_ice(self._reader.getState())
        except Ice.OperationNotExistException:
            self._missing = True
            self.unavailable = "this MAVLinkServer serves no smart shots (an older version)"

    def _call(self, name: str, start) -> Future:
        if self._missing:
            return self._no(name)
        future: Future = Future()

        def done(ice_future) -> None:
            try:
                future.set_result(self._result(ice_future.result()))
            except Exception as exc:            # noqa: BLE001 - an Ice failure is the answer
                status = CommandStatus.TIMED_OUT if isinstance(exc, Ice.TimeoutException) else CommandStatus.REJECTED
                future.set_result(CommandResult(name, status, f"server unreachable: {type(exc).__name__}"))

        def run() -> None:
            try:
                start(self._commands).add_done_callback(done)
            except Exception as exc:            # noqa: BLE001
                future.set_result(CommandResult(name, CommandStatus.REJECTED, f"server unreachable: {exc}"))
        try:
            self._worker.submit(run)
        except RuntimeError as exc:             # closed
            future.set_result(CommandResult(name, CommandStatus.REJECTED, f"closed: {exc}"))
        return future

    def orbit(self, lat=None, lon=None, alt=0.0, radius=None, speed=0.0, roi=False) -> Future:
        if not finite(alt, speed) or (lat is not None and not finite(lat, lon)) or (radius is not None
                                                                                    and not finite(radius)):
            return answered(CommandResult("orbit", CommandStatus.REJECTED, "not finite numbers"))
        return self._call("orbit", lambda p: p.orbitAsync(lat is not None, lat or 0.0, lon or 0.0, alt,
                                                          radius is not None, radius or 0.0, speed, bool(roi)))

    def cable(self, speed=0.0, attach=None) -> Future:
        return self._call("cable", lambda p: p.cableAsync(float(speed), -1 if attach is None else int(attach)))

    def selfie(self, distance=30.0, rise=15.0, speed=3.0, pilot=None) -> Future:
        return self._call("selfie", lambda p: p.selfieAsync(distance, rise, speed, pilot is not None,
                                                            *(pilot or (0.0, 0.0))))

    def follow(self, source="given", engine="auto") -> Future:
        if source not in ("", "given", "api", "ice"):
            try:
                self._forward_from(source)
            except (ValueError, OSError) as exc:
                return answered(CommandResult("follow", CommandStatus.REJECTED, str(exc)))
            if self._local.latest() is None:
                return answered(CommandResult("follow", CommandStatus.REJECTED,
                                              f"no fix of the target yet from {source} (open here now): ask again "
                                              "once it sends"))
        return self._call("follow", lambda p: p.followAsync(engine))

    def _forward_from(self, source: str) -> None:
        """Open ``source`` here (the pilot's GPS) and send each new fix to the server."""
        if self._local is not None and self._local.name == source:
            return
        if self._local is not None:
            self._forwarding.set()
            self._local.close()
        self._local = local = open_target(source)
        self._forwarding = stop = threading.Event()

        def forward() -> None:
            sent = None
            while not stop.wait(FORWARD_EVERY):
                fix = local.latest()
                if fix is not None and fix.time != sent:
                    sent = fix.time
                    self.follow_position(fix.lat, fix.lon, fix.alt, fix.vn if fix.has_velocity else None,
                                         fix.ve if fix.has_velocity else None, fix.vd)
        threading.Thread(target=forward, name="ice-target", daemon=True).start()

    def follow_position(self, lat, lon, alt=None, vn=None, ve=None, vd=0.0) -> bool:
        if self._missing or not finite(lat, lon):
            return False
        has_v = vn is not None and ve is not None and finite(vn, ve, vd)
        try:
            self._reader.followPositionAsync(lat, lon, alt is not None, alt or 0.0, has_v, vn or 0.0, ve or 0.0,
                                             vd or 0.0)
        except Ice.Exception:
            return False
        return True

    def pano(self, shape="cylinder", fov=360.0, lens=74.0, pitch=0.0) -> Future:
        return self._call("pano", lambda p: p.panoAsync(shape, fov, lens, pitch))

    def sticks(self, forward, right, up, yaw) -> bool:
        """The newest sticks only: one call in flight at a time, later ones replace those waiting."""
        if self._missing or not finite(forward, right, up, yaw) or not self._state.active:
            return False
        with self._sticks_lock:
            idle = self._sticks_pending is None
            self._sticks_pending = (float(forward), float(right), float(up), float(yaw))
        if idle:
            self._worker.submit(self._send_sticks)
        return True

    def _send_sticks(self) -> None:
        with self._sticks_lock:
            sticks, self._sticks_pending = self._sticks_pending, None
        if sticks is not None:
            try:
                self._reader.sticks(*sticks)
            except Ice.Exception as exc:
                log.debug("sticks not sent: %s", exc)

    def pause(self) -> Future:
        return self._call("shot pause", lambda p: p.pauseAsync())

    def resume(self) -> Future:
        return self._call("shot resume", lambda p: p.resumeAsync())

    def reverse(self) -> Future:
        return self._call("shot reverse", lambda p: p.reverseAsync())

    def set_cruise(self, speed) -> Future:
        return self._call("shot speed", lambda p: p.setCruiseAsync(float(speed)))

    def stop(self) -> Future:
        return self._call("shot stop", lambda p: p.stopAsync())

    def record_keyframe(self) -> Future:
        return self._call("record keyframe", lambda p: p.recordKeyframeAsync())

    def set_keyframes(self, keyframes) -> Future:
        keys = [mavlinkserver.ShotKeyframe(k.lat, k.lon, k.alt, k.pitch, k.yaw) for k in keyframes]
        return self._call("keyframes", lambda p: p.setKeyframesAsync(keys))

    def keyframes(self):
        return self._state.keyframes

    def close(self) -> None:
        self._forwarding.set()
        if self._local is not None:
            self._local.close()
        self._worker.shutdown(wait=False, cancel_futures=True)

