"""Which stick of a gamepad flies what, and which button asks for what: one mapping per controller GUID.

A game controller SDL knows starts in mode 2 (left: climb and yaw; right: forward and sideways) or mode 1, with
Stop on A, Land on B, Take off on Start (it asks, as the button does) and RTL on Back. A joystick SDL does not
know (an RC transmitter in joystick mode, a flight stick) flies nothing until its axes are mapped; its first two
buttons are Stop and Land from the start. Stop and Land are always mapped. Each pilot axis has its own dead zone,
expo and inversion. No Qt here.
"""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field, replace

from .gamepad import Pad, PadReading
from .sticks import Axes, StickMode, StickShaping, shape

__all__ = ["PILOT_AXES", "ACTIONS", "CONTROLLER_BUTTONS", "AxisMap", "GamepadMapping", "default_mapping", "AxisCapture",
           "ButtonCapture", "mappings_from_json", "mappings_to_json"]

#: pilot axis -> what the pilot reads, and which way to move the stick when mapping it
PILOT_AXES: dict[str, tuple[str, str]] = {
    "up": ("Climb", "up"),
    "yaw": ("Yaw", "right (nose right)"),
    "forward": ("Forward", "forward (up)"),
    "right": ("Sideways", "right"),
}
#: action -> what the pilot reads
ACTIONS: dict[str, str] = {"stop": "Stop (hover)", "land": "Land", "takeoff": "Take off (asks)",
                           "rtl": "Return to launch",
                           # the drone's camera, 5 degrees a press (a paddle or shoulder button; unmapped at first)
                           "tilt_up": "Camera tilt up", "tilt_down": "Camera tilt down"}
ALWAYS_MAPPED = ("stop", "land")
#: a known game controller's buttons until the pilot maps others (SDL's names for the Xbox layout's places)
CONTROLLER_BUTTONS = {"stop": "a", "land": "b", "takeoff": "start", "rtl": "back"}
DEFAULT_DEADBAND = 0.10          # physical sticks rest a little off centre and drift with wear
CAPTURE_THRESHOLD = 0.5          # how far a stick must move from where it rested to be taken

_PRESETS = {StickMode.MODE2: {"up": "lefty", "yaw": "leftx", "forward": "righty", "right": "rightx"},
            StickMode.MODE1: {"forward": "lefty", "yaw": "leftx", "up": "righty", "right": "rightx"}}


@dataclass(frozen=True)
class AxisMap:
    """One pilot axis: the pad's input ("" = none), inverted or not, its own dead zone and expo."""
    input: str = ""
    invert: bool = False
    deadband: float = DEFAULT_DEADBAND
    expo: float = 0.0

    def value(self, reading: PadReading) -> float:
        if not self.input:
            return 0.0
        v = reading.axis(self.input)
        return shape(-v if self.invert else v, StickShaping(self.deadband, self.expo))


