"""Tilting the vehicle's camera from the window moves the simulated picture (issue 23): the Level and Down
buttons, the mouse wheel and a drag on the video, the keys; the HUD and the row under the video show the pitch."""
from __future__ import annotations

import numpy as np
from PyQt5.QtCore import QPoint, QPointF, Qt
from PyQt5.QtGui import QWheelEvent
from PyQt5.QtWidgets import QApplication

from driver.camera.sim import SKY
from gamepad_fixtures import pad, pad_factory  # noqa: F401  (fixtures)
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)
from driver.vehicle.state import CommandStatus


def horizon_row(image: np.ndarray) -> int:
    column = image[:, image.shape[1] // 2].astype(int)
    ground = np.where(np.abs(column - np.array(SKY)).sum(axis=1) > 30)[0]
    return int(ground[0]) if len(ground) else image.shape[0]


def near(window, pitch: float):
    return lambda: (window.adapter.state is not None and window.adapter.state.gimbal.pitch_deg is not None
                    and abs(window.adapter.state.gimbal.pitch_deg - pitch) < 0.6)


def row_now(window) -> int:
    return horizon_row(window.camera_view.frame().image)


def wheel(view, notches: int) -> None:
    centre = QPointF(view.width() / 2, view.height() / 2)
    event = QWheelEvent(centre, view.mapToGlobal(centre.toPoint()), QPoint(0, 0), QPoint(0, 120 * notches),
                        Qt.NoButton, Qt.NoModifier, Qt.NoScrollPhase, False)
    QApplication.sendEvent(view, event)


def test_tilting_from_the_window_moves_the_simulated_picture(qtbot, vehicle, window_factory):
    w = window_factory(vehicle, cameras=["sim"])
    qtbot.waitUntil(lambda: w.camera_view.frame() is not None and w.adapter.state is not None
                    and w.adapter.state.gimbal.known, timeout=10000)
    qtbot.waitUntil(near(w, -90), timeout=5000)                   # the mount's default: straight down
    qtbot.waitUntil(lambda: row_now(w) == 0, timeout=5000)        # nothing but ground
    assert "-90°" in w.gimbal_bar.pitch_label.text() and "gimbal -90°" in w.gimbal_bar.pitch_label.toolTip()

    w.gimbal_bar.level_button.click()
    qtbot.waitUntil(near(w, 0), timeout=10000)
    qtbot.waitUntil(lambda: w.gimbal._target is None, timeout=3000)   # reached: tilting starts from what it says
    qtbot.waitUntil(lambda: abs(row_now(w) - 240) <= 3, timeout=5000)   # level: the horizon across the middle
    level = w.camera_view.frame().image.copy()

    wheel(w.camera_view, -4)                                      # four notches down: -20 deg
    qtbot.waitUntil(near(w, -20), timeout=10000)
    qtbot.waitUntil(lambda: row_now(w) < 240 - 100, timeout=5000)  # the horizon went up the picture
    assert not np.array_equal(level, w.camera_view.frame().image)

    w.camera_view.setFocus()
    qtbot.keyClick(w.camera_view, Qt.Key_PageUp)                  # the key: 5 deg up
    qtbot.waitUntil(near(w, -15), timeout=10000)
    view = w.camera_view                                          # drag up 40 px: 10 deg up
    start = QPoint(view.width() // 2, view.height() // 2)
    qtbot.mousePress(view, Qt.LeftButton, pos=start)
    qtbot.mouseMove(view, start - QPoint(0, 40))
    qtbot.mouseRelease(view, Qt.LeftButton, pos=start - QPoint(0, 40))
    qtbot.waitUntil(near(w, -5), timeout=10000)
    qtbot.waitUntil(lambda: abs(row_now(w) - 240) < 40, timeout=5000)

    w.gimbal_bar.down_button.click()
    qtbot.waitUntil(near(w, -90), timeout=10000)
    results = [r for r in vehicle.state().results if r.command.startswith("gimbal pitch")]
    assert results and all(r.status is CommandStatus.ACCEPTED for r in results), results


def test_gamepad_buttons_mapped_to_the_camera_tilt(qtbot, vehicle, window_factory, pad):
    """A paddle or shoulder button, mapped in the gamepad page's table, tilts the drone's camera 5° a press."""
    from test_viewer_gamepad import press, use_mapping, wait_pad
    w = window_factory(vehicle)
    wait_pad(qtbot, w, "Virtual gamepad")
    qtbot.waitUntil(near(w, -90), timeout=10000)
    use_mapping(w, pad.guid, {"mode": "mode2", "buttons": {"tilt_up": "rightshoulder",
                                                          "tilt_down": "leftshoulder"}})
    assert w.gamepad.mapping.action_for("rightshoulder") == "tilt_up"
    press(qtbot, w, pad, "rightshoulder")
    qtbot.waitUntil(near(w, -85), timeout=10000)
    press(qtbot, w, pad, "rightshoulder")
    qtbot.waitUntil(near(w, -80), timeout=10000)
    press(qtbot, w, pad, "leftshoulder")
    qtbot.waitUntil(near(w, -85), timeout=10000)
