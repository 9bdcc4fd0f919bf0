"""The gamepad's parts without a window: the SDL reader on virtual pads, mappings, mapping by moving, and which
input flies."""
from __future__ import annotations

import json
import queue

import pytest

from uavviewer.input.gamepad import GamepadReader, Pad, PadReading
from uavviewer.input.gamepad_mapping import AxisCapture, GamepadMapping, default_mapping, mappings_from_json
from uavviewer.input.selector import Input, InputSelector
from uavviewer.input.sticks import Axes, StickMode

from gamepad_fixtures import pad_factory  # noqa: F401  (fixture)

CONTROLLER = Pad("03000000de280000ff11000001000000", "Steam Virtual Gamepad", 7, True,
                 ("leftx", "lefty", "rightx", "righty", "lefttrigger", "righttrigger"),
                 ("a", "b", "x", "y", "back", "guide", "start"))
JOYSTICK = Pad("0300000000f000000300000000010000", "RC transmitter", 8, False, ("axis0", "axis1", "axis2"),
               ("button0", "button1", "hat0up"))


def reading(pad: Pad, **axes: float) -> PadReading:
    return PadReading(pad, tuple(axes.get(a, 0.0) for a in pad.axes))


def frames_until(q: queue.Queue, test, timeout: float = 5.0):
    """Frames from the reader's thread until one passes ``test`` (a deadline, never a sleep)."""
    while True:
        frame = q.get(timeout=timeout)
        if test(frame):
            return frame


def test_reader_sees_virtual_pads_come_and_go(pad_factory):
    reader = GamepadReader()
    q: queue.Queue = queue.Queue()
    reader.subscribe(q.put)
    try:
        pad = pad_factory("Reader pad")
        frame = frames_until(q, lambda f: any(p.name == "Reader pad" for p in f.added))
        known = next(p for p in frame.pads if p.name == "Reader pad")
        assert known.controller and known.guid == pad.guid and "lefty" in known.axes and "a" in known.buttons
        pad.set_axis("lefty", 0.5)        # up is + for a game controller's y axes
        pad.set_axis("lefttrigger", 1.0)
        frames_until(q, lambda f: any(r.axis("lefty") == pytest.approx(0.5, abs=1e-4)
                                      and r.axis("lefttrigger") == pytest.approx(1.0) for r in f.readings))
        pad.set_button("start", True)
        frame = frames_until(q, lambda f: any("start" in r.pressed for r in f.readings))
        assert "start" in frame.readings[0].held
        pad.detach()
        frame = frames_until(q, lambda f: any(p.name == "Reader pad" for p in f.removed))
        assert not any(p.name == "Reader pad" for p in frame.pads)
    finally:
        reader.unsubscribe(q.put)


def test_mode_presets_and_default_buttons():
    m2 = default_mapping(CONTROLLER)
    assert [m2.axis(n).input for n in ("up", "yaw", "forward", "right")] == ["lefty", "leftx", "righty", "rightx"]
    m1 = default_mapping(CONTROLLER, StickMode.MODE1)
    assert [m1.axis(n).input for n in ("up", "yaw", "forward", "right")] == ["righty", "leftx", "lefty", "rightx"]
    assert m2.buttons == {"stop": "a", "land": "b", "takeoff": "start", "rtl": "back"}
    assert m2.pilot_axes(reading(CONTROLLER, lefty=1.0, rightx=-1.0)) == Axes(up=1.0, right=-1.0)
    raw = default_mapping(JOYSTICK)
    assert not raw.flies and raw.buttons["stop"] == "button0" and raw.buttons["land"] == "button1"
    assert raw.pilot_axes(reading(JOYSTICK, axis0=1.0, axis1=1.0, axis2=-1.0)).is_zero


def test_each_axis_has_its_own_dead_zone_expo_and_inversion():
    m = default_mapping(CONTROLLER).with_axis("forward", deadband=0.3, expo=1.0, invert=True) \
        .with_axis("yaw", deadband=0.0)
    axes = m.pilot_axes(reading(CONTROLLER, righty=0.25, leftx=0.05))
    assert axes.forward == 0.0 and axes.yaw == pytest.approx(0.05)
    axes = m.pilot_axes(reading(CONTROLLER, righty=0.65))
    assert axes.forward == pytest.approx(-(0.5 ** 3))          # inverted, (0.65 - 0.3) / 0.7 = 0.5, cubic
    assert m.mode == "custom"


