"""The camera panel with real video: colours and order as painted, streams, failures, snapshot, record, HUD."""
from __future__ import annotations

import math
import os
import threading

import cv2
import numpy as np
import pytest
from PyQt5.QtCore import QRectF
from PyQt5.QtGui import QColor, QImage, QPainter

from camera_media import COLOURS, UdpSender, frames_and_rate, free_udp_port, write_clip, write_ts
from test_camera_sources import rate_of
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)
from driver.vehicle.state import Attitude, Battery, LocalPosition, VehicleState, Velocity
from driver.camera import VideoRecorder
from uavviewer.camera import controller as camera_controller
from uavviewer.camera.controller import CameraController
from uavviewer.camera.panel import CameraPanel
from uavviewer.camera.view import BACKGROUND
from uavviewer.camera.hud import HUD_COLOUR, paint_hud, text_rows

HOVER = VehicleState(attitude=Attitude(roll=math.radians(10)), local=LocalPosition(0, 0, -4), altitude=4.0,
                     mode="GUIDED")


def nearest(rgb):
    return min(COLOURS, key=lambda c: sum((a - b) ** 2 for a, b in zip(rgb, c)))


def painted_rgb(view, x=None, y=None):
    """The colour actually painted in the widget at (x, y) (default: its centre)."""
    img = view.grab().toImage()
    c = QColor(img.pixel(view.width() // 2 if x is None else x, view.height() // 2 if y is None else y))
    return (c.red(), c.green(), c.blue())


@pytest.fixture
def camera(qtbot, tmp_path):
    """``camera(uris, **options)`` -> (panel, controller) shown on screen, closed afterwards."""
    made = []

    def make(uris, **options):
        panel = CameraPanel()
        qtbot.addWidget(panel)
        panel.resize(640, 520)
        panel.show()
        options.setdefault("folder", str(tmp_path / "media"))
        controller = CameraController(panel, uris, **options)
        made.append(controller)
        return panel, controller

    yield make
    for c in made:
        c.close()
        if c.source is not None:
            c.source.close(wait=3)


def test_file_colours_reach_the_screen_in_order(qtbot, camera, tmp_path):
    """Each picture painted has its own frame's colour (red painted red: no channel swap), in the clip's order.
    A file is paced at its frame rate and the view shows only the newest picture, so a starved window skips some:
    the verdict is on the pictures it painted, each against the colour of its own frame number."""
    repeat = 12
    clip = write_clip(str(tmp_path / "colours.mp4"), repeat=repeat, fps=30)
    panel, controller = camera([clip])
    view = panel.view
    view.set_hud_visible(False)
    painted = []                                     # (frame number, the colour painted)

    def record_colour():
        frame = view.frame()
        if frame is not None:
            rgb = painted_rgb(view)                  # the widget painted again now, with this frame
            c = nearest(rgb)
            assert all(abs(a - b) <= 40 for a, b in zip(rgb, c)), f"painted {rgb} is no clip colour"
            if not painted or painted[-1][0] != frame.index:
                painted.append((frame.index, c))
        return controller.source.status().state == "ended"

    qtbot.waitUntil(record_colour, timeout=10000)
    assert painted
    assert [i for i, _ in painted] == sorted(i for i, _ in painted)              # in order
    wrong = [(i, c) for i, c in painted if c != COLOURS[(i - 1) // repeat]]
    assert not wrong, f"frames painted in another colour than their own: {wrong}"
    qtbot.waitUntil(lambda: view.message().startswith("No video: end of file"), timeout=2000)


def test_picture_keeps_its_aspect_ratio(qtbot, camera, tmp_path):
    clip = write_clip(str(tmp_path / "red.mp4"), COLOURS[:1], repeat=300)
    panel, controller = camera([clip])
    view = panel.view
    view.set_hud_visible(False)
    panel.resize(900, 300)
    qtbot.waitUntil(lambda: view.frame() is not None and view.height() < 300, timeout=5000)
    rect = view.video_rect()
    assert rect.width() / rect.height() == pytest.approx(320 / 240, rel=0.01)
    assert rect.height() == pytest.approx(view.height(), abs=1)
    assert painted_rgb(view, 5) == BACKGROUND.getRgb()[:3]                    # bars beside the picture
    assert nearest(painted_rgb(view)) == (255, 0, 0)


def test_udp_mpegts_stream_is_shown(qtbot, camera, tmp_path):
    data = write_ts(str(tmp_path / "s.ts"))
    port = free_udp_port()
    with UdpSender(data, port):
        panel, controller = camera([f"udp://127.0.0.1:{port}"], timeout_ms=2000)
        qtbot.waitUntil(lambda: panel.view.frame() is not None, timeout=8000)
        panel.view.set_hud_visible(False)
        rgb = painted_rgb(panel.view)
        controller.source.close(wait=3)
    assert any(all(abs(a - b) <= 40 for a, b in zip(rgb, c)) for c in COLOURS)
    assert panel.view.frame().width == 320


def test_dead_source_shows_why_and_recovers(qtbot, camera, tmp_path):
    data = write_ts(str(tmp_path / "s.ts"))
    port = free_udp_port()
    panel, controller = camera([f"udp://127.0.0.1:{port}"], timeout_ms=600)
    view = panel.view
    qtbot.waitUntil(lambda: view.message().startswith("No video: "), timeout=5000)
    assert "retrying" in view.message()
    with UdpSender(data, port):
        qtbot.waitUntil(lambda: view.frame() is not None and view.message() == "", timeout=10000)
        controller.source.close(wait=3)


def test_stalled_stream_shows_why_without_the_hud_then_recovers(qtbot, camera, tmp_path):
    """A camera that goes quiet (the capture still waiting in its read) is not shown as a frozen
    live picture: the view says why, without picture or HUD, and shows video again when it resumes."""
    data = write_ts(str(tmp_path / "s.ts"))
    port = free_udp_port()
    with UdpSender(data, port) as sender:
        panel, controller = camera([f"udp://127.0.0.1:{port}"], state_fn=lambda: HOVER, timeout_ms=30000,
                                   stall_s=0.5)
        view = panel.view
        qtbot.waitUntil(lambda: view.frame() is not None and hud_pixels(view) > 200, timeout=8000)
        sender.pause()
        qtbot.waitUntil(lambda: view.message().startswith("No video: no frame for "), timeout=5000)
        assert view.frame() is None and hud_pixels(view) == 0
        sender.resume()
        qtbot.waitUntil(lambda: view.frame() is not None and view.message() == "", timeout=8000)
        controller.source.close(wait=3)                   # while frames still come: the read returns


def hud_pixels(view):
    """How many pixels of the view are painted in the HUD's colour."""
    img = view.grab().toImage()
    arr = np.frombuffer(img.convertToFormat(img.Format_RGB888).constBits().asstring(img.width() * img.height() * 3),
                        np.uint8)
    arr = arr.reshape(img.height(), img.width(), 3)
    return int(np.count_nonzero(np.all(arr == HUD_COLOUR.getRgb()[:3], axis=2)))


def test_stats_line_counts_what_is_painted(qtbot, camera, tmp_path):
    clip = write_clip(str(tmp_path / "c.mp4"), COLOURS, repeat=40)
    panel, controller = camera([clip])
    qtbot.waitUntil(lambda: controller.stats()["fps"] >= 5, timeout=5000)
    s = controller.stats()
    assert s["resolution"] == (320, 240)
    assert 0 <= s["latency_median"] <= s["latency_p95"]
    qtbot.waitUntil(lambda: "fps · 320×240" in panel.view._stats, timeout=2000)


class KeepingRecorder(VideoRecorder):
    """The controller's recorder, remembering each frame handed to it until it is stopped; its queue has room
    for the whole test, so a slow encoder on a loaded machine drops none."""

    def __init__(self, path, fps=None):
        super().__init__(path, fps, max_queue=10_000)
        self.frames = []
        self._gate = threading.Lock()
        self._taking = True

    def push(self, frame):
        with self._gate:                  # a frame is remembered exactly when it is queued before the end
            if not self._taking:
                return
            if not self.frames or frame.index != self.frames[-1].index:
                self.frames.append(frame)
            super().push(frame)

    def stop(self, wait=5.0):
        with self._gate:
            self._taking = False
        return super().stop(wait)


def test_snapshot_and_recording_write_readable_files(qtbot, camera, tmp_path, monkeypatch):
    monkeypatch.setattr(camera_controller, "VideoRecorder", KeepingRecorder)
    clip = write_clip(str(tmp_path / "c.mp4"), COLOURS[:3], repeat=10, fps=15)
    panel, controller = camera([clip + "?loop=1"])
    qtbot.waitUntil(lambda: panel.view.frame() is not None, timeout=5000)
    with qtbot.waitSignal(controller.snapshotSaved) as saved:
        panel.snapshot_button.click()
    img = cv2.imread(saved.args[0])
    assert img is not None and img.shape == (240, 320, 3) and saved.args[0].endswith(".png")
    assert nearest(tuple(int(v) for v in img[120, 160][::-1])) in COLOURS[:3]

    with qtbot.waitSignal(controller.recordingChanged) as started:
        panel.record_button.click()
    assert started.args[0] is True and panel.record_button.isChecked()
    recorder = controller._recorder
    assert isinstance(recorder, KeepingRecorder)
    qtbot.waitUntil(lambda: recorder.frames_written >= 15, timeout=5000)
    qtbot.waitUntil(lambda: panel.view._recording.startswith("REC "), timeout=2000)
    with qtbot.waitSignal(controller.recordingChanged) as stopped:
        panel.record_button.click()
    path = stopped.args[1]
    assert stopped.args[0] is False and os.path.basename(path).startswith("video-")
    n, fps = frames_and_rate(path)
    assert recorder.frames_dropped == 0
    assert n == recorder.frames_written == len(recorder.frames) >= 15   # every frame the camera delivered to it
    assert fps == pytest.approx(rate_of(recorder.frames), abs=1e-3)   # plays at the rate they came at


def test_recording_that_fails_on_its_thread_says_so(qtbot, camera, tmp_path):
    """The encoder opens the file only once it knows the frame rate; if it cannot then (the media
    folder has gone), REC goes away and the pilot is told, without pressing anything."""
    import shutil
    clip = write_clip(str(tmp_path / "c.mp4"), COLOURS[:3], repeat=20)
    panel, controller = camera([clip + "?loop=1"], folder=str(tmp_path / "gone"))
    qtbot.waitUntil(lambda: panel.view.frame() is not None, timeout=5000)
    panel.record_button.click()
    assert controller.recording
    shutil.rmtree(tmp_path / "gone")
    with qtbot.waitSignal(controller.failed, timeout=5000) as failed:
        pass
    assert failed.args[0].startswith("Cannot record: ") and panel.note.text() == failed.args[0]
    assert not controller.recording and not panel.record_button.isChecked() and panel.view._recording == ""


def test_snapshot_without_video_says_so(qtbot, camera, tmp_path):
    panel, controller = camera([str(tmp_path / "none.mp4")])
    with qtbot.waitSignal(controller.failed) as failed:
        controller.snapshot()
    assert "no video" in failed.args[0]


def test_hud_toggles_over_the_video(qtbot, camera):
    panel, controller = camera(["sim"], state_fn=lambda: HOVER)
    view = panel.view
    qtbot.waitUntil(lambda: view.frame() is not None, timeout=5000)
    assert hud_pixels(view) > 200
    panel.hud_button.click()
    assert not view.hud_visible()
    assert hud_pixels(view) == 0


def hud_image(state, size=(448, 336)):
    """The HUD alone, painted over black, as an array (rows, columns, R G B)."""
    img = QImage(size[0], size[1], QImage.Format_RGB888)
    img.fill(QColor(0, 0, 0))
    p = QPainter(img)
    paint_hud(p, QRectF(0, 0, *size), state)
    p.end()
    return np.frombuffer(img.constBits().asstring(img.bytesPerLine() * img.height()), np.uint8) \
        .reshape(img.height(), img.bytesPerLine())[:, :size[0] * 3].reshape(size[1], size[0], 3)


def in_rows(rows, shape):
    """A mask of the pixels whose centres lie in any of ``rows`` (QRectF)."""
    ys, xs = np.mgrid[0:shape[0], 0:shape[1]] + 0.5
    mask = np.zeros(shape[:2], bool)
    for r in rows:
        mask |= (xs >= r.left()) & (xs <= r.right()) & (ys >= r.top()) & (ys <= r.bottom())
    return mask


def test_hud_text_stays_clear_of_horizon_ladder_and_roll_scale(qtbot):
    """The heading tape and the readouts look the same whatever the attitude: no rung, horizon line or
    roll pointer crosses them (and the rows do hold all the text)."""
    rows = text_rows(QRectF(0, 0, 448, 336))
    base = dict(local=LocalPosition(0, 0, -3), altitude=3.0, mode="GUIDED", armed=True, heading_deg=175.0,
                velocity=Velocity(north=1.5), battery=Battery(voltage=16.1, remaining=99))
    level = hud_image(VehicleState(**base))
    mask = in_rows(rows, level.shape)
    other = dict(base, altitude=123.4, mode="LOITER", armed=False, heading_deg=20.0,
                 velocity=Velocity(north=12.5, down=3.2), battery=Battery(voltage=11.0, remaining=5))
    changed = np.any(hud_image(VehicleState(**other)) != level, axis=2)
    assert changed.any() and not (changed & ~mask).any(), "text drawn outside text_rows"
    for roll in (-25, 0, 25):
        for pitch in (-15, -8, 0, 8, 15):
            tilted = hud_image(VehicleState(attitude=Attitude(roll=math.radians(roll), pitch=math.radians(pitch)),
                                            **base))
            crossed = np.any(tilted != level, axis=2) & mask
            assert not crossed.any(), f"roll {roll}°, pitch {pitch}°: {np.argwhere(crossed)[:3].tolist()} (row, col)"


def test_switch_moves_to_the_next_source(qtbot, camera, tmp_path):
    red = write_clip(str(tmp_path / "red.mp4"), [(255, 0, 0)], repeat=300)
    blue = write_clip(str(tmp_path / "blue.mp4"), [(0, 0, 255)], repeat=300)
    panel, controller = camera([red, blue])
    panel.view.set_hud_visible(False)
    assert panel.switch_button.isEnabled()
    qtbot.waitUntil(lambda: panel.view.frame() is not None and nearest(painted_rgb(panel.view)) == (255, 0, 0),
                    timeout=5000)
    with qtbot.waitSignal(controller.sourceChanged):
        panel.switch_button.click()
    qtbot.waitUntil(lambda: panel.view.frame() is not None and nearest(painted_rgb(panel.view)) == (0, 0, 255),
                    timeout=5000)


def test_simulated_camera_follows_the_simulated_vehicle(qtbot, camera, flying):
    """--sim: the picture comes from the simulated vehicle, and its horizon tilts as it rolls."""
    from test_camera_sources import horizon_rows
    panel, controller = camera(["sim"], state_fn=flying.state)
    assert flying.point_gimbal(0).result(10).ok              # the mount starts straight down (RC, as recorded)
    qtbot.waitUntil(lambda: flying.state().gimbal.pitch_deg == 0.0, timeout=5000)
    qtbot.waitUntil(lambda: panel.view.frame() is not None, timeout=5000)
    left, right = horizon_rows(controller.source.latest().image)
    assert abs(left - right) <= 3                           # hovering level

    def rolled():
        flying.set_velocity(0.0, 2.0, 0.0, 0.0)             # fly right: the copter rolls right
        s = flying.state()
        frame = controller.source.latest()
        if s.attitude.roll < math.radians(5) or frame is None:
            return False
        l, r = horizon_rows(frame.image)
        return l - r > 10                                    # the horizon rises on the right

    qtbot.waitUntil(rolled, timeout=15000)
    flying.set_velocity(0.0, 0.0, 0.0, 0.0)


def test_main_window_shows_the_simulated_camera(qtbot, vehicle, window_factory):
    """``main.py --sim``: the camera area of the window shows the simulated vehicle's camera with the HUD."""
    w = window_factory(vehicle, cameras=["sim"])
    assert w.instrumentSplitter.indexOf(w.camera_panel) >= 0 and w.camera_panel.isVisible()
    qtbot.waitUntil(lambda: w.camera_view.frame() is not None and w.camera_view.width() > 100, timeout=5000)
    assert w.camera_view.frame().image.shape == (480, 640, 3)
    assert w.camera_view.hud_visible()


def test_main_window_without_camera_says_how_to_get_one(qtbot, vehicle, window_factory):
    w = window_factory(vehicle)
    assert w.camera_view.message().startswith("No video: no camera configured")
    assert not w.camera_panel.switch_button.isEnabled()


@pytest.mark.parametrize("size", [(156, 117), (220, 165), (448, 336)], ids=["1024x600", "1280x720", "roomy"])
def test_no_hud_text_overlaps_another_on_a_small_video(qtbot, size):
    """At 1024×600 the video is 156 px wide: the mode, the heading and the battery overlapped on the top row."""
    from PyQt5.QtGui import QFont, QFontMetricsF
    from uavviewer.camera.hud import hud_font, hud_labels
    rect = QRectF(0, 0, *size)
    state = VehicleState(local=LocalPosition(0, 0, -3), altitude=123.4, mode="GUIDED_NOGPS", armed=True,
                         heading_deg=355.0, velocity=Velocity(north=12.5, down=3.2),
                         battery=Battery(voltage=16.1, remaining=100))
    font = hud_font(QFont(), rect)
    fm = QFontMetricsF(font)
    inked = [(label.text, fm.boundingRect(label.rect, label.flags, label.text)) for label in hud_labels(rect, state, font)]
    overlaps = [f"{a} {ra} / {b} {rb}" for i, (a, ra) in enumerate(inked) for b, rb in inked[i + 1:]
                if ra.intersects(rb)]
    outside = [f"{t} {r}" for t, r in inked if not rect.contains(r)]
    assert not overlaps and not outside, "\n".join(overlaps + outside)