@dataclass(frozen=True)
class GamepadMapping:
    mode: str = StickMode.MODE2.value            # mode2, mode1, or "custom" once the pilot moved an axis
    axes: dict = field(default_factory=dict)     # pilot axis -> AxisMap
    buttons: dict = field(default_factory=dict)  # action -> the pad's button name

    def axis(self, name: str) -> AxisMap:
        return self.axes.get(name, AxisMap())

    def pilot_axes(self, reading: PadReading) -> Axes:
        """The pad's sticks as pilot axes, each shaped by its own dead zone and expo."""
        return Axes(**{name: self.axis(name).value(reading) for name in PILOT_AXES})

    def action_for(self, button: str) -> str | None:
        for action, name in self.buttons.items():
            if name == button:
                return action
        return None

    def with_axis(self, name: str, **changes) -> "GamepadMapping":
        axes = dict(self.axes)
        axes[name] = replace(self.axis(name), **changes)
        mode = "custom" if "input" in changes or "invert" in changes else self.mode
        return replace(self, axes=axes, mode=mode)

    def with_button(self, action: str, button: str) -> "GamepadMapping":
        """``button`` for ``action``; a button does one thing, so it leaves any other action (which keeps
        its own button when it must always be mapped: Stop and Land)."""
        buttons = dict(self.buttons)
        for other, name in list(buttons.items()):
            if name == button and other != action:
                if other in ALWAYS_MAPPED:
                    return self                  # the pilot must first give Stop/Land another button
                buttons[other] = ""
        buttons[action] = button
        return replace(self, buttons=buttons)

    def with_mode(self, mode: StickMode, pad: Pad) -> "GamepadMapping":
        """The preset's sticks for ``mode`` (a game controller), keeping each axis's dead zone and expo."""
        preset = _PRESETS.get(mode)
        if preset is None or not pad.controller:
            return replace(self, mode=mode.value)
        axes = {n: replace(self.axis(n), input=preset[n], invert=False) for n in PILOT_AXES}
        return replace(self, axes=axes, mode=mode.value)

    @property
    def flies(self) -> bool:
        return any(self.axis(n).input for n in PILOT_AXES)

    def to_dict(self) -> dict:
        return {"mode": self.mode, "axes": {n: asdict(a) for n, a in self.axes.items()}, "buttons": self.buttons}

    @classmethod
    def from_dict(cls, data: dict, pad: Pad | None = None) -> "GamepadMapping":
        """A saved mapping, checked: unknown keys are dropped, numbers kept in range, Stop and Land kept."""
        preset = StickMode.MODE1 if data.get("mode") == StickMode.MODE1.value else StickMode.MODE2
        base = default_mapping(pad, preset) if pad is not None else GamepadMapping()
        axes = dict(base.axes)
        for name, a in (data.get("axes") or {}).items():
            if name in PILOT_AXES and isinstance(a, dict):
                axes[name] = AxisMap(input=str(a.get("input", "")), invert=bool(a.get("invert", False)),
                                     deadband=_number(a.get("deadband"), DEFAULT_DEADBAND, 0.0, 0.5),
                                     expo=_number(a.get("expo"), 0.0, 0.0, 1.0))
        buttons = dict(base.buttons)
        for action, name in (data.get("buttons") or {}).items():
            if action in ACTIONS and isinstance(name, str) and (name or action not in ALWAYS_MAPPED):
                buttons[action] = name
        mode = data.get("mode") if data.get("mode") in ("mode2", "mode1", "custom") else base.mode
        return cls(mode=mode, axes=axes, buttons=buttons)


def _number(raw, default: float, low: float, high: float) -> float:
    try:
        v = float(raw)
    except (TypeError, ValueError):
        return default
    return min(max(v, low), high) if v == v else default


def default_mapping(pad: Pad, mode: StickMode = StickMode.MODE2) -> GamepadMapping:
    """What a pad flies before the pilot maps it (see the module's note)."""
    if pad.controller:
        return GamepadMapping(buttons={a: b for a, b in CONTROLLER_BUTTONS.items()
                                       if b in pad.buttons or a in ALWAYS_MAPPED}
                              ).with_mode(mode, pad)
    first = list(pad.buttons[:2]) + ["", ""]
    return GamepadMapping(mode="custom", axes={n: AxisMap() for n in PILOT_AXES},
                          buttons={"stop": first[0] or "button0", "land": first[1] or "button1", "takeoff": "",
                                   "rtl": ""})


def mappings_from_json(text: str) -> dict[str, dict]:
    """GUID -> saved mapping (as a dict; checked against the pad when it connects)."""
    try:
        data = json.loads(text or "{}")
    except ValueError:
        return {}
    return {str(k): v for k, v in data.items() if isinstance(v, dict)} if isinstance(data, dict) else {}


def mappings_to_json(mappings: dict[str, dict]) -> str:
    """GUID -> mapping (as :meth:`GamepadMapping.to_dict` gives it), for ViewerSettings.gamepad_mappings."""
    return json.dumps(mappings, sort_keys=True)


class AxisCapture:
    """"Move the stick you want for climb": the first axis moved far from its rest; moved the negative way, it
    is taken inverted. An axis's rest is the value nearest the centre seen since asking, so a stick still
    springing back from the last one mapped is not taken, and an RC throttle resting at the bottom is."""

    def __init__(self, rest: PadReading) -> None:
        self._pad = rest.pad
        self._rest = list(rest.axes)

    def feed(self, reading: PadReading) -> tuple[str, bool] | None:
        if reading.pad.instance != self._pad.instance:
            return None
        best, name = 0.0, ""
        for i, (axis, now) in enumerate(zip(reading.pad.axes, reading.axes)):
            if abs(now) < abs(self._rest[i]):
                self._rest[i] = now
            was = self._rest[i]
            if abs(now - was) > abs(best):
                best, name = now - was, axis
        if abs(best) < CAPTURE_THRESHOLD:
            return None
        return name, best < 0


class ButtonCapture:
    """"Press the button you want for Land": the next button pressed on that pad."""

    def __init__(self, pad: Pad) -> None:
        self._pad = pad

    def feed(self, reading: PadReading) -> str | None:
        if reading.pad.instance != self._pad.instance or not reading.pressed:
            return None
        return reading.pressed[0]