def test_stop_and_land_keep_a_button():
    m = default_mapping(CONTROLLER)
    assert m.with_button("takeoff", "a") is m                 # a is Stop's: refused
    moved = m.with_button("stop", "x").with_button("takeoff", "a")
    assert moved.buttons["stop"] == "x" and moved.buttons["takeoff"] == "a"
    assert m.with_button("rtl", "start").buttons["takeoff"] == ""     # a button does one thing


def test_saved_mappings_are_checked():
    text = json.dumps({CONTROLLER.guid: {"mode": "mode1", "axes": {
        "up": {"input": "righty", "deadband": 7, "expo": "x"}, "pitch": {"input": "leftx"}},
        "buttons": {"land": "", "stop": "y", "selfdestruct": "x"}}, "junk": 3})
    saved = mappings_from_json(text)
    assert list(saved) == [CONTROLLER.guid]
    m = GamepadMapping.from_dict(saved[CONTROLLER.guid], CONTROLLER)
    assert m.axis("up").deadband == 0.5 and m.axis("up").expo == 0.0 and m.axis("forward").input == "lefty"
    assert m.buttons["land"] == "b" and m.buttons["stop"] == "y" and "selfdestruct" not in m.buttons
    assert "pitch" not in m.axes
    assert mappings_from_json("not json") == {} and mappings_from_json("[1]") == {}
    assert GamepadMapping.from_dict(m.to_dict(), CONTROLLER) == m


def test_capture_takes_the_stick_moved_and_its_way():
    capture = AxisCapture(reading(CONTROLLER, righty=0.8))            # still springing back from the last one
    assert capture.feed(reading(CONTROLLER, righty=0.0)) is None
    assert capture.feed(reading(CONTROLLER, lefty=-0.3)) is None
    assert capture.feed(reading(CONTROLLER, lefty=-0.7)) == ("lefty", True)
    throttle = AxisCapture(reading(JOYSTICK, axis2=-1.0))             # an RC throttle resting at the bottom
    assert throttle.feed(reading(JOYSTICK, axis2=-0.6)) is None
    assert throttle.feed(reading(JOYSTICK, axis2=0.6)) == ("axis2", False)


def test_the_input_moved_last_flies():
    s = InputSelector()
    screen, pad = Axes(forward=0.5), Axes(right=1.0)
    assert s.choose(screen, Axes()) == screen and s.owner is Input.SCREEN
    assert s.choose(screen, pad) == pad and s.owner is Input.GAMEPAD          # the pad left its centre
    assert s.choose(screen, Axes(right=0.8)) == Axes(right=0.8)              # the screen held still: pad flies
    assert s.choose(Axes(forward=0.6), Axes(right=0.8)) == Axes(forward=0.6)  # the screen moved: it takes over
    assert s.choose(Axes(), Axes(right=0.8)) == Axes() and s.owner is None    # let go: the held pad waits
    assert s.choose(Axes(), Axes()) == Axes()
    assert s.choose(Axes(), pad) == pad                                         # centred, then out: it flies
    assert s.choose(screen, Axes()) == screen                                   # pad let go, screen held: screen


def test_without_sdl_the_viewer_says_so_and_flies_on(qtbot, monkeypatch):
    """SDL2 missing (its import failed): the reader reports why, the gamepad input stays empty."""
    import uavviewer.input.gamepad as gamepad
    from driver.vehicle.state import Severity
    from uavviewer.input.gamepad_input import GamepadInput
    from uavviewer.settings import ViewerSettings
    monkeypatch.setattr(gamepad, "sdl2", None)
    monkeypatch.setattr(gamepad, "_IMPORT_ERROR", "SDL2 is not available (no libSDL2)")
    messages = []
    g = GamepadInput(ViewerSettings(), reader=GamepadReader())
    g.message.connect(lambda text, severity: messages.append((text, severity)))
    try:
        qtbot.waitUntil(lambda: bool(messages), timeout=3000)
        assert messages == [("Gamepads unavailable: SDL2 is not available (no libSDL2)", Severity.WARNING)]
        assert g.pad is None and g.axes().is_zero and g.error
    finally:
        g.close()
