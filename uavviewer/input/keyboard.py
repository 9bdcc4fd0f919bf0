"""Keyboard flying: which key moves which axis, and which key asks for what.

Held keys give full deflection on their axis; releasing a key centres that
axis. The table here also fills the Help > Keys dialog, so the two never differ.
"""
from __future__ import annotations

from PyQt5.QtCore import Qt

from .sticks import Axes

__all__ = ["AXIS_KEYS", "ACTION_KEYS", "EVERYWHERE_KEYS", "KeyboardSticks", "key_help"]

# key -> (axis, sign, what the pilot reads)
AXIS_KEYS: dict[int, tuple[str, float, str]] = {
    Qt.Key_W: ("forward", +1.0, "Forward"),
    Qt.Key_S: ("forward", -1.0, "Back"),
    Qt.Key_A: ("right", -1.0, "Left"),
    Qt.Key_D: ("right", +1.0, "Right"),
    Qt.Key_Up: ("up", +1.0, "Climb"),
    Qt.Key_Down: ("up", -1.0, "Descend"),
    Qt.Key_Left: ("yaw", -1.0, "Yaw left"),
    Qt.Key_Right: ("yaw", +1.0, "Yaw right"),
}

# key -> (action name, what the pilot reads)
ACTION_KEYS: dict[int, tuple[str, str]] = {
    Qt.Key_Space: ("stop", "Stop: hover where you are"),
    Qt.Key_Escape: ("stop", "Stop: cancel a Fly here, hover where you are"),
    Qt.Key_T: ("takeoff", "Take off"),
    Qt.Key_L: ("land", "Land"),
    Qt.Key_R: ("rtl", "Return to launch (RTL)"),
    Qt.Key_PageUp: ("tilt_up", "Tilt the drone's camera up 5° (or the mouse wheel / drag on the video)"),
    Qt.Key_PageDown: ("tilt_down", "Tilt the drone's camera down 5°"),
}

#: The flight buttons' keys that work from every window of the program, whichever has the focus (not in a text
#: field): Stop, Take off, Land, RTL. Esc closes the other windows; the sticks' keys fly from the main window only.
EVERYWHERE_KEYS = (Qt.Key_Space, Qt.Key_T, Qt.Key_L, Qt.Key_R)

_KEY_NAMES = {Qt.Key_Up: "↑", Qt.Key_Down: "↓", Qt.Key_Left: "←", Qt.Key_Right: "→", Qt.Key_Space: "Space",
              Qt.Key_Escape: "Esc", Qt.Key_PageUp: "PgUp", Qt.Key_PageDown: "PgDn"}


class KeyboardSticks:
    """The set of held flight keys, as pilot axes."""

    def __init__(self) -> None:
        self._held: list[int] = []      # in press order; the latest of two opposite keys wins

    def press(self, key: int) -> bool:
        """True if the key flies an axis (and the demand may have changed)."""
        if key not in AXIS_KEYS:
            return False
        if key in self._held:
            self._held.remove(key)
        self._held.append(key)
        return True

    def release(self, key: int) -> bool:
        """Centre the axis of a released key (opposite key held? it takes over)."""
        if key not in AXIS_KEYS:
            return False
        if key in self._held:
            self._held.remove(key)
        return True

    def clear(self) -> None:
        self._held.clear()

    @property
    def active(self) -> bool:
        return bool(self._held)

    def axes(self) -> Axes:
        values = {"forward": 0.0, "right": 0.0, "up": 0.0, "yaw": 0.0}
        for key in self._held:
            axis, sign, _ = AXIS_KEYS[key]
            values[axis] = sign
        return Axes(**values)


def key_help() -> list[tuple[str, str]]:
    """(key, meaning) rows for the Keys dialog."""
    def name(key: int) -> str:
        return _KEY_NAMES.get(key) or chr(key)
    rows = [(name(k), text) for k, (_, _, text) in AXIS_KEYS.items()]
    rows += [(name(k), text) for k, (_, text) in ACTION_KEYS.items()]
    rows.append(("(release)", "Releasing a key centres its axis"))
    rows.append(("Space T L R", "Also from Setup, Parameters and every other window (not while typing in a field)"))
    return rows
