"""Issue 21, problem 7: states that lied. Record with a broken camera says nothing was recorded (and leaves no
file); the quit-in-flight question says what the vehicle will do in its mode; the Gamepad page without a
controller shows no bars that look like a reading; a camera that never delivered a frame is retried less and
less often.

(The replay's "telemetry still shows a live heartbeat" is the pilot branch's, with the replay controls.)
"""
from __future__ import annotations

import pytest
from PyQt5.QtWidgets import QProgressBar

from driver.camera.source import SourceFailed, VideoSource
from uavviewer.input.gamepad_page import GamepadPage

from test_viewer_window import silent_vehicle  # noqa: F401  (fixture)
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def test_record_with_a_broken_camera_says_nothing_was_recorded(qtbot, silent_vehicle, window_factory, tmp_path):
    w = window_factory(silent_vehicle, cameras=[str(tmp_path / "no-such-video.mp4")])
    w.camera.folder = str(tmp_path / "media")
    qtbot.waitUntil(lambda: w.camera.source.status().state in ("retrying", "ended"), timeout=10000)
    assert w.camera.set_recording(True)
    w.camera.set_recording(False)
    note = w.camera_panel.note.text()
    assert note.startswith("Nothing recorded") and "Recorded" not in note and "0 frames" not in note
    assert not list((tmp_path / "media").glob("*.mp4"))


def test_the_quit_question_says_what_the_vehicle_does_in_its_mode(qtbot, sim, flying, window_factory):
    w = window_factory(flying)
    assert flying.set_mode("LOITER").result(timeout=10).ok
    qtbot.waitUntil(lambda: w.adapter.state.mode == "LOITER" and w.adapter.state.gcs_failsafe is not None,
                    timeout=10000)
    w.close()
    qtbot.waitUntil(lambda: w.closing.quit_box is not None and w.closing.quit_box.isVisible(), timeout=3000)
    text = w.closing.quit_box.text()
    assert "holds position in LOITER" in text and "GUIDED" not in text
    assert "GCS failsafe is off" in text                    # the simulated vehicle's FS_GCS_ENABLE is 0
    w.closing.quit_box.reject()
    qtbot.waitUntil(lambda: w.closing.quit_box is None, timeout=3000)


def test_the_gamepad_page_without_a_controller_shows_no_readings(qtbot, silent_vehicle, window_factory):
    w = window_factory(silent_vehicle)
    w.preferences.edit()
    dialog = w.preferences.dialog
    page = dialog.findChild(GamepadPage)
    dialog.pages.setCurrentWidget(page)
    qtbot.waitUntil(page.isVisible, timeout=3000)
    assert page.pad is None and "No controller" in page.padInfo.text()
    shown = [bar for bar in page.findChildren(QProgressBar) if bar.isVisible()]
    assert shown == [], [bar.text() for bar in shown]
    dialog.reject()


class NeverOpens(VideoSource):
    """An unsupported source: it never opens. Tiny delays so the test sees several retries quickly."""
    retry_initial, retry_max, retry_max_unheard = 0.001, 0.004, 0.2

    def _open(self):
        raise SourceFailed("unsupported")

    def _read(self):
        return None

    def _release(self):
        pass


def test_a_source_that_never_delivered_backs_off_further(qtbot):
    source = NeverOpens("bogus://camera").start()
    try:
        qtbot.waitUntil(lambda: "retrying in 0.2 s" in source.status().reason, timeout=10000)
    finally:
        source.close()
