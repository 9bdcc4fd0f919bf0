"""Issue 29, item 5: nothing moves under the cursor. One flight per laptop size, from no vehicle to a replay's end;
after each state change the place and size (mapTo the window) of every visible control is compared with the one
before: no button, stick, attitude indicator, camera row, replay bar or Messages may move or resize by more than
1 px. Real simulated vehicle (its camera, its link cut by fault injection), real driver, real window, real
ArduCopter recording.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys

import pytest
from PyQt5.QtCore import QPoint, QRect, Qt
from PyQt5.QtWidgets import QApplication, QMessageBox

from driver.vehicle.state import LinkStatus
from recordings import FLIGHT
from uavviewer.replay.bar import clock_text

from conftest import LAST_LEG_SPEEDUP
from viewer_fixtures import app_style, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = [pytest.mark.timeout(240), pytest.mark.usefixtures("app_style")]

SIZES = [(1366, 768), (1280, 720)]
TOLERANCE = 1                       # px


def controls(w) -> dict:
    """Every control a pilot aims at in the central area, and Messages."""
    fc, cam, gb, rb = w.flightControls, w.camera_panel, w.gimbal_bar, w.replayBar
    named = {"main button": fc.main_button, "stop": fc.stop_button, "rtl": fc.rtl_button, "arm": fc.arm_button,
             "mode": w.modeSelector, "left stick": w.leftStick, "right stick": w.rightStick,
             "attitude": w.attitude, "video": w.camera_view, "HUD": cam.hud_button, "snapshot": cam.snapshot_button,
             "record": cam.record_button, "switch camera": cam.switch_button, "gimbal pitch": gb.pitch_label,
             "level": gb.level_button, "down": gb.down_button, "photo": gb.photo_button, "video on vehicle":
             gb.record_button, "replay play": rb.play_button, "replay restart": rb.restart_button,
             "replay speed": rb.speed, "replay seek": rb.progress, "replay clock": rb.clock,
             "messages": w.messagesDock}
    return {name: widget for name, widget in named.items() if widget.isVisible()}


class Watch:
    """The controls' rectangles after each step, and every move or resize between two steps."""

    def __init__(self, w) -> None:
        self.w = w
        self.moves: list[str] = []
        self.last = self.rects()

    def rects(self) -> dict[str, QRect]:
        QApplication.processEvents()            # the layout requests the change posted
        return {name: QRect(widget.mapTo(self.w, QPoint(0, 0)), widget.size())
                for name, widget in controls(self.w).items()}

    def step(self, name: str) -> None:
        now = self.rects()
        for control in sorted(now.keys() & self.last.keys()):
            a, b = self.last[control], now[control]
            if max(abs(a.x() - b.x()), abs(a.y() - b.y()), abs(a.width() - b.width()),
                   abs(a.height() - b.height())) > TOLERANCE:
                self.moves.append(f"{name}: {control} {a.getRect()} -> {b.getRect()}")
        self.last = now


def answer(qtbot, box_of, button) -> None:
    qtbot.waitUntil(lambda: box_of() is not None and box_of().isVisible(), timeout=5000)
    box = box_of()
    qtbot.mouseClick(box.button(button) if isinstance(button, QMessageBox.StandardButton) else button(box),
                     Qt.LeftButton)


