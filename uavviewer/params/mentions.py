"""Which parameter a message names, so that its line can offer Fix… (open it on the Parameters page)."""
from __future__ import annotations

import re
from typing import Container

from pymavlink.dialects.v20 import ardupilotmega as mavlink

__all__ = ["named_parameter"]

_CANDIDATE = re.compile(r"\b[A-Z][A-Z0-9]*(?:_[A-Z0-9]+)+\b")


def _mavlink_name(word: str) -> bool:
    """A MAVLink message, enum entry or flight mode (FENCE_STATUS, MAV_CMD_..., GUIDED_NOGPS), not a parameter."""
    return (hasattr(mavlink, f"MAVLINK_MSG_ID_{word}") or hasattr(mavlink, word) or word.startswith("MAV_")
            or hasattr(mavlink, f"COPTER_MODE_{word}"))


def named_parameter(text: str, known: Container[str] = (), complete: bool = False) -> str:
    """The first parameter ``text`` names, or "".

    ``known``: the names the vehicle (or the metadata) has; with ``complete`` only those count. Before the
    list is complete a word shaped like a parameter (FS_GCS_ENABLE, RTL_ALT) counts too, unless it is a
    MAVLink name: the page opens it once the vehicle reports it.
    """
    for word in _CANDIDATE.findall(text):
        if word in known:
            return word
        if not complete and len(word) <= 16 and not _mavlink_name(word):
            return word
    return ""
