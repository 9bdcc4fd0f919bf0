"""Replaying a real ArduCopter recording in the window (issue 29, items 17-18): the seek bar goes where it is
clicked or dragged to, and the end of the recording is said as the end of a replay (with Restart), not as a lost
link."""
from __future__ import annotations

import pytest
from PyQt5.QtCore import QEvent, QPoint, QPointF, Qt
from PyQt5.QtGui import QMouseEvent
from PyQt5.QtWidgets import QApplication

from driver.vehicle.state import LinkStatus
from recordings import FLIGHT
from uavviewer.camera.hud import stale_text

from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def _mouse(widget, kind, x: float, buttons) -> None:
    pos = QPointF(x, widget.height() / 2)
    button = Qt.NoButton if kind == QEvent.MouseMove else Qt.LeftButton
    QApplication.sendEvent(widget, QMouseEvent(kind, pos, button, buttons, Qt.NoModifier))


@pytest.fixture
def replaying(qtbot, vehicle_factory, window_factory):
    replay = vehicle_factory(f"{FLIGHT}.tlog", tlog_path=None, replay_speed=8.0)
    replay.replay.pause()
    w = window_factory(replay)
    qtbot.waitUntil(lambda: replay.replay.duration > 0 and w.replayBar._duration > 0, timeout=10000)
    return w, replay.replay


def test_a_click_on_the_seek_bar_goes_where_it_was_clicked_and_a_drag_follows(qtbot, replaying):
    w, replay = replaying
    bar = w.replayBar.progress
    duration = replay.duration
    assert replay.position < 0.02 * duration
    qtbot.mouseClick(bar, Qt.LeftButton, pos=QPoint(int(bar.width() * 0.75), bar.height() // 2))
    qtbot.waitUntil(lambda: abs(replay.position - 0.75 * duration) < 0.05 * duration, timeout=5000)
    # a drag from a quarter to the middle: the time under the pointer where it is let go
    _mouse(bar, QEvent.MouseButtonPress, bar.width() * 0.25, Qt.LeftButton)
    for f in (0.3, 0.4, 0.5):
        _mouse(bar, QEvent.MouseMove, bar.width() * f, Qt.LeftButton)
    _mouse(bar, QEvent.MouseButtonRelease, bar.width() * 0.5, Qt.NoButton)
    qtbot.waitUntil(lambda: abs(replay.position - 0.5 * duration) < 0.05 * duration, timeout=5000)


def test_the_end_of_a_replay_is_said_as_such_with_restart(qtbot, replaying):
    w, replay = replaying
    replay.resume()
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=15000)
    w.replayBar.seek_to(replay.duration - 2.0)
    qtbot.waitUntil(lambda: replay.finished and w.adapter.state.link.status is LinkStatus.CLOSED, timeout=15000)
    qtbot.waitUntil(lambda: not w.replayBar.play_button.isEnabled(), timeout=5000)   # one Restart: beside it
    qtbot.waitUntil(lambda: w.statusStrip.link.text() == "Replay ended", timeout=5000)
    qtbot.waitUntil(lambda: w.attitude.values["flag"] == "REPLAY ENDED", timeout=5000)
    s = w.adapter.state
    shown = [w.statusStrip.link.text(), w.phaseLabel.text(), w.linkBanner.text(), stale_text(s),
             w.attitude.values["flag"], w.telemetry.stale_label.text()]
    assert not any("lost" in t.lower() or "NO LINK" in t for t in shown), shown
    assert w.phaseLabel.text().startswith("Replay ended") and "Restart" in w.linkBanner.text()
    assert stale_text(s).startswith("REPLAY ENDED")
    # Restart plays it again from the start
    qtbot.mouseClick(w.replayBar.restart_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: not replay.finished and w.adapter.state.link.status is LinkStatus.OK, timeout=10000)
    qtbot.waitUntil(lambda: w.replayBar.play_button.text() == "Pause", timeout=5000)