@pytest.mark.parametrize("size", SIZES, ids=[f"{w}x{h}" for w, h in SIZES])
def test_no_control_moves_as_the_state_changes(qtbot, sim_factory, vehicle_factory, window_factory, size):
    sim = sim_factory(camera=True, speedup=8.0)                  # a MAVLink camera: photos and video
    sim.faults.link_down = True                                  # no vehicle heard yet
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", loss_timeout=1.0)
    w = window_factory(vehicle, cameras=["sim"], takeoff_altitude=3.0)
    w.connections.adopt(vehicle)
    w.resize(*size)
    qtbot.waitUntil(lambda: (w.width(), w.height()) == size, timeout=3000)
    watch = Watch(w)

    sim.faults.link_down = False
    qtbot.waitUntil(lambda: w.adapter.state.connected and w.flightControls.main_button.isEnabled(), timeout=20000)
    watch.step("connect")
    qtbot.waitUntil(lambda: w.camera_view.frame() is not None and w.adapter.state.gimbal.known, timeout=15000)
    qtbot.waitUntil(lambda: "-90" in w.gimbal_bar.pitch_label.text(), timeout=5000)
    watch.step("camera start")

    qtbot.mouseClick(w.flightControls.main_button, Qt.LeftButton)            # Take off, and its confirmation
    answer(qtbot, lambda: w.flight.takeoff_box, QMessageBox.Yes)
    qtbot.waitUntil(lambda: w.adapter.state.armed, timeout=30000)
    watch.step("arm")
    qtbot.waitUntil(lambda: w.flightControls.progress.isVisible() or w.adapter.state.can_fly_velocity, timeout=20000)
    watch.step("taking off")
    qtbot.waitUntil(lambda: w.adapter.state.can_fly_velocity and w.leftStick.isEnabled(), timeout=30000)
    watch.step("airborne")
    qtbot.waitUntil(w.alert_banner.isVisible, timeout=10000)                  # no GCS failsafe: in the banner
    watch.step("banner shown")
    qtbot.mouseClick(w.alert_banner.close_button, Qt.LeftButton)
    assert not w.alert_banner.isVisible()
    watch.step("banner hidden")

    qtbot.mouseClick(w.gimbal_bar.record_button, Qt.LeftButton)               # the vehicle's camera records
    # the start answered (the next click is a stop, not a second start superseding a start still pending)
    qtbot.waitUntil(lambda: w.adapter.state.camera.recording and "●" in w.gimbal_bar.record_button.text()
                    and any(r.command == "record on" and r.ok for r in w.adapter.state.results), timeout=10000)
    qtbot.waitUntil(w.gimbal_bar.record_button.isChecked, timeout=5000)       # it follows the camera, every snapshot
    watch.step("record")
    qtbot.mouseClick(w.gimbal_bar.record_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.adapter.state.camera.recording is False, timeout=10000)
    watch.step("stop recording")
    qtbot.mouseClick(w.gimbal_bar.photo_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.adapter.state.camera.photos >= 1, timeout=10000)
    watch.step("photo")
    home = w.adapter.state.home
    assert vehicle.look_at(home.lat + 0.0002, home.lon).result(10).ok       # the map's "Look here"
    qtbot.waitUntil(lambda: w.gimbal_bar.stop_looking_button.isVisible(), timeout=10000)
    watch.step("look at")
    qtbot.mouseClick(w.gimbal_bar.stop_looking_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: not w.gimbal_bar.stop_looking_button.isVisible(), timeout=10000)
    watch.step("stop looking")

    sim.faults.link_down = True
    qtbot.waitUntil(lambda: w.adapter.state.link.status is LinkStatus.LOST and w.linkBanner.isVisible(),
                    timeout=10000)
    watch.step("link lost")
    sim.faults.link_down = False
    qtbot.waitUntil(lambda: w.adapter.state.link.status is LinkStatus.OK and not w.linkBanner.isVisible(),
                    timeout=10000)
    w.alert_banner.dismiss()                                  # "Link lost" stays there until dismissed
    watch.step("link back")

    qtbot.mouseClick(w.plan.plan_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.plan.dock.isVisible(), timeout=3000)
    watch.step("plan opened")
    qtbot.mouseClick(w.plan.plan_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: not w.plan.dock.isVisible(), timeout=3000)
    watch.step("plan closed")

    qtbot.mouseClick(w.flightControls.main_button, Qt.LeftButton)            # Land
    sim.speedup = LAST_LEG_SPEEDUP          # the descent is only waited out: the controls are watched all the way
    qtbot.waitUntil(lambda: not w.adapter.state.armed, timeout=60000)
    watch.step("landed")

    w.tools.open_flight_log(f"{FLIGHT}.tlog")
    qtbot.waitUntil(lambda: w.adapter.replay is not None and w.adapter.state.connected, timeout=20000)
    qtbot.waitUntil(lambda: w.replayBar.isVisible() and w.adapter.replay.duration > 0, timeout=5000)
    # the bar seeks only once it has shown the duration (else the whole log plays: 10 s at 8×)
    qtbot.waitUntil(lambda: w.replayBar.clock.text().endswith(f"/ {clock_text(w.adapter.replay.duration)}"),
                    timeout=5000)
    watch.step("replay start")
    replay = w.adapter.replay
    replay.speed = 8.0
    w.replayBar.seek_to(replay.duration - 3.0)
    qtbot.waitUntil(lambda: not w.replayBar.play_button.isEnabled(), timeout=20000)   # the end: Restart beside
    watch.step("replay end")

    assert not watch.moves, f"at {size[0]}×{size[1]}:\n" + "\n".join(watch.moves)


