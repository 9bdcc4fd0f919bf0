"""How long the vehicle takes to answer: one estimate of the link's round trip, and the waits made from it.

A reply is counted only when it answers exactly one request (Karn's rule: never a request sent twice, whose
reply could be to either), and the estimate is RFC 6298's: a smoothed round trip and its variation, the
timeout their sum with four times the variation. A satellite-slow radio and a loopback SITL are both measured,
not guessed: the parts that wait on the vehicle (commands, transfers) read :meth:`RoundTrip.timeout` instead of
keeping estimators of their own.
"""
from __future__ import annotations

__all__ = ["RoundTrip"]

ALPHA = 1 / 8               # RFC 6298's gains
BETA = 1 / 4
K = 4


class RoundTrip:
    """The link's round trip, in seconds. Not thread-safe: its owner's lock guards it."""

    def __init__(self, initial: float = 1.0, floor: float = 0.05, ceiling: float = 10.0) -> None:
        self.initial, self.floor, self.ceiling = initial, floor, ceiling
        self.srtt: float | None = None        # smoothed round trip, None before the first sample
        self.rttvar = initial / 2
        self.samples = 0
        self.lowest: float | None = None      # the quickest answer seen: the link's own delay, queues aside

    def sample(self, seconds: float) -> None:
        """One request answered once, ``seconds`` after it went out."""
        if not 0.0 <= seconds < 60.0:
            return
        self.samples += 1
        self.lowest = seconds if self.lowest is None else min(self.lowest, seconds)
        if self.srtt is None:
            self.srtt, self.rttvar = seconds, seconds / 2
            return
        self.rttvar = (1 - BETA) * self.rttvar + BETA * abs(self.srtt - seconds)
        self.srtt = (1 - ALPHA) * self.srtt + ALPHA * seconds

    @property
    def estimate(self) -> float:
        """The smoothed round trip, or the initial guess before any answer."""
        return self.initial if self.srtt is None else self.srtt

    def timeout(self) -> float:
        """How long a request may stay unanswered before it counts as lost (RFC 6298's RTO)."""
        if self.srtt is None:
            return self.ceiling if self.initial > self.ceiling else max(self.floor, 2 * self.initial)
        return min(self.ceiling, max(self.floor, self.srtt + K * self.rttvar))
