"""The window's words (issue 29, items 19-21) in the real window on the real driver and simulated vehicle: one
wording for Disconnect, one log line per gesture, repeated lines counted, and the small things."""
from __future__ import annotations

import pytest
from PyQt5.QtCore import QPoint, QPointF, Qt
from PyQt5.QtGui import QWheelEvent
from PyQt5.QtWidgets import QApplication

from driver.vehicle.state import LinkStatus, Severity

from lockstep_fixtures import lockstep_window  # noqa: F401  (fixtures)
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)


def test_disconnect_is_said_one_way(qtbot, vehicle, window_factory):
    w = window_factory(vehicle)
    w.connections.adopt(vehicle)
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=10000)
    w.actionDisconnect.trigger()
    qtbot.waitUntil(lambda: w.adapter.drone is not vehicle, timeout=5000)
    qtbot.waitUntil(lambda: w.statusStrip.link.text() == "Not connected", timeout=5000)
    qtbot.waitUntil(lambda: w.attitude.values["flag"] == "NOT CONNECTED", timeout=5000)
    shown = {"banner": w.linkBanner.text(), "phase": w.phaseLabel.text(), "strip": w.statusStrip.link.text(),
             "flag": w.attitude.values["flag"], "title": w.window_name(), "status bar": w.link_status.text(),
             "heartbeat": w.telemetry.text("heartbeat"), "sticks": w.leftStick._hint}
    for where, text in shown.items():
        assert "Not connected" in text or "NOT CONNECTED" in text or text == "none (not connected)", (where, text)
        for other in ("no vehicle", "link lost", "link closed", "no link", "disconnected"):
            assert other not in text.lower(), (where, text)
    w.connections.close()


def wheel_notch(view, notches: int = 1) -> None:
    centre = QPointF(view.width() / 2, view.height() / 2)
    QApplication.sendEvent(view, QWheelEvent(centre, view.mapToGlobal(centre.toPoint()), QPoint(0, 0),
                                             QPoint(0, 120 * notches), Qt.NoButton, Qt.NoModifier,
                                             Qt.NoScrollPhase, False))


def test_a_wheel_gesture_is_one_line_and_repeats_are_counted(qtbot, vehicle, window_factory):
    w = window_factory(vehicle)
    qtbot.waitUntil(lambda: w.adapter.state.gimbal.pitch_deg is not None, timeout=10000)
    w.gimbal_bar.level_button.click()
    # level to the float's last digits: the wheel tilts from the reported pitch, and "gimbal pitch -20°" is
    # written with :g, so a gesture started at -0.3° would say -20.3°
    qtbot.waitUntil(lambda: abs(w.adapter.state.gimbal.pitch_deg) < 1e-4, timeout=10000)
    qtbot.waitUntil(lambda: w.gimbal._target is None, timeout=5000)
    before = len([r for r in vehicle.state().results if r.command.startswith("gimbal pitch")])
    for _ in range(4):                                   # a wheel turned four notches: four events, four commands
        wheel_notch(w.camera_view, -1)
    qtbot.waitUntil(lambda: len([r for r in w.adapter.state.results if r.command.startswith("gimbal pitch")])
                    == before + 4, timeout=10000)
    qtbot.waitUntil(lambda: any("gimbal pitch -20°" in t for t in w.messages.texts()), timeout=5000)
    gimbal_lines = [t for t in w.messages.texts() if t.startswith("gimbal pitch")]
    # the gesture is one line, its last angle (Level's line before it, unless it came moments before)
    assert gimbal_lines[-1].startswith("gimbal pitch -20°") and len(gimbal_lines) <= 2, gimbal_lines
    assert not any(f"gimbal pitch -{a}°" in t for t in gimbal_lines for a in (5, 10, 15)), gimbal_lines
    # the same line three times in a row: one line, counted
    for _ in range(3):
        w.log_message("Camera not found: sim", Severity.WARNING)
    assert w.messages.texts()[-1] == "Camera not found: sim (×3)"
    assert sum(t.startswith("Camera not found: sim") for t in w.messages.texts()) == 1


def test_time_left_is_shown_only_in_the_air(qtbot, vehicle, window_factory):
    w = window_factory(vehicle, takeoff_altitude=3.0)
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=10000)
    assert vehicle.takeoff(3.0).result(timeout=60).ok
    qtbot.waitUntil(lambda: " left" in w.statusStrip.battery.text(), timeout=10000)     # flying: time left
    assert vehicle.land().result(timeout=60).ok
    qtbot.waitUntil(lambda: not w.adapter.state.armed, timeout=60000)
    s = w.adapter.state
    qtbot.waitUntil(lambda: bool(w.adapter.state.battery.consumed_mah), timeout=5000)
    qtbot.waitUntil(lambda: "mAh" in w.statusStrip.battery.text(), timeout=5000)
    assert " left" not in w.statusStrip.battery.text(), (w.statusStrip.battery.text(), s.battery)


