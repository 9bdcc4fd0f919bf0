"""What is wrong with a mission as planned, said on the item (no Qt).

ArduCopter ends a mission at an RTL or a LAND: RTL lands at home, LAND lands where it is, and either disarms on
the ground (mode_auto.cpp: a landed vehicle's mission is complete), so the items after them are never flown.
"""
from __future__ import annotations

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.mission.plan import MissionItem

__all__ = ["unreachable"]

_ENDS = {mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH: "RTL", mavlink.MAV_CMD_NAV_LAND: "LAND"}


def unreachable(entries, numbers: list[int]) -> dict[int, str]:
    """``{entry index: why}`` for each entry after the mission's first RTL or LAND; ``numbers``: each entry's
    item number on the vehicle (the words name it)."""
    out: dict[int, str] = {}
    end = None
    for i, entry in enumerate(entries):
        if end is not None:
            out[i] = (f"Never flown: item {end[1]} ({end[0]}) lands and ends the mission before it; "
                      "move it before, or delete it")
        elif isinstance(entry, MissionItem) and entry.command in _ENDS:
            end = (_ENDS[entry.command], numbers[i])
    return out
