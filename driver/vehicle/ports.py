"""The vehicle's side of the ports (:mod:`driver.core.ports`): the few services each part is handed.

Each adapter is a thin view of one thing the :class:`~driver.vehicle.vehicle.Vehicle` owns (its ticker, its
command path), so a part never holds the vehicle itself and never reaches its private fields.
"""
from __future__ import annotations

from concurrent.futures import Future

from ..core.ports import Ports

__all__ = ["LinkOutbox", "SequencePilot", "vehicle_ports"]


class LinkOutbox:
    """:class:`~driver.core.ports.Outbox` over the vehicle's ticker and the peer it talks to."""

    def __init__(self, ticker, wake, peer) -> None:
        self._ticker, self._wake, self._peer = ticker, wake, peer

    def post(self, msg) -> None:
        self._ticker.post(msg)

    def wake(self) -> None:
        self._wake.set()

    def tick_within(self, seconds: float) -> None:
        self._ticker.tick_within(seconds)

    def target(self) -> tuple[int, int]:
        return self._peer.target()

    def encoder(self):
        return self._ticker.new_encoder()

    @property
    def mavlink2(self) -> bool:
        return self._peer.mavlink2


def vehicle_ports(*, clock, store, ticker, wake, peer, commands, settler, firmware, roundtrip, replaying) -> Ports:
    return Ports(clock, store, LinkOutbox(ticker, wake, peer), commands, settler, firmware, roundtrip, replaying)


class SequencePilot:
    """:class:`~driver.vehicle.sequences.machine.Pilot` over the vehicle: what a takeoff, a mission start, a Land or
    a Stop may do, each through the one command path and its flight rules."""

    def __init__(self, *, state, airborne, mode, arm, disarm, long, retry_interval, hold, quiet) -> None:
        self.state, self.may_be_airborne, self.retry_interval = state, airborne, retry_interval
        self._mode, self._arm, self._disarm, self._long = mode, arm, disarm, long
        self.hold, self.quiet = hold, quiet

    def mode(self, name: str, *, early: bool = False) -> Future:
        return self._mode(name, early=early)

    def arm(self, *, early: bool = False) -> Future:
        return self._arm(early=early)

    def disarm(self) -> Future:
        return self._disarm()

    def long(self, command: int, params=(), name: str | None = None, *, retry: float | None = None,
             shows_mode: str | None = None) -> Future:
        return self._long(command, params, name, retry=retry, shows_mode=shows_mode)
