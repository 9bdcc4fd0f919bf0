"""A recorded flight replayed through the window moves the instruments; the replay bar controls it."""
from __future__ import annotations

import pytest
from PyQt5.QtCore import Qt

from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def test_replay_moves_the_instruments(qtbot, sim, tmp_path, vehicle_factory, window_factory):
    tlog = tmp_path / "recorded.tlog"
    live = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", tlog_path=str(tlog))
    assert live.wait_for(lambda s: s.connected, 10)
    assert live.takeoff(3.0).result(timeout=60).ok
    live.close()                                         # flushes the recording
    assert tlog.stat().st_size > 1000

    replay = vehicle_factory(str(tlog), tlog_path=None, replay_speed=1.0)
    assert replay.replay is not None
    replay.replay.pause()                                # held at the start until the window listens: on a busy
    w = window_factory(replay)                           # machine the window may open after the ground phase
    assert w.replayBar.isVisible()
    assert not w.flightControls.main_button.isEnabled() and not w.rightStick.isEnabled()   # nothing to fly
    shown = []                                           # altitudes the instrument displayed, in order
    w.adapter.stateChanged.connect(lambda s: shown.append(w.attitude.values["altitude"]))
    replay.replay.resume()
    qtbot.waitUntil(lambda: (w.attitude.values["altitude"] or 0.0) > 2.0, timeout=30000)
    assert w.attitude.values["valid"]
    assert min(a for a in shown if a is not None) < 0.5          # it started on the ground...
    # ...and climbed with the recording (the panel refreshes on its own timer: wait for it too)
    qtbot.waitUntil(lambda: float(w.telemetry.text("altitude").split()[0]) > 2.0, timeout=5000)
    assert w.plots.sample_count > 5
    assert "/" in w.replayBar.clock.text() and "--:--" not in w.replayBar.clock.text()

    qtbot.mouseClick(w.replayBar.play_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: replay.replay.paused and w.replayBar.play_button.text() == "Play", timeout=3000)
    w.replayBar.speedRequested.emit(2.0)
    assert replay.replay.speed == 2.0
