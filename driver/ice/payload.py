"""The camera on the vehicle over Ice: ``mavlinkserver.Payload`` both ways, the Vehicle servant's
payload operations and the client's (mixins for :class:`~driver.ice.servants.VehicleI` and
:class:`~driver.ice.client.IceDrone`)."""
from __future__ import annotations

import math
from concurrent.futures import Future

import Ice

from ..core.frames import finite
from ..payload.model import CameraKind, Gimbal, GimbalControl, VehicleCamera
from ..vehicle.state import CommandStatus, VehicleState

__all__ = ["payload_to_ice", "payload_from_ice", "PayloadServant", "PayloadClient"]

_CONTROLS = {c.name: c for c in GimbalControl}
_KINDS = {k.value: k for k in CameraKind}


def payload_to_ice(ms, s: VehicleState):
    g, c = s.gimbal, s.camera
    return ms.Payload(hasPitch=g.pitch_deg is not None, pitchDeg=g.pitch_deg or 0.0,
                      hasYaw=g.yaw_deg is not None, yawDeg=g.yaw_deg or 0.0, yawEarth=g.yaw_earth,
                      hasRetracted=g.retracted is not None, retracted=bool(g.retracted), control=g.control.name,
                      protocol=g.protocol, hasRoi=g.roi is not None,
                      roiLat=g.roi[0] if g.roi else 0.0, roiLon=g.roi[1] if g.roi else 0.0,
                      roiAlt=g.roi[2] if g.roi else 0.0, cameraKind=c.kind.value, cameraName=c.name,
                      photos=int(c.photos), hasRecording=c.recording is not None, recording=bool(c.recording))


def payload_from_ice(p) -> tuple[Gimbal, VehicleCamera]:
    """The driver's values of a ``mavlinkserver.Payload``; a number that is not finite counts as not told."""
    def known(has: bool, value: float):
        return float(value) if has and math.isfinite(value) else None
    roi = (p.roiLat, p.roiLon, p.roiAlt) if p.hasRoi and finite(p.roiLat, p.roiLon, p.roiAlt) else None
    gimbal = Gimbal(pitch_deg=known(p.hasPitch, p.pitchDeg), yaw_deg=known(p.hasYaw, p.yawDeg),
                    yaw_earth=bool(p.yawEarth), retracted=bool(p.retracted) if p.hasRetracted else None,
                    control=_CONTROLS.get(p.control, GimbalControl.UNKNOWN), protocol=p.protocol, roi=roi,
                    source="Ice")
    camera = VehicleCamera(kind=_KINDS.get(p.cameraKind, CameraKind.UNKNOWN), name=p.cameraName,
                           photos=max(0, int(p.photos)), recording=bool(p.recording) if p.hasRecording else None)
    return gimbal, camera


class PayloadServant:
    """``mavlinkserver.Vehicle``'s payload operations; ``self._vehicle``, ``_answer``, ``_rejected`` are VehicleI's."""

    def getPayload(self, current=None):
        from . import load_slice
        return payload_to_ice(load_slice()[1], self._vehicle.state())

    def pointGimbal(self, pitchDeg, hasYaw, yawDeg, current=None):
        if not finite(pitchDeg) or (hasYaw and not finite(yawDeg)):
            return self._rejected("gimbal", "non-finite angle")
        return self._answer("gimbal", lambda: self._vehicle.point_gimbal(pitchDeg, yawDeg if hasYaw else None))

    def gimbalRate(self, pitchDegS, yawDegS, current=None):
        if not finite(pitchDegS, yawDegS):
            return self._rejected("gimbal rate", "non-finite rate")
        return self._answer("gimbal rate", lambda: self._vehicle.gimbal_rate(pitchDegS, yawDegS))

    def lookAt(self, lat, lon, alt, current=None):
        if not finite(lat, lon, alt):
            return self._rejected("look at", "non-finite position")
        return self._answer("look at", lambda: self._vehicle.look_at(lat, lon, alt))

    def stopLooking(self, current=None):
        return self._answer("stop looking", self._vehicle.stop_looking)

    def takePhoto(self, current=None):
        return self._answer("photo", self._vehicle.take_photo)

    def recordVideo(self, on, current=None):
        return self._answer(f"record {'on' if on else 'off'}", lambda: self._vehicle.record_video(bool(on)))


class PayloadClient:
    """:class:`~driver.vehicle.api.Drone`'s payload calls on a MAVLinkServer (``self._vehicle``: its Vehicle proxy)."""

    _payload_missing = False

    def _payload_call(self, name: str, start) -> Future:
        if self._vehicle is None:
            return self._no_extension(name)
        if self._payload_missing:
            return self._local_result(name, CommandStatus.REJECTED, "this MAVLinkServer has no camera control "
                                                                    "(an older version)")
        return self._command(name, start)

    def point_gimbal(self, pitch_deg: float, yaw_deg: float | None = None) -> Future:
        if not finite(pitch_deg) or (yaw_deg is not None and not finite(yaw_deg)):
            return self._local_result("gimbal", CommandStatus.REJECTED, "angle is not a finite number")
        return self._payload_call("gimbal", lambda p: p.pointGimbalAsync(
            float(pitch_deg), yaw_deg is not None, float(yaw_deg or 0.0)))

    def gimbal_rate(self, pitch_deg_s: float, yaw_deg_s: float = 0.0) -> Future:
        if not finite(pitch_deg_s, yaw_deg_s):
            return self._local_result("gimbal rate", CommandStatus.REJECTED, "rate is not a finite number")
        return self._payload_call("gimbal rate", lambda p: p.gimbalRateAsync(float(pitch_deg_s), float(yaw_deg_s)))

    def look_at(self, lat: float, lon: float, alt: float = 0.0) -> Future:
        if not finite(lat, lon, alt):
            return self._local_result("look at", CommandStatus.REJECTED, "not a place on Earth")
        return self._payload_call("look at", lambda p: p.lookAtAsync(float(lat), float(lon), float(alt)))

    def stop_looking(self) -> Future:
        return self._payload_call("stop looking", lambda p: p.stopLookingAsync())

    def take_photo(self) -> Future:
        return self._payload_call("photo", lambda p: p.takePhotoAsync())

    def record_video(self, on: bool) -> Future:
        return self._payload_call(f"record {'on' if on else 'off'}", lambda p: p.recordVideoAsync(bool(on)))

    def _read_payload(self) -> None:
        """Vehicle.getPayload with each poll (an older server has none: asked once)."""
        if self._payload_missing or self._vehicle is None:
            return
        try:
            self._payload = payload_from_ice(self._vehicle.getPayload())
        except Ice.OperationNotExistException:
            self._payload_missing = True

    def on_payload(self, p) -> None:
        """The payload published on the vehicle's IceStorm topic (an Ice dispatch thread)."""
        self._payload = payload_from_ice(p)