def test_the_flight_timer_goes_on_over_a_reconnection_in_the_air(qtbot, sim, vehicle_factory, window_factory):
    url = f"tcp:127.0.0.1:{sim.tcp_port}"
    first = vehicle_factory(url)
    w = window_factory(first, takeoff_altitude=3.0)
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=10000)
    assert first.takeoff(3.0).result(timeout=60).ok
    qtbot.waitUntil(lambda: w.flight_timer.seconds > 2.0, timeout=20000)
    flown = w.flight_timer.seconds
    again = vehicle_factory(url)                         # the same vehicle, connected again (File › Connect)
    assert again.wait_for(lambda s: s.connected and s.armed, 10)
    w.use_connection(again)
    qtbot.waitUntil(lambda: w.adapter.state.armed and w.flight_timer.started, timeout=10000)
    assert w.flight_timer.seconds >= flown               # the flight it left, not a new one from zero


def test_stop_looking_goes_back_to_the_pitch_before(qtbot, lockstep_window):
    """In lockstep the window is shown each state: the pitch it remembers is the one before the point was looked
    at (over a socket, a starved window first saw the vehicle already turning, with no point reported yet)."""
    steps = lockstep_window()
    w = steps.window
    steps.until(lambda: w.adapter.state.gimbal.pitch_deg is not None and w.adapter.state.home is not None, 10,
                "the gimbal and home")
    w.gimbal_bar.level_button.click()
    steps.until(lambda: abs(w.adapter.state.gimbal.pitch_deg) < 0.6, 10, "level")
    steps.until(lambda: w.gimbal._target is None, 5, "level reached")
    for _ in range(8):                                   # the wheel: 40° down
        wheel_notch(w.camera_view, -1)
    steps.until(lambda: abs(w.adapter.state.gimbal.pitch_deg + 40) < 0.6, 10, "40° down")
    steps.until(lambda: w.gimbal._target is None, 5, "40° down reached")
    home = w.adapter.state.home
    from driver.core.frames import offset_latlon
    lat, lon = offset_latlon(home.lat, home.lon, 30.0, 0.0)
    w.adapter.send(w.adapter.drone.look_at, lat, lon, 0.0)    # the map's "Look here"
    steps.until(lambda: w.adapter.state.gimbal.roi is not None and w.gimbal_bar.stop_looking_button.isVisible(),
                10, "looking at the point")
    steps.until(lambda: abs(w.adapter.state.gimbal.pitch_deg + 40) > 20, 10, "turned to it")   # it looks there
    qtbot.mouseClick(w.gimbal_bar.stop_looking_button, Qt.LeftButton)
    steps.until(lambda: w.adapter.state.gimbal.roi is None, 10, "no point")
    steps.until(lambda: abs(w.adapter.state.gimbal.pitch_deg + 40) < 0.6, 10, "back at 40° down")   # not -90


def test_file_open_logs_folder_and_about(qtbot, vehicle, window_factory, tmp_path):
    w = window_factory(vehicle)
    w.connections.log_dir = str(tmp_path / "logs")
    opened = []
    w.logs.open_url = lambda url: opened.append(url.toLocalFile()) or True
    action = next(a for a in w.menuFile.actions() if a.text().replace("&", "") == "Open logs folder")
    action.trigger()
    assert opened == [str(tmp_path / "logs")] and (tmp_path / "logs").is_dir()
    w.actionAbout.trigger()
    from PyQt5.QtWidgets import QMessageBox
    box = w.findChild(QMessageBox, "aboutBox")
    qtbot.waitUntil(lambda: box is not None and box.isVisible(), timeout=3000)
    assert f"Flight logs: {tmp_path / 'logs'}" in box.text()
    box.close()


def test_file_names_reviewing_a_log_and_replaying_a_flight_apart(qtbot, vehicle, window_factory):
    """"Open log…" (a review) and "Open flight log…" (a replay) read alike: a pilot picked one for the other."""
    w = window_factory(vehicle)
    texts = {a.objectName(): a.text().replace("&", "") for a in w.menuFile.actions()}
    review, replay = texts["actionReviewLog"], texts["actionReplayFlight"]
    assert review.startswith("Review") and "plots" in review
    assert replay.startswith("Replay") and ".tlog" in replay
    assert not any(t.startswith("Open") and "log…" in t for t in texts.values())    # no two "Open … log…" left
    actions = [a.objectName() for a in w.menuFile.actions()]
    assert abs(actions.index("actionReviewLog") - actions.index("actionReplayFlight")) <= 2   # side by side
