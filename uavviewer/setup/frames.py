"""The motor layouts of ArduCopter's frames, as data: frames.json, written by scripts/frames-table from ArduPilot's
own AP_MotorsMatrix.cpp and AP_MotorsTri.cpp (4.6.3), never typed in by hand.

A layout is looked up by (FRAME_CLASS, FRAME_TYPE) as ArduCopter picks it: a class whose setup has a ``default``
case (Y6, the tricopter) takes it for every type it does not name."""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from functools import lru_cache

__all__ = ["Motor", "Layout", "layout", "layouts", "CW", "CCW"]

CW, CCW = "CW", "CCW"
_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "frames.json")


@dataclass(frozen=True)
class Motor:
    output: int                  # SERVOn / the motor's output number
    angle: float                 # degrees from the nose, clockwise seen from above
    radius: float                # from the centre, in the source's factor units (1 = a plain arm)
    spin: str | None             # CW, CCW, or None when the frame yaws otherwise (the tricopter's servo)
    test: int                    # its place in the motor test (MAV_CMD_DO_MOTOR_TEST's motor number)
    servo: bool = False          # the tricopter's yaw servo, tested in the sequence as a motor is


@dataclass(frozen=True)
class Layout:
    frame_class: int
    frame_type: int | str        # "default": every type the class does not name
    name: str                    # ArduPilot's own "OCTA/X" (get_frame_and_type_string without "Frame: ")
    motors: tuple[Motor, ...]

    @property
    def letters(self) -> dict[int, str]:
        """Output → its test letter (A = test 1), as the page labels it."""
        return {m.output: chr(ord("A") + m.test - 1) for m in self.motors}


@lru_cache(maxsize=1)
def layouts() -> dict[tuple[int, int | str], Layout]:
    with open(_FILE) as f:
        data = json.load(f)
    return {(d["class"], d["type"]): Layout(d["class"], d["type"], d["name"],
                                            tuple(Motor(**m) for m in d["motors"]))
            for d in data["layouts"]}


def layout(frame_class: int | None, frame_type: int | None) -> Layout | None:
    """The layout ArduCopter sets up for FRAME_CLASS / FRAME_TYPE, None when it draws none (a helicopter, an
    unknown number)."""
    if frame_class is None or frame_type is None:
        return None
    table = layouts()
    return table.get((int(frame_class), int(frame_type))) or table.get((int(frame_class), "default"))
