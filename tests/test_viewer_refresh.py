"""The window's display clock: views redraw at the rate the eye needs, and nothing is painted or decoded while
the window is minimised (uavviewer/refresh.py)."""
from __future__ import annotations

from dataclasses import replace

from PyQt5.QtCore import QEvent, QObject
from PyQt5.QtWidgets import QApplication, QWidget

from uavviewer.refresh import Refresh

from viewer_fixtures import viewer_settings, window_factory  # noqa: F401


class Paints(QObject):
    """Counts the paint events a widget gets."""

    def __init__(self, widget: QWidget) -> None:
        super().__init__(widget)
        self.count = 0
        widget.installEventFilter(self)

    def eventFilter(self, watched, event) -> bool:  # noqa: N802
        if event.type() == QEvent.Paint:
            self.count += 1
        return False


def test_many_marks_make_one_redraw_per_period(qtbot):
    widget = QWidget()
    qtbot.addWidget(widget)
    refresh = Refresh(widget)
    runs = []
    channel = refresh.add(5.0, lambda: runs.append(1))
    channel.mark()
    qtbot.waitUntil(lambda: len(runs) == 1, timeout=3000)
    for _ in range(50):                       # a burst of snapshots within one period
        channel.mark()
    assert len(runs) == 1 and channel.pending  # deferred to the end of the period, not run per snapshot
    qtbot.waitUntil(lambda: len(runs) == 2, timeout=3000)
    assert not channel.pending and not channel._timer.isActive()    # the burst made one redraw, no more due


def test_minimised_window_paints_nothing_and_stops_the_video(qtbot, vehicle, window_factory):
    w = window_factory(vehicle, cameras=["sim"])
    frames = []
    w.camera_view.framePainted.connect(lambda index, latency: frames.append(index))
    snapshots = []
    w.adapter.stateChanged.connect(snapshots.append)
    attitude = Paints(w.attitude)
    readouts = w.readouts
    qtbot.waitUntil(lambda: len(frames) >= 3 and readouts.instruments_channel.runs > 0 and readouts.text_channel.runs > 0,
                    timeout=10000)

    w.showMinimized()
    qtbot.waitUntil(lambda: not w.refresh.shown, timeout=3000)
    source = w.camera.source
    assert w.camera._cameras.suspended
    qtbot.waitUntil(lambda: source.closed, timeout=3000)          # nothing captured or decoded
    QApplication.sendPostedEvents()           # a paint asked before the window went down may still be queued:
    QApplication.processEvents()              # let it happen before counting (on a loaded machine it came late)
    painted, paints = len(frames), attitude.count
    runs = (w.readouts.instruments_channel.runs, w.readouts.text_channel.runs, w.readouts.plots_channel.runs)
    seen = len(snapshots)
    qtbot.waitUntil(lambda: len(snapshots) >= seen + 10, timeout=10000)   # the vehicle goes on reporting
    assert len(frames) == painted and attitude.count == paints
    assert (w.readouts.instruments_channel.runs, w.readouts.text_channel.runs, w.readouts.plots_channel.runs) == runs
    assert w.readouts.instruments_channel.pending and w.readouts.text_channel.pending   # kept for when the pilot looks again
    assert not w.flight_timer.started
    w.show_state(replace(w.adapter.state, armed=True))             # an arm while minimised is not missed
    assert w.flight_timer.started

    w.showNormal()
    qtbot.waitUntil(lambda: w.refresh.shown, timeout=3000)
    qtbot.waitUntil(lambda: w.readouts.instruments_channel.runs > runs[0] and w.readouts.text_channel.runs > runs[1],
                    timeout=3000)
    assert not w.camera._cameras.suspended and w.camera.source is not source
    qtbot.waitUntil(lambda: len(frames) > painted, timeout=10000)  # the video opened again and is painted


def test_a_recording_keeps_capturing_while_minimised(qtbot, vehicle, window_factory, tmp_path):
    w = window_factory(vehicle, cameras=["sim"])
    w.camera.folder = str(tmp_path)
    qtbot.waitUntil(lambda: w.camera.source.status().frames > 0, timeout=10000)
    assert w.camera.set_recording(True)
    w.showMinimized()
    qtbot.waitUntil(lambda: not w.refresh.shown, timeout=3000)
    assert not w.camera._cameras.suspended
    captured = w.camera.source.status().frames
    qtbot.waitUntil(lambda: w.camera.source.status().frames > captured + 5, timeout=10000)
    w.camera.set_recording(False)                                  # nobody watches, nothing records: stop
    assert w.camera._cameras.suspended
