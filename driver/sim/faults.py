"""Faults a test switches on and off while the simulated vehicle runs.

Plain attributes, read by the sim's threads on every use, so setting one takes
effect at once without locking (each is a single reference swap).
"""
from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

__all__ = ["Faults"]


@dataclass
class Faults:
    link_down: bool = False                   # send nothing and ignore everything received (TCP stays open)
    heartbeats: bool = True                   # False: the vehicle stops sending HEARTBEAT
    drop_fraction: float = 0.0                # share of outgoing frames lost (sequence numbers still advance)
    corrupt_fraction: float = 0.0             # share of outgoing frames with a flipped byte (bad CRC)
    ignore_commands: set[int] | bool = field(default_factory=set)   # MAV_CMD ids never answered; True = all
    refuse_arm: str | None = None             # arming refused with "PreArm: <reason>"
    ignored: deque = field(default_factory=lambda: deque(maxlen=200))   # MAV_CMD ids swallowed so far, oldest first

    def ignores(self, command: int) -> bool:
        ignored = self.ignore_commands
        if ignored is True:
            return True
        return bool(ignored) and command in ignored