DOCK_SIZES = [(1366, 768), (1280, 720), (1024, 560)]


@pytest.mark.parametrize("size", DOCK_SIZES, ids=[f"{w}x{h}" for w, h in DOCK_SIZES])
def test_no_control_moves_as_a_dock_is_hidden_or_shown(qtbot, vehicle, window_factory, size):
    """View › Messages hidden and shown again moved every button and both sticks by 103 px (Messages stood under
    the controls, as the window lays it out on a 768 px high screen). Each of View › Messages, Plan, Map and
    Telemetry, hidden and shown again: nothing a pilot aims at moves."""
    first = window_factory(vehicle)
    first.addDockWidget(Qt.BottomDockWidgetArea, first.messagesDock)    # as a 1366×768 screen's window had it
    first.messagesDock.show()
    first.close()                                                         # its layout saved, as on quitting
    w = window_factory(vehicle)                                           # the next run, the same settings
    w.resize(*size)
    qtbot.waitUntil(lambda: (w.width(), w.height()) == size, timeout=3000)
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=10000)
    watch = Watch(w)
    docks = {"Messages": w.messagesDock, "Plan": w.plan.dock, "Map": w.mapDock, "Telemetry": w.telemetryDock}
    for name, dock in docks.items():
        action = dock.toggleViewAction()                                  # View › <name>
        for turn in ("off", "on") if action.isChecked() else ("on", "off"):
            action.trigger()
            watch.step(f"View › {name} {turn}")
    moved = [m for m in watch.moves if ": messages " not in m]          # a dock itself may come and go
    assert not moved, f"at {size[0]}×{size[1]}:\n" + "\n".join(moved)


@pytest.mark.parametrize("screen", ["1366x768", "1280x720"])
def test_no_control_moves_as_a_dock_is_hidden_or_shown_on_a_laptop_screen(screen):
    """The same on a real X server of a laptop's size, with a fresh profile: the layout such a screen gets (the
    offscreen test screen, 600 px high, never had Messages under the controls)."""
    if shutil.which("xvfb-run") is None:
        pytest.fail("xvfb-run is missing: scripts/bootstrap installs it (Debian's xvfb)")
    env = dict(os.environ, QT_QPA_PLATFORM="xcb")
    run = subprocess.run(["xvfb-run", "-a", "-s", f"-screen 0 {screen}x24", sys.executable,
                          os.path.join(os.path.dirname(__file__), "xvfb_docks.py")],
                         capture_output=True, text=True, timeout=90, env=env)
    lines = [json.loads(line) for line in run.stdout.splitlines() if line.startswith("{")]
    assert run.returncode == 0 and len(lines) == 9, run.stdout + run.stderr
    moved = [f"{line['step']}: {line['moved']}" for line in lines[1:] if line["moved"]]
    assert not moved, f"window {lines[0]['window']} on {screen}:\n" + "\n".join(moved)

