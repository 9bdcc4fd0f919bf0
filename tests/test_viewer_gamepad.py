"""Flying with a gamepad: SDL's virtual joystick (a real SDL device, no hardware) moves the sticks and presses the
buttons; the setpoints are read where they land, at the simulated vehicle.

Real simulator, real driver, real window; waits are on conditions with deadlines.
"""
from __future__ import annotations

import json
import math
from dataclasses import replace

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QWidget

from uavviewer.input.gamepad import sdl2

from gamepad_fixtures import pad, pad_factory, reached  # noqa: F401  (fixtures)
from test_viewer_safety import sent_commands, wait_flying
from test_viewer_window import silent_vehicle  # noqa: F401  (fixture)
from viewer_fixtures import viewer_settings, window, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def wait_pad(qtbot, w, name: str) -> None:
    qtbot.waitUntil(lambda: w.gamepad.pad is not None and w.gamepad.pad.name == name, timeout=5000)


def ready_to_fly(qtbot, w, name: str = "Virtual gamepad") -> None:
    """The vehicle flies velocity, and the pad is there and has been seen centred."""
    wait_flying(qtbot, w)
    wait_pad(qtbot, w, name)
    qtbot.waitUntil(lambda: w.gamepad.status == "", timeout=3000)


def hold_forward(qtbot, w, pad) -> None:
    pad.set_axis("righty", 1.0)
    qtbot.waitUntil(lambda: w.adapter.setpoint.forward > 1.9, timeout=3000)


def press(qtbot, w, pad, button: str) -> None:
    """Press and release: a virtual pad reports its state when read, so each is held until seen."""
    def held() -> bool:
        return w.gamepad.reading is not None and button in w.gamepad.reading.held
    pad.set_button(button, True)
    qtbot.waitUntil(held, timeout=3000)
    pad.set_button(button, False)
    qtbot.waitUntil(lambda: not held(), timeout=3000)


def shaped(value: float, deadband: float = 0.1, expo: float = 0.0) -> float:
    """What the sticks module makes of a deflection (as the pilot would compute it by hand)."""
    m = (abs(value) - deadband) / (1 - deadband)
    return math.copysign((1 - expo) * m + expo * m ** 3, value)


def use_mapping(w, guid: str, mapping: dict, **settings) -> None:
    w.preferences.set_settings(replace(w.settings, gamepad_mappings=json.dumps({guid: mapping}), **settings))


def test_mode2_sticks_reach_the_vehicle_then_mode1(qtbot, sim, flying, window, pad):
    w = window
    wait_flying(qtbot, w)
    wait_pad(qtbot, w, "Virtual gamepad")
    qtbot.waitUntil(lambda: w.gamepad.status == "", timeout=3000)      # seen centred: ready to fly
    n = len(sim.received_setpoints)
    pad.set_axis("lefty", 0.82)          # mode 2, left stick: climb and yaw
    pad.set_axis("leftx", 0.55)
    pad.set_axis("righty", 1.0)          # right stick: forward and sideways
    pad.set_axis("rightx", -0.46)
    up, yaw, fwd, right = shaped(0.82), shaped(0.55), 1.0, shaped(-0.46)
    qtbot.waitUntil(lambda: reached(sim, n, forward=2.0 * fwd, right=2.0 * right, up=1.0 * up,
                                    yaw_rate=math.radians(45.0 * yaw)), timeout=3000)
    assert w.inputLabel.text() == "Flying: gamepad Virtual gamepad"
    n = len(sim.received_setpoints)
    pad.centre()                         # let go: hover at once
    qtbot.waitUntil(lambda: reached(sim, n, forward=0.0, right=0.0, up=0.0, yaw_rate=0.0), timeout=3000)
    assert not w.inputLabel.text().startswith("Flying")

    use_mapping(w, pad.guid, {"mode": "mode1"})
    assert w.gamepad.mapping.axis("forward").input == "lefty" and w.gamepad.mapping.axis("up").input == "righty"
    n = len(sim.received_setpoints)
    pad.set_axis("lefty", 0.82)          # mode 1, left stick: forward and yaw
    pad.set_axis("righty", -0.64)        # right stick: climb (here: descend) and sideways
    qtbot.waitUntil(lambda: reached(sim, n, forward=2.0 * shaped(0.82), up=1.0 * shaped(-0.64), right=0.0),
                    timeout=3000)
    pad.centre()
    qtbot.waitUntil(lambda: w.adapter.setpoint.is_zero, timeout=3000)


