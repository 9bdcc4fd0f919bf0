"""The vehicle's MAVLink 2 signing glue: a key used at once, unsigned frames let in or not, and the SETUP_SIGNING
exchange that gives the vehicle a key (or takes it away), settled when its heartbeats show it.

The signing itself (keys, timestamps, what is accepted) is :mod:`driver.link.signing`; this part holds the
vehicle's side: the checks, the pilot's messages and the results.
"""
from __future__ import annotations

from concurrent.futures import Future

from ..core.ports import Ports
from .state import CommandResult, CommandStatus, Severity

__all__ = ["SigningControl"]

SERVICE_INTERVAL = 0.1       # s between looks at the SETUP_SIGNING exchange


class SigningControl:
    """``Vehicle.use_signing_key``, ``allow_unsigned``, ``setup_signing`` and ``remove_signing`` do their work here;
    ``signing`` is the link's (driver.link.signing), ``peer`` says the MAVLink version the link speaks."""

    def __init__(self, signing, peer, ports: Ports):
        self._signing, self._peer = signing, peer
        self._store, self._lock = ports.state, ports.state.lock
        self._settler, self._outbox, self._answer = ports.settler, ports.outbox, ports.commands.answer
        self._clock, self._replaying = ports.clock, ports.replaying
        self._next_service = -1e9

    def use_key(self, key: bytes | None, allow_unsigned: bool | None = None) -> CommandResult:
        """Sign with ``key`` from now on, or stop (None), without telling the vehicle; ``allow_unsigned`` lets
        the vehicle's unsigned frames in (a vehicle without the key yet)."""
        if key is not None and len(key) != 32:
            return self._store.record("signing key", CommandStatus.REJECTED, "a signing key is 32 bytes")
        with self._lock:
            self._signing.use_key(key, allow_unsigned)
            self._store.set(signing=self._signing.snapshot(self._peer.version))
            result = self._store.record_locked("signing key", CommandStatus.ACCEPTED,
                                               "signing with the new key" if key else "signing off")
        self._outbox.wake()
        return result

    def allow_unsigned(self, on: bool) -> CommandResult:
        """Let the vehicle's unsigned frames in while we sign (a vehicle that has no key yet), or stop."""
        with self._lock:
            self._signing.use_key(self._signing.key, allow_unsigned=on)
            self._store.set(signing=self._signing.snapshot(self._peer.version))
            return self._store.record_locked("signing unsigned", CommandStatus.ACCEPTED,
                                             "the vehicle's unsigned frames are let in" if on else
                                             "the vehicle's unsigned frames are dropped")

    def setup(self, key: bytes) -> Future:
        """Give the vehicle ``key`` with SETUP_SIGNING (in clear: a trusted link only) and sign with it;
        resolves when the vehicle's heartbeats arrive signed with it."""
        if len(key) != 32 or not any(key):
            return self._answer("signing setup", CommandStatus.REJECTED, "a signing key is 32 bytes, not all zero")
        return self._change("signing setup", key)

    def remove(self) -> Future:
        """Tell the vehicle to stop signing (a key of zeros); we stop once its heartbeats arrive unsigned."""
        if self._signing.key is None:
            return self._answer("signing remove", CommandStatus.REJECTED, "no signing key in use")
        return self._change("signing remove", None)

    def _change(self, name: str, key: bytes | None) -> Future:
        s = self._store.state
        problem = ("replaying a recording: no vehicle to command" if self._replaying else
                   "no vehicle connected" if not s.connected else
                   "the vehicle refuses it while armed: disarm first" if s.armed else
                   "the vehicle speaks MAVLink 1, which cannot be signed" if not self._peer.mavlink2 else None)
        if problem:
            return self._answer(name, CommandStatus.REJECTED, problem)
        future: Future = Future()
        with self._lock:
            if key is not None:
                self._store.add_message_locked(Severity.WARNING, "SETUP_SIGNING carries the key in clear: anyone "
                                               "listening on this link learns it (use USB or a cable)")
            self.settle(self._signing.begin(name, key, future, self._clock()))
            self._store.set(signing=self._signing.snapshot(self._peer.version))
            self._store.publish()
        self._outbox.wake()
        return future

    def settle(self, settled) -> None:
        """Record a finished SETUP_SIGNING exchange and settle its future (_lock held)."""
        if settled is not None:
            future, name, status, reason = settled
            self._store.set(signing=self._signing.snapshot(self._peer.version))
            self._settler.settle(future, self._store.record_locked(name, status, reason))

    # -- the driver's threads (lock held) ----------------------------------------------------------------------
    def on_heartbeat(self, m) -> None:
        """The autopilot's heartbeat: signed with the new key (or unsigned) ends a SETUP_SIGNING exchange."""
        self.settle(self._signing.heartbeat(m))

    def on_text(self, text: str) -> None:
        self.settle(self._signing.statustext(text))

    def service(self, now: float, state) -> list:
        """Every 100 ms: SETUP_SIGNING sent again while the vehicle's heartbeats do not show it."""
        if now < self._next_service:
            return []
        self._next_service = now + SERVICE_INTERVAL
        frames, settled = self._signing.service(now, self._peer.target(), self._outbox.encoder)
        self.settle(settled)
        return frames
