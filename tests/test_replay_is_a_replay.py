"""A replay is plainly a replay: a flight recorded by this program (a head-on aircraft, the vehicle's GCS failsafe
off) played back in the window raises no live-only alert (no traffic banner, no "no GCS failsafe"), offers no Fix…
for a vehicle that is not there, says "Replay" where a live link says "Link OK", keeps the vehicle camera's buttons
off, logs no lost link when the pilot seeks, and has one Restart at the end."""
from __future__ import annotations

import pytest
from PyQt5.QtCore import Qt

from driver.vehicle.state import LinkStatus
from uavviewer.alerts.model import LIVE_ONLY

from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)


@pytest.fixture
def recorded(sim, vehicle_factory, tmp_path) -> str:
    """A .tlog this program wrote while an aircraft came head on and the vehicle's FS_GCS_ENABLE was 0."""
    path = str(tmp_path / "recorded.tlog")
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}", tlog_path=path)
    assert v.wait_for(lambda s: s.position is not None and s.home is not None and s.readiness.prearm_ok, 30)
    ground = sim.autopilot.home_alt
    sim.autopilot.add_aircraft(4242, north=2500.0, east=0.0, alt=ground + 50.0, heading=180.0, speed=60.0)
    s = v.wait_for(lambda s: s.traffic.alerts and s.gcs_failsafe == 0, 30)
    assert s is not None
    assert v.wait_for(lambda st: st.boot.seconds > s.boot.seconds + 40, 30)     # 40 s more of the flight
    v.close()
    return path


def test_a_replay_raises_no_live_alert_and_offers_no_live_action(qtbot, recorded, vehicle_factory, window_factory):
    drone = vehicle_factory(recorded, tlog_path=None, replay_speed=4.0)
    replay = drone.replay
    w = window_factory(drone)
    alerts = []
    w.alerts.alerted.connect(alerts.append)
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=15000)
    qtbot.waitUntil(lambda: bool(w.adapter.state.traffic.alerts), timeout=30000)         # the aircraft came head on
    qtbot.waitUntil(lambda: any("GCS failsafe is off" in t for t in w.messages.texts()), timeout=15000)
    qtbot.waitUntil(lambda: w.statusStrip.link.text() == "Replay · recorded, not live", timeout=5000)
    assert not [a.text for a in alerts if a.kind in LIVE_ONLY]
    assert "Traffic" not in (w.alert_banner.text if w.alert_banner.isVisible() else "")
    rows = [i for i, t in enumerate(w.messages.texts()) if "GCS failsafe is off" in t or "FS_" in t]
    assert rows and all(w.messages.fix_button(i) is None for i in rows)             # nothing to fix on a recording
    bar = w.gimbal_bar
    assert not any(b.isEnabled() for b in (bar.level_button, bar.down_button, bar.photo_button, bar.record_button))

    lost_before = w.adapter.state.link.lost_count
    replay.pause()
    if replay.position + 8.0 > replay.duration:              # a loaded machine played on while the window caught up
        replay.seek(replay.duration - 8.0)
    at = replay.position + 6.0                               # 6 s on: more than the loss timeout (3.5 s) at once
    assert at + 2.0 <= replay.duration and at > 6.0
    received = w.adapter.state.link.packets_received
    replay.seek(at)
    replay.resume()
    # read on from there (connected or, on a loaded machine, already at the end: the replay's 2 s are 0.5 s here)
    qtbot.waitUntil(lambda: replay.position > at + 1.5 and w.adapter.state.link.packets_received > received + 10,
                    timeout=15000)
    replay.pause()
    qtbot.waitUntil(lambda: w.adapter.state is drone.state(), timeout=5000)      # the window shows the newest
    s = w.adapter.state
    assert s.connected or s.link.replay_ended
    assert s.link.lost_count == lost_before and not any(t.startswith("Link lost") for t in w.messages.texts())
    assert not [a for a in alerts if a.kind in LIVE_ONLY]
    replay.resume()

    replay.seek(replay.duration - 1.0)
    qtbot.waitUntil(lambda: replay.finished and w.adapter.state.link.status is LinkStatus.CLOSED, timeout=15000)
    qtbot.waitUntil(lambda: not w.replayBar.play_button.isEnabled(), timeout=5000)
    assert w.replayBar.play_button.text() == "Play"                        # one Restart: the button beside it
    assert w.replayBar.restart_button.text() == "Restart" and w.replayBar.restart_button.isEnabled()
    qtbot.mouseClick(w.replayBar.restart_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.replayBar.play_button.isEnabled() and w.replayBar.play_button.text() == "Pause",
                    timeout=10000)
