"""The driver's replay controls on a real ArduCopter recording: seek, restart, and an end that closes the link."""
from __future__ import annotations

import pytest

from driver.vehicle.state import LinkStatus
from recordings import FLIGHT

pytestmark = pytest.mark.timeout(60)


def test_seek_to_the_end_closes_the_link_and_restart_opens_it(vehicle_factory):
    v = vehicle_factory(f"{FLIGHT}.tlog", tlog_path=None, replay_speed=8.0)
    replay = v.replay
    assert v.wait_for(lambda s: s.connected, 10)
    replay.seek(replay.duration - 2.0)
    assert replay.duration - 2.5 <= replay.position <= replay.duration
    s = v.wait_for(lambda s: s.link.status is LinkStatus.CLOSED, 10)      # no heartbeat is live after the end
    assert s is not None and replay.finished
    assert any(m.text == "Replay ended: the whole recording has been played" for m in s.messages)
    replay.restart()
    assert not replay.finished and replay.position < 1.0
    assert v.wait_for(lambda s: s.link.status is LinkStatus.OK, 10)        # its first heartbeat again
    replay.seek(-5.0)                                                      # clamped to the recording
    assert replay.position < 1.0
    replay.pause()
    replay.seek(30.0)
    assert replay.paused and 30.0 <= replay.position < 30.5                # a paused replay stays paused there