def test_dead_zone_expo_and_inversion_per_axis(qtbot, sim, flying, window, pad):
    w = window
    wait_flying(qtbot, w)
    wait_pad(qtbot, w, "Virtual gamepad")
    use_mapping(w, pad.guid, {"mode": "mode2", "axes": {
        "forward": {"input": "righty", "invert": True, "deadband": 0.25, "expo": 0.6},
        "right": {"input": "rightx", "deadband": 0.0, "expo": 0.0}}})
    qtbot.waitUntil(lambda: w.gamepad.status == "", timeout=3000)
    pad.set_axis("righty", 0.2)          # inside forward's own dead zone (0.25): nothing
    qtbot.waitUntil(lambda: w.gamepad.reading is not None and w.gamepad.reading.axis("righty") > 0.19,
                    timeout=3000)
    assert w.adapter.setpoint.is_zero
    n = len(sim.received_setpoints)
    pad.set_axis("righty", 0.7)          # inverted: pushed up flies backwards, shaped by its expo
    pad.set_axis("rightx", 0.05)         # no dead zone on sideways: the smallest touch counts
    qtbot.waitUntil(lambda: reached(sim, n, forward=-2.0 * shaped(0.7, 0.25, 0.6), right=2.0 * shaped(0.05, 0.0)),
                    timeout=3000)
    pad.centre()
    qtbot.waitUntil(lambda: w.adapter.setpoint.is_zero, timeout=3000)


def test_buttons_stop_and_land_at_one_press(qtbot, sim, flying, window, pad):
    w = window
    ready_to_fly(qtbot, w)
    commands = sent_commands(w)
    pad.set_axis("righty", 1.0)
    qtbot.waitUntil(lambda: w.adapter.setpoint.forward == pytest.approx(2.0, abs=1e-3), timeout=3000)
    press(qtbot, w, pad, "a")            # Stop: one press, the stick still held
    qtbot.waitUntil(lambda: "stop" in commands, timeout=3000)
    assert w.adapter.setpoint.is_zero
    assert w.gamepad.status == "centre its sticks"        # the held stick no longer flies
    n = len(sim.received_setpoints)
    qtbot.waitUntil(lambda: reached(sim, n, forward=0.0), timeout=3000)
    pad.centre()
    qtbot.waitUntil(lambda: w.gamepad.status == "", timeout=3000)
    press(qtbot, w, pad, "back")         # RTL, as its button
    qtbot.waitUntil(lambda: "return_to_launch" in commands, timeout=3000)
    qtbot.waitUntil(lambda: flying.state().mode == "RTL", timeout=5000)
    press(qtbot, w, pad, "b")            # Land: one press, no question
    qtbot.waitUntil(lambda: "land" in commands, timeout=3000)
    qtbot.waitUntil(lambda: flying.state().mode == "LAND", timeout=5000)
    assert w.flight.takeoff_box is None


def test_take_off_button_asks_first(qtbot, sim, vehicle, window, pad):
    w = window
    qtbot.waitUntil(lambda: w.adapter.state.readiness.ready_to_arm and w.flightControls.main_button.isEnabled(),
                    timeout=20000)
    wait_pad(qtbot, w, "Virtual gamepad")
    commands = sent_commands(w)
    press(qtbot, w, pad, "start")
    qtbot.waitUntil(lambda: w.flight.takeoff_box is not None and w.flight.takeoff_box.isVisible(), timeout=3000)
    assert "takeoff" not in commands and not vehicle.state().armed
    press(qtbot, w, pad, "a")            # no other button answers the question
    press(qtbot, w, pad, "start")
    qtbot.waitUntil(lambda: w.gamepad.reading is not None and "start" not in w.gamepad.reading.held, timeout=3000)
    assert "takeoff" not in commands and w.flight.takeoff_box.isVisible()
    w.flight.takeoff_box.reject()


def test_disconnect_hovers_with_a_message_and_a_new_pad_plugs_in(qtbot, sim, flying, window, pad_factory):
    w = window
    first = pad_factory("First pad")
    ready_to_fly(qtbot, w, "First pad")
    hold_forward(qtbot, w, first)
    n = len(sim.received_setpoints)
    first.detach()                       # unplugged with the stick held
    qtbot.waitUntil(lambda: w.adapter.setpoint.is_zero, timeout=3000)
    qtbot.waitUntil(lambda: reached(sim, n, forward=0.0), timeout=3000)
    assert "Gamepad First pad disconnected: hovering" in w.messages.texts()
    assert w.gamepad.pad is None
    second = pad_factory("Second pad")   # hot-plug: no restart
    second.set_axis("rightx", 0.9)       # plugged in with a stick held: it must be centred first
    wait_pad(qtbot, w, "Second pad")
    assert w.gamepad.status == "centre its sticks" and w.adapter.setpoint.is_zero
    second.centre()
    qtbot.waitUntil(lambda: w.gamepad.status == "", timeout=3000)
    n = len(sim.received_setpoints)
    second.set_axis("rightx", 1.0)
    qtbot.waitUntil(lambda: reached(sim, n, right=2.0), timeout=3000)
    assert "Gamepad Second pad connected" in w.messages.texts()
    second.centre()


