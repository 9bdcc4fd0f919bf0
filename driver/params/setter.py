"""Writing one parameter: PARAM_SET, confirmed only by a PARAM_VALUE that carries the new value.

* The value goes out in the parameter's own type as the vehicle reported it (ArduPilot casts the float to it);
  a value the type cannot hold (1.5 for an int8, 300 for an int8) is refused before anything is sent.
* The echo is compared at that type's precision (driver.params.values); a PARAM_VALUE with another value
  confirms nothing (it may be the list's stream, or another ground station): the set is sent again, and if
  the vehicle keeps reporting another value the result says which.
* Unanswered, the set is sent again (a lost PARAM_SET and a lost echo look the same; setting twice is
  harmless): a name the vehicle listed gets many tries, one not (yet) listed a few.
* A set never echoed is not confirmed, and nothing is said yet: the value is read back by name
  (PARAM_REQUEST_READ; the answer carries param_index 65535). The read-back showing the value confirms it; showing
  another value for a name not listed yet, the vehicle has the name but not our value: the set goes again with a
  listed name's tries (after those, another value is the answer: refused with it). A name the vehicle does not have gets no answer at all, to a set
  or a read (the recording), but so does every name over a radio that loses everything: "no such parameter" is
  said only when the vehicle's COMPLETE list lacks it (then nothing is read back); otherwise the result says the
  set is not confirmed.

All methods run with the driver's state lock held.
"""
from __future__ import annotations

from concurrent.futures import Future
from dataclasses import dataclass

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from .model import ParamType
from .values import format_value, same_value

__all__ = ["PendingSet", "SET_RETRY", "KNOWN_TRIES", "UNKNOWN_TRIES"]

SET_RETRY = 1.0          # s without the echo before PARAM_SET goes again (MAVProxy waits 1 s)
KNOWN_TRIES = 10         # a listed parameter: 30 % loss each way loses all ten with a chance under 0.1 %
UNKNOWN_TRIES = 3        # a name the vehicle never listed
READ_TRIES = 5           # reads by name of a set never echoed: 30 % loss each way loses all five with a chance of 3 %
OTHER_VALUE_ECHOES = 3   # echoes of another value, each after a PARAM_SET of ours: the vehicle's answer


@dataclass(eq=False)
class PendingSet:
    name: str
    value: float
    ptype: ParamType | None              # None: the vehicle has not said (sent as REAL32, which ArduPilot obeys)
    future: Future
    known: bool                          # the vehicle listed this name
    listed_complete: bool                # ... and its list is complete, so "unknown" is certain
    attempts: int = 0
    next_send: float = 0.0
    reported: float | None = None        # another value the vehicle reported meanwhile
    other_echoes: int = 0                # how many times
    reads: int = 0                       # PARAM_REQUEST_READ sent once the sets went unanswered

    @property
    def command(self) -> str:
        return f"param {self.name}={format_value(self.ptype, self.value)}"

    @property
    def reading(self) -> bool:
        """Every PARAM_SET went unechoed: the value is being read back by name."""
        return self.reads > 0

    @property
    def can_read_back(self) -> bool:
        """Whether a read by name may still tell (not when the complete list lacks the name)."""
        return not self.listed_complete and self.reads < READ_TRIES

    def read_message(self, target: tuple[int, int]):
        return mavlink.MAVLink_param_request_read_message(target[0], target[1], self.name.encode(), -1)

    def message(self, target: tuple[int, int]):
        ptype = int(self.ptype) if self.ptype is not None else mavlink.MAV_PARAM_TYPE_REAL32
        return mavlink.MAVLink_param_set_message(target[0], target[1], self.name.encode(), float(self.value), ptype)

    def confirms(self, ptype: ParamType, value: float) -> bool:
        """Whether a PARAM_VALUE of this name (its true ``ptype``) carries the value asked for."""
        if same_value(ptype, value, self.value):
            return True
        self.reported = value
        self.other_echoes += 1
        return False

    @property
    def answered_otherwise(self) -> bool:
        """The vehicle keeps reporting another value: it will not take this one (or something resets it)."""
        return self.other_echoes >= OTHER_VALUE_ECHOES

    def due(self, now: float) -> bool:
        return self.attempts == 0 or now >= self.next_send

    @property
    def tries(self) -> int:
        return KNOWN_TRIES if self.known else UNKNOWN_TRIES

    def failure(self) -> str:
        """Why the set ended unconfirmed."""
        read = f" and {self.reads} reads by name" if self.reads else ""
        if self.reported is not None:
            return (f"the vehicle reports {self.name} = {format_value(self.ptype, self.reported)}, not "
                    f"{format_value(self.ptype, self.value)}, after {self.attempts} attempts{read}")
        if self.listed_complete:
            return (f"no answer after {self.attempts} attempts: the vehicle has no parameter {self.name} and it is "
                    "not in the vehicle's list (ArduPilot does not answer an unknown name)")
        unlisted = "" if self.known else (f"; {self.name} is not in the part of the vehicle's list read so far, "
                                          "and ArduPilot does not answer a name it does not have")
        return (f"not confirmed: no answer to {self.attempts} PARAM_SET{read}: the link lost them, the vehicle may "
                f"or may not have the new value{unlisted}")
