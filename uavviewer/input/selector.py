"""Which input flies: the on-screen sticks and keys, or the gamepad. The driver sees one velocity demand.

The input the pilot moved last flies alone. The on-screen sticks and the keys (summed, as ever) take over
whenever the pilot moves them. The gamepad takes over only as its sticks leave their dead zone: a pad lying on
the desk, or held off centre while the pilot flies the screen, never does. When the flying input lets go, a
held on-screen stick flies again (the pilot's hand is on it); the gamepad must come back to the centre first.
"""
from __future__ import annotations

import enum

from .sticks import Axes

__all__ = ["Input", "InputSelector"]


class Input(enum.Enum):
    SCREEN = "screen"        # the on-screen sticks and the keyboard
    GAMEPAD = "gamepad"


class InputSelector:
    def __init__(self) -> None:
        self.owner: Input | None = None
        self._screen = Axes()
        self._gamepad = Axes()

    def choose(self, screen: Axes, gamepad: Axes) -> Axes:
        """The demand to fly, given both inputs now (calling it again with the same inputs changes nothing)."""
        gamepad_left_centre = self._gamepad.is_zero and not gamepad.is_zero
        screen_moved = screen != self._screen and not screen.is_zero
        self._screen, self._gamepad = screen, gamepad
        if gamepad_left_centre:
            self.owner = Input.GAMEPAD
        if screen_moved:
            self.owner = Input.SCREEN
        if self.owner is Input.GAMEPAD and gamepad.is_zero:
            self.owner = None
        if self.owner is Input.SCREEN and screen.is_zero:
            self.owner = None
        if self.owner is None and not screen.is_zero:
            self.owner = Input.SCREEN
        if self.owner is Input.GAMEPAD:
            return gamepad
        return screen if self.owner is Input.SCREEN else Axes()

    def reset(self) -> None:
        """Nobody flies (sticks inert); the gamepad must leave its centre again to take over."""
        self.owner = None
        self._screen = Axes()
        self._gamepad = Axes()