def test_a_stalled_reader_means_hover(qtbot, sim, flying, window, pad):
    """SDL's joystick lock held here stalls the reader's thread, as a wedged driver would."""
    w = window
    ready_to_fly(qtbot, w)
    hold_forward(qtbot, w, pad)
    sdl2.SDL_LockJoysticks()
    try:
        qtbot.waitUntil(lambda: w.adapter.setpoint.is_zero, timeout=3000)
        assert "Gamepad Virtual gamepad stopped reporting: hovering" in w.messages.texts()
        assert w.gamepad.status == "not reporting"
    finally:
        sdl2.SDL_UnlockJoysticks()
    qtbot.waitUntil(lambda: w.gamepad.status == "centre its sticks", timeout=3000)    # back, still held
    assert w.adapter.setpoint.is_zero
    pad.centre()


def test_the_gamepad_takes_over_from_the_screen_only_out_of_its_dead_zone(qtbot, sim, flying, window, pad):
    w = window
    ready_to_fly(qtbot, w)
    w.rightStick.hold(0.0, 0.8)          # the pilot flies the on-screen stick...
    assert w.adapter.setpoint.forward > 0 and w.inputLabel.text() == "Flying: sticks"
    pad.set_axis("rightx", 0.08)         # ...a pad's stick resting within its dead zone changes nothing
    qtbot.waitUntil(lambda: w.gamepad.reading is not None and w.gamepad.reading.axis("rightx") > 0.07,
                    timeout=3000)
    assert w.adapter.setpoint.right == 0.0 and w.adapter.setpoint.forward > 0
    n = len(sim.received_setpoints)
    pad.set_axis("rightx", 1.0)          # out of its dead zone: the gamepad flies alone
    qtbot.waitUntil(lambda: reached(sim, n, forward=0.0, right=2.0), timeout=3000)
    assert w.inputLabel.text() == "Flying: gamepad Virtual gamepad"
    w.rightStick.hold(0.3, 0.8)          # the pilot moves the screen stick: it takes over again
    assert w.adapter.setpoint.right > 0 and w.adapter.setpoint.right < 2.0 and w.adapter.setpoint.forward > 0
    w.rightStick.centre()                # let go; the pad is still held but must come back to centre first
    assert w.adapter.setpoint.is_zero
    pad.centre()
    qtbot.keyPress(w, Qt.Key_W)          # the keys are the screen's too
    assert w.inputLabel.text() == "Flying: keyboard" and w.adapter.setpoint.forward > 0
    qtbot.keyRelease(w, Qt.Key_W)


def test_focus_loss_hovers_unless_flying_in_background(qtbot, sim, flying, window, pad):
    w = window
    ready_to_fly(qtbot, w)
    hold_forward(qtbot, w, pad)
    other = QWidget()
    qtbot.addWidget(other)
    other.show()
    other.activateWindow()
    qtbot.waitUntil(lambda: not w.isActiveWindow(), timeout=3000)
    assert w.adapter.setpoint.is_zero and w.gamepad.status == "window not active"
    commands = sent_commands(w)
    press(qtbot, w, pad, "a")            # Stop acts whatever the focus...
    press(qtbot, w, pad, "back")         # ...RTL does not
    qtbot.waitUntil(lambda: "stop" in commands, timeout=3000)
    assert "return_to_launch" not in commands
    w.activateWindow()
    qtbot.waitUntil(w.isActiveWindow, timeout=3000)
    assert w.gamepad.status == "centre its sticks"         # still held: not before it is centred
    pad.centre()
    w.preferences.set_settings(replace(w.settings, gamepad_background=True))
    qtbot.waitUntil(lambda: w.gamepad.status == "", timeout=3000)
    hold_forward(qtbot, w, pad)
    other.activateWindow()
    qtbot.waitUntil(lambda: not w.isActiveWindow(), timeout=3000)
    n = len(sim.received_setpoints)
    qtbot.waitUntil(lambda: len(sim.received_setpoints) > n + 5, timeout=3000)
    assert w.adapter.setpoint.forward > 1.9 and reached(sim, n, forward=2.0)       # flying on
    pad.centre()


def test_no_device_no_trouble(qtbot, silent_vehicle, window_factory):
    """No pad at all (as in CI): the window says only the inputs it has, and nothing flies."""
    w = window_factory(silent_vehicle)
    started = w.gamepad.frame.time
    # the reader runs and reports (it beats every 0.1 s): a real frame from SDL, saying no pad is there
    qtbot.waitUntil(lambda: w.gamepad.frame.time > started, timeout=3000)
    assert w.gamepad.pads == () and w.gamepad.error == ""
    assert w.inputLabel.text() == "Input: sticks, keyboard"
    assert w.gamepad.axes().is_zero


def test_off_means_no_gamepad_flies(qtbot, silent_vehicle, viewer_settings, window_factory, pad):
    w = window_factory(silent_vehicle)
    wait_pad(qtbot, w, "Virtual gamepad")
    w.preferences.set_settings(replace(w.settings, gamepad="off"))
    assert w.gamepad.pad is None and "gamepad" not in w.inputLabel.text()
    w.preferences.set_settings(replace(w.settings, gamepad=pad.guid))
    assert w.gamepad.pad is not None and w.gamepad.pad.guid == pad.guid

