"""How long the vehicle takes to answer: one estimate of the link's round trip, and the waits made from it.

A reply is counted only when it answers exactly one request (Karn's rule: never a request sent twice, whose
reply could be to either), and the estimate is RFC 6298's: a smoothed round trip and its variation, the
timeout their sum with four times the variation. A command that goes unanswered for a whole timeout doubles the
timeouts after it until an answer times the link again (RFC 6298 5.5, Karn's backoff): a link that slows down
all at once (a radio's latency jumping) is waited for instead of being asked faster than it can answer, which
would leave no request answered once to measure it by, and a command would give up on answers still on their way.
A transfer's lost request does not back off: on a radio a loss is chance, not a slower link, and the transfer's
next request answered once times the link again (measured: backing off there made a mission upload at 30 % loss
twice as slow).

A satellite-slow radio and a loopback SITL are both measured, not guessed: every part that waits on the vehicle
(commands, the mission transfer, the parameter download, MAVLink FTP) feeds one estimate per vehicle with the
answers that can only be to one request of its own, and reads :meth:`RoundTrip.timeout` instead of keeping an
estimator of its own; a part may bound the timeout by its protocol's own limits (the vehicle's own re-ask time).
The link supervisor's first requests (AUTOPILOT_VERSION, the parameters it reads by name) time the link as it
connects, so the first transfer does not wait on the first guess.
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
        self.backoff = 1                      # timeouts doubled since the last answer that timed the link
        self._backed_off_until = -1e18        # one doubling per timeout: requests out together expire together

    def sample(self, seconds: float) -> None:
        """One request answered once, ``seconds`` after it went out (an answer in no time was on its way before the
        request, whatever the clock says: not a round trip)."""
        if not 0.0 < seconds < 60.0:
            return
        self.samples += 1
        self.backoff = 1
        self.lowest = seconds if self.lowest is None else min(self.lowest, seconds)
        if self.srtt is None:
            self.srtt, self.rttvar = seconds, seconds / 2
            return
        self.rttvar = (1 - BETA) * self.rttvar + BETA * abs(self.srtt - seconds)
        self.srtt = (1 - ALPHA) * self.srtt + ALPHA * seconds

    @property
    def measured(self) -> bool:
        """An answer has timed the link (else :attr:`estimate` is the first guess)."""
        return self.srtt is not None

    @property
    def estimate(self) -> float:
        """The smoothed round trip, or the initial guess before any answer."""
        return self.initial if self.srtt is None else self.srtt

    def expired(self, now: float) -> None:
        """A command went unanswered for a whole :meth:`timeout` and goes again: the waits double (up to the
        ceiling) until an answer to a request sent once times the link again. Once per timeout, however many
        were out: they were lost together, or the link slowed for them all."""
        if now < self._backed_off_until:
            return
        if self.timeout() < self.ceiling:
            self.backoff *= 2
        self._backed_off_until = now + self.timeout()

    def timeout(self) -> float:
        """How long a request may stay unanswered before it counts as lost (RFC 6298's RTO, backed off)."""
        if self.srtt is None:
            rto = self.ceiling if self.initial > self.ceiling else max(self.floor, 2 * self.initial)
        else:
            rto = max(self.floor, self.srtt + K * self.rttvar)
        return min(self.ceiling, rto * self.backoff)
