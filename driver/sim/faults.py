"""Faults a test switches on and off while the simulated vehicle runs.

Plain attributes, read by the sim's threads on every use, so setting one takes
effect at once without locking (each is a single reference swap). Values are
checked when set: a share outside 0..1 or a negative time is a ValueError at
the line that set it, never a silently odd link.

Directions are seen from the ground station: ``uplink`` is what a ground station
sends to the vehicle (faults act before the autopilot sees a message),
``downlink`` what the vehicle says (faults act on each peer's frames). Times are
REAL seconds, whatever the sim's speed-up, because a ground station's timeouts
run on real time.
"""
from __future__ import annotations

import math
import random
import time
from collections import deque
from dataclasses import dataclass, fields
from typing import Callable

__all__ = ["Faults", "LinkFaults", "LinkCounters", "Counters"]

_SHARES = ("loss", "burst_rate", "duplicate", "reorder")
_SECONDS = ("burst_seconds", "latency", "jitter")


def _share(name: str, value) -> float:
    value = float(value)
    if not 0.0 <= value <= 1.0:            # NaN fails too
        raise ValueError(f"{name} must be a share from 0 to 1, got {value!r}")
    return value


def _seconds(name: str, value) -> float:
    value = float(value)
    if not (value >= 0.0 and math.isfinite(value)):
        raise ValueError(f"{name} must be zero or a positive number of seconds, got {value!r}")
    return value


@dataclass
class LinkFaults:
    """What one direction of the radio does to each frame (per peer: every ground station has its own link)."""
    loss: float = 0.0               # share of frames lost, each on its own
    burst_rate: float = 0.0         # chance per frame that a burst starts; every frame in a burst is lost
    burst_seconds: float = 0.0      # real seconds a burst lasts
    duplicate: float = 0.0          # share of frames delivered twice (a radio's retry)
    latency: float = 0.0            # real seconds every frame is held
    jitter: float = 0.0             # real seconds: latency varies by up to this much either way (order is kept)
    reorder: float = 0.0            # share of frames held back and delivered behind the next one

    def __setattr__(self, name, value) -> None:
        if name in _SHARES:
            value = _share(name, value)
        elif name in _SECONDS:
            value = _seconds(name, value)
        super().__setattr__(name, value)

    @property
    def active(self) -> bool:
        return any(getattr(self, f.name) for f in fields(self))


@dataclass
class LinkCounters:
    """What the faults did to one direction, summed over peers (for tests and bench/fault_matrix.py)."""
    frames: int = 0                 # frames offered to the link
    delivered: int = 0              # frames (copies included) handed on
    lost: int = 0                   # lost on their own (``loss``; downlink also ``drop_fraction``)
    burst_lost: int = 0             # lost inside a burst
    bursts: int = 0                 # bursts started
    outage_lost: int = 0            # lost because the link was down (``link_down``, ``outage()``)
    duplicated: int = 0             # extra copies
    delayed: int = 0                # held for latency/jitter
    reordered: int = 0              # held back behind a later frame
    corrupted: int = 0              # downlink only: a flipped bit (``corrupt_fraction``)


@dataclass
class Counters:
    uplink: LinkCounters
    downlink: LinkCounters


class Faults:
    """Every fault of the simulated vehicle and its link; all off by default.

    * ``link_down``: send nothing and ignore everything received (the TCP connection stays open).
    * ``outage(seconds)``: the same for that many real seconds, then back by itself.
    * ``heartbeats``: False stops the autopilot's HEARTBEAT (other components keep theirs).
    * ``drop_fraction``: downlink share lost (the older name; applied as well as ``downlink.loss``);
      sequence numbers still advance, so a peer sees the gap.
    * ``corrupt_fraction``: downlink share of frames with one flipped bit (bad CRC).
    * ``uplink`` / ``downlink``: :class:`LinkFaults` (loss, bursts, duplicates, latency, jitter, reordering).
    * ``ignore_commands``: MAV_CMD ids never answered nor acted on (True: all); each one lands in ``ignored``.
    * ``lose_replies``: the vehicle ACTS on the command but its COMMAND_ACK is lost: a set of MAV_CMD ids,
      True for all, or a share from 0 to 1; each one lands in ``replies_lost``.
    * ``refuse_arm``: arming refused with "PreArm: <reason>", at the arming only (as an arming check): the
      SYS_STATUS pre-arm bit stays as the vehicle's own checks say (``Calibration.failing_prearm``).
    """

    def __init__(self, seed: int | None = None, clock: Callable[[], float] = time.monotonic, **settings) -> None:
        self.clock = clock                      # real time (a test may hand in a ManualClock's)
        self.link_down = False
        self.heartbeats = True
        self.drop_fraction = 0.0
        self.corrupt_fraction = 0.0
        self.uplink = LinkFaults()
        self.downlink = LinkFaults()
        self.ignore_commands: set[int] | bool = set()
        self.lose_replies: set[int] | bool | float = set()
        self.refuse_arm: str | None = None
        self.outage_until = -math.inf
        self.ignored: deque = deque(maxlen=200)         # MAV_CMD ids swallowed so far, oldest first
        self.replies_lost: deque = deque(maxlen=200)    # MAV_CMD ids acted on whose ACK was lost
        self.counters = Counters(LinkCounters(), LinkCounters())
        self.seed = seed
        self.reply_rng = random.Random(None if seed is None else seed + 3)
        for name, value in settings.items():
            if not hasattr(self, name) or name.startswith("_"):
                raise TypeError(f"no such fault: {name}")
            setattr(self, name, value)

    def __setattr__(self, name, value) -> None:
        if name in ("drop_fraction", "corrupt_fraction"):
            value = _share(name, value)
        elif name in ("uplink", "downlink") and not isinstance(value, LinkFaults):
            raise ValueError(f"{name} must be a LinkFaults")
        elif name == "lose_replies":
            value = self._check_replies(value)
        elif name == "ignore_commands" and value is not True:
            value = set(value or ())
        super().__setattr__(name, value)

    @staticmethod
    def _check_replies(value):
        if isinstance(value, bool):
            return value
        if isinstance(value, float):
            return _share("lose_replies", value)
        if isinstance(value, int):
            if value == 0:
                return set()
            raise ValueError("lose_replies: give a set of MAV_CMD ids, True, or a share as a float")
        return {int(v) for v in (value or ())}

    # -- questions the sim's threads ask --------------------------------------------------------------
    def ignores(self, command: int) -> bool:
        ignored = self.ignore_commands
        if ignored is True:
            return True
        return bool(ignored) and command in ignored

    def loses_reply(self, command: int) -> bool:
        """Whether this command's COMMAND_ACK is lost (recorded in ``replies_lost`` when it is)."""
        lose = self.lose_replies
        if lose is True:
            lost = True
        elif isinstance(lose, float):
            lost = lose > 0 and self.reply_rng.random() < lose
        else:
            lost = command in lose
        if lost:
            self.replies_lost.append(command)
        return lost

    def dead(self, now: float | None = None) -> bool:
        """True while nothing gets through either way (``link_down`` or an ``outage``)."""
        if self.link_down:
            return True
        return (self.clock() if now is None else now) < self.outage_until

    def outage(self, seconds: float) -> None:
        """Both directions dead for ``seconds`` real seconds from now, then back (the TCP connection stays)."""
        self.outage_until = self.clock() + _seconds("outage", seconds)

    def end_outage(self) -> None:
        self.outage_until = -math.inf
