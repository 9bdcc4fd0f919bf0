"""The vehicle's MAVLink 2 signing glue: a key used at once, unsigned frames let in or not, and the SETUP_SIGNING
exchange that gives the vehicle a key (or takes it away), settled when its heartbeats show it.

The signing itself (keys, timestamps, what is accepted) is :mod:`driver.link.signing`; this part holds the
vehicle's side: the checks, the pilot's messages and the results.
"""
from __future__ import annotations

from concurrent.futures import Future

from .state import CommandResult, CommandStatus, Severity

__all__ = ["SigningControl"]


class SigningControl:
    """``Vehicle.use_signing_key``, ``allow_unsigned``, ``setup_signing`` and ``remove_signing`` do their work here."""

    def __init__(self, vehicle):
        self._v = vehicle
        self._signing, self._store, self._lock = vehicle._signing, vehicle._store, vehicle._lock
        self._notifier, self._wake = vehicle._notifier, vehicle._wake

    def use_key(self, key: bytes | None, allow_unsigned: bool | None = None) -> CommandResult:
        """Sign with ``key`` from now on, or stop (None), without telling the vehicle; ``allow_unsigned`` lets
        the vehicle's unsigned frames in (a vehicle without the key yet)."""
        if key is not None and len(key) != 32:
            return self._store.record("signing key", CommandStatus.REJECTED, "a signing key is 32 bytes")
        with self._lock:
            self._signing.use_key(key, allow_unsigned)
            self._store.set(signing=self._signing.snapshot(self._v._version))
            result = self._store.record_locked("signing key", CommandStatus.ACCEPTED,
                                               "signing with the new key" if key else "signing off")
        self._wake.set()
        return result

    def allow_unsigned(self, on: bool) -> CommandResult:
        """Let the vehicle's unsigned frames in while we sign (a vehicle that has no key yet), or stop."""
        with self._lock:
            self._signing.use_key(self._signing.key, allow_unsigned=on)
            self._store.set(signing=self._signing.snapshot(self._v._version))
            return self._store.record_locked("signing unsigned", CommandStatus.ACCEPTED,
                                             "the vehicle's unsigned frames are let in" if on else
                                             "the vehicle's unsigned frames are dropped")

    def setup(self, key: bytes) -> Future:
        """Give the vehicle ``key`` with SETUP_SIGNING (in clear: a trusted link only) and sign with it;
        resolves when the vehicle's heartbeats arrive signed with it."""
        if len(key) != 32 or not any(key):
            return self._v._finish("signing setup", CommandStatus.REJECTED, "a signing key is 32 bytes, not all zero")
        return self._change("signing setup", key)

    def remove(self) -> Future:
        """Tell the vehicle to stop signing (a key of zeros); we stop once its heartbeats arrive unsigned."""
        if self._signing.key is None:
            return self._v._finish("signing remove", CommandStatus.REJECTED, "no signing key in use")
        return self._change("signing remove", None)

    def _change(self, name: str, key: bytes | None) -> Future:
        s = self._v.state()
        problem = ("replaying a recording: no vehicle to command" if self._v._replay is not None else
                   "no vehicle connected" if not s.connected else
                   "the vehicle refuses it while armed: disarm first" if s.armed else
                   "the vehicle speaks MAVLink 1, which cannot be signed" if not self._v._v2 else None)
        if problem:
            return self._v._finish(name, CommandStatus.REJECTED, problem)
        future: Future = Future()
        with self._lock:
            if key is not None:
                self._store.add_message_locked(Severity.WARNING, "SETUP_SIGNING carries the key in clear: anyone "
                                               "listening on this link learns it (use USB or a cable)")
            self.settle(self._signing.begin(name, key, future, self._v.clock()))
            self._store.set(signing=self._signing.snapshot(self._v._version))
            self._store.publish()
        self._wake.set()
        return future

    def settle(self, settled) -> None:
        """Record a finished SETUP_SIGNING exchange and settle its future (_lock held)."""
        if settled is not None:
            future, name, status, reason = settled
            self._store.set(signing=self._signing.snapshot(self._v._version))
            self._notifier.settle(future, self._store.record_locked(name, status, reason))
