"""The velocity setpoint: clamped to the pilot's limits, streamed, and zero when the pilot stops.

A stick released, Stop, or a stalled command stream (the deadman) all mean hover. Hover is not silence:
after a zero, the streamer keeps sending zeros at the setpoint rate for :data:`ZERO_HOLD` seconds
(ArduCopter's own GUIDED timeout), as MAVSDK's offboard does, so that a burst of radio loss that swallows
the first zeros cannot leave the last velocity flying until the vehicle's timeout. A go-to silences the
stream at once: a velocity setpoint would override the position target.
"""
from __future__ import annotations

import logging

from ..core import frames
from .api import Limits
from .state import Setpoint

log = logging.getLogger(__name__)

__all__ = ["SetpointStreamer", "ZERO_HOLD"]

ZERO_HOLD = 3.0          # s of zeros after a stop or the deadman (ArduCopter GUID_TIMEOUT)


class SetpointStreamer:
    """What velocity to stream and when; the caller (the driver's ticker) sends it. Not thread-safe: the
    driver calls it with its state lock held."""

    def __init__(self, deadman: float, rate: float):
        self.deadman = deadman
        self.interval = 1.0 / rate
        self.setpoint = Setpoint()
        self._demand_time = 0.0           # last pilot demand (deadman clock)
        self._sent_at = -1e9
        self._dirty = False               # changed since last sent: send now, not at the next interval
        self._zero_until = 0.0            # keep streaming zeros until then

    @staticmethod
    def clamp(forward: float, right: float, up: float, yaw_rate: float, limits: Limits) -> Setpoint | None:
        """The setpoint within ``limits``, or None when a value is not a finite number."""
        if not frames.finite(forward, right, up, yaw_rate):
            return None
        return Setpoint(frames.clamp(float(forward), limits.horizontal), frames.clamp(float(right), limits.horizontal),
                        frames.clamp(float(up), limits.vertical), frames.clamp(float(yaw_rate), limits.yaw_rate))

    def demand(self, sp: Setpoint, now: float) -> bool:
        """The pilot's newest demand; True when it changed the setpoint."""
        self._demand_time = now
        if sp == self.setpoint:
            return False
        self._set(sp, now)
        return True

    def stop(self, now: float) -> None:
        """Hover: zero now, and zeros for ZERO_HOLD seconds."""
        self._set(Setpoint(), now)

    def silence(self) -> None:
        """Stream nothing (a go-to is flying the vehicle)."""
        self.setpoint = Setpoint()
        self._zero_until = 0.0
        self._dirty = False

    def _set(self, sp: Setpoint, now: float) -> None:
        if sp.is_zero:
            self._zero_until = now + ZERO_HOLD
        self.setpoint = sp
        self._dirty = True

    @property
    def streaming(self) -> bool:
        return not self.setpoint.is_zero or self._dirty or self._zero_until > 0.0

    def tick(self, now: float) -> tuple[Setpoint | None, bool]:
        """(the setpoint to send now or None, whether the deadman just zeroed it)."""
        fired = False
        if not self.setpoint.is_zero and now - self._demand_time > self.deadman:
            self._set(Setpoint(), now)
            fired = True
            log.warning("velocity commands stopped for %.1f s: hovering", self.deadman)
        if self.setpoint.is_zero and now >= self._zero_until:
            self._zero_until = 0.0
            self._dirty = False
            return None, fired
        if not self._dirty and now - self._sent_at < self.interval - 0.002:
            return None, fired
        self._sent_at = now
        self._dirty = False
        return self.setpoint, fired
