"""Preferences > Gamepad with a virtual pad: live bars and lights, mapping by moving a stick or pressing a button,
saved per controller GUID."""
from __future__ import annotations

import json

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QCheckBox, QComboBox, QDialogButtonBox, QLabel, QProgressBar, QPushButton

from uavviewer.settings import load_settings
from uavviewer.input.gamepad_page import GamepadPage

from gamepad_fixtures import pad, pad_factory  # noqa: F401  (fixtures)
from test_viewer_gamepad import press, wait_pad
from test_viewer_window import silent_vehicle  # noqa: F401  (fixture)
from viewer_fixtures import pick_mode, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(60)


def open_page(qtbot, w) -> GamepadPage:
    w.preferences.edit()
    dialog = w.preferences.dialog
    page = dialog.findChild(GamepadPage)
    dialog.pages.setCurrentWidget(page)
    qtbot.waitUntil(lambda: page.pad is not None and page.isVisible(), timeout=3000)
    return page


def click(qtbot, page, name: str) -> None:
    qtbot.mouseClick(page.findChild(QPushButton, name), Qt.LeftButton)


def ok(qtbot, w) -> None:
    dialog = w.preferences.dialog
    qtbot.mouseClick(dialog.buttons.button(QDialogButtonBox.Ok), Qt.LeftButton)
    qtbot.waitUntil(lambda: w.preferences.dialog is None, timeout=3000)


def test_map_by_moving_and_pressing_saved_for_that_controller(qtbot, silent_vehicle, viewer_settings,
                                                             window_factory, pad):
    w = window_factory(silent_vehicle)
    wait_pad(qtbot, w, "Virtual gamepad")
    page = open_page(qtbot, w)
    assert page.controllerChoice.currentData() == "auto"
    assert page.controllerChoice.findText("Virtual gamepad") >= 0
    # Live: the raw axis, the pilot axis it flies (mode 2: righty is forward), and a button's light.
    pad.set_axis("righty", 0.55)
    forward = page.findChild(QProgressBar, "forwardLive")
    qtbot.waitUntil(lambda: forward.value() == 50, timeout=3000)           # (0.55 - 0.1) / 0.9
    pad.set_button("x", True)
    light = [lab for lab in page.findChildren(QLabel) if lab.text() == "x"][0]
    qtbot.waitUntil(lambda: light.property("held") is True, timeout=3000)
    pad.set_button("x", False)
    pad.centre()
    qtbot.waitUntil(lambda: forward.value() == 0, timeout=3000)

    # "Move the stick you want for climb": pulled down, so it is taken inverted. The pad does not fly meanwhile.
    click(qtbot, page, "upMap")
    assert page.capturing == "up" and "Move the stick you want for climb up" in page.captureLabel.text()
    assert w.gamepad.status == "being mapped"
    pad.set_axis("righty", -0.9)
    qtbot.waitUntil(lambda: page.capturing is None, timeout=3000)
    assert page.findChild(QComboBox, "upInput").currentData() == "righty"
    assert page.findChild(QCheckBox, "upInvert").isChecked()
    assert page.padMode.currentData() == "custom"
    pad.centre()

    # "Press the button you want for Land"; Stop cannot then take Land's button.
    click(qtbot, page, "landMap")
    press(qtbot, w, pad, "y")
    qtbot.waitUntil(lambda: page.capturing is None, timeout=3000)
    assert page.findChild(QLabel, "landButton").text() == "y"
    click(qtbot, page, "stopMap")
    press(qtbot, w, pad, "y")
    qtbot.waitUntil(lambda: page.capturing is None, timeout=3000)
    assert "must always have one" in page.captureLabel.text()
    assert page.findChild(QLabel, "stopButton").text() == "a"
    ok(qtbot, w)

    saved = json.loads(load_settings(viewer_settings).gamepad_mappings)[pad.guid]
    assert saved["axes"]["up"]["input"] == "righty" and saved["axes"]["up"]["invert"] is True
    assert saved["buttons"]["land"] == "y" and saved["buttons"]["stop"] == "a"
    mapping = w.gamepad.mapping
    assert mapping.axis("up").input == "righty" and mapping.action_for("y") == "land"
    # The window flies by it: pulled down on righty is climb now.
    w.activateWindow()
    qtbot.waitUntil(lambda: w.gamepad.status == "", timeout=3000)
    pad.set_axis("righty", -1.0)
    qtbot.waitUntil(lambda: w.gamepad.axes().up == pytest.approx(1.0), timeout=3000)
    # Opened again, the page shows what was saved; mode 1 from its list, this controller by name, in background.
    page = open_page(qtbot, w)
    assert page.findChild(QLabel, "landButton").text() == "y"
    assert page.findChild(QCheckBox, "upInvert").isChecked()
    pick_mode(qtbot, page.padMode, page.padMode.itemText(page.padMode.findData("mode1")))
    assert page.findChild(QComboBox, "forwardInput").currentData() == "lefty"
    assert not page.findChild(QCheckBox, "upInvert").isChecked()
    pick_mode(qtbot, page.controllerChoice, "Virtual gamepad")
    page.flyInBackground.click()
    ok(qtbot, w)
    chosen = load_settings(viewer_settings)
    assert chosen.gamepad == pad.guid and chosen.gamepad_background
    assert json.loads(chosen.gamepad_mappings)[pad.guid]["axes"]["up"]["input"] == "righty"   # mode 1's climb
    assert w.gamepad.background and w.gamepad.mapping.axis("forward").input == "lefty"


def test_an_unknown_joystick_flies_only_once_mapped(qtbot, silent_vehicle, viewer_settings, window_factory,
                                                    pad_factory):
    rc = pad_factory("RC transmitter", controller=False, axes=4, buttons=4)
    w = window_factory(silent_vehicle)
    wait_pad(qtbot, w, "RC transmitter")
    assert w.gamepad.status == "map it in Preferences"
    qtbot.waitUntil(lambda: any("map its sticks in Preferences" in t for t in w.messages.texts()), timeout=3000)
    rc.set_axis(2, 1.0)
    qtbot.waitUntil(lambda: w.gamepad.reading is not None and w.gamepad.reading.axis("axis2") == 1.0, timeout=3000)
    assert w.gamepad.axes().is_zero
    rc.set_axis(2, 0.0)
    page = open_page(qtbot, w)
    assert "SDL does not know its layout" in page.padInfo.text()
    assert not page.padMode.isEnabled()
    for name, axis in (("up", 2), ("yaw", 3), ("forward", 1), ("right", 0)):
        click(qtbot, page, f"{name}Map")
        rc.set_axis(axis, 0.8)
        qtbot.waitUntil(lambda: page.capturing is None, timeout=3000)
        rc.set_axis(axis, 0.0)
        assert page.findChild(QComboBox, f"{name}Input").currentData() == f"axis{axis}"
    ok(qtbot, w)
    w.activateWindow()
    qtbot.waitUntil(lambda: w.gamepad.status == "", timeout=3000)
    rc.set_axis(2, 1.0)
    qtbot.waitUntil(lambda: w.gamepad.axes().up == pytest.approx(1.0), timeout=3000)
    assert w.gamepad.mapping.buttons["stop"] == "button0" and w.gamepad.mapping.buttons["land"] == "button1"
