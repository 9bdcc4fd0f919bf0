"""The review's Geotag photos… dialog (issue 31): opened from a reviewed log, it runs off the window's thread and
shows the report; a log without camera events says why."""
from __future__ import annotations

import threading

import pytest
from PyQt5.QtCore import Qt

from driver.review import open_log
from driver.review.geotag import GeotagReport, geotag
from patience import patient
from test_geotag import CAMERA_AHEAD, assert_tagged, cam_rows, shoot, write_log
from uavviewer.review import geotag_dialog
from uavviewer.review.view import ReviewWindow


def review(qtbot, path) -> ReviewWindow:
    view = ReviewWindow(open_log(path))
    qtbot.addWidget(view)
    view.show()
    qtbot.waitExposed(view)
    return view


def test_geotag_from_the_review_view(qtbot, tmp_path, monkeypatch):
    # the real geotag, held on its worker until the window has been looked at: on a loaded machine it was done
    # before the click returned, and the button was already back
    release = threading.Event()

    def held(*args, **kwargs):
        release.wait(patient(30))
        return geotag(*args, **kwargs)

    monkeypatch.setattr(geotag_dialog, "geotag", held)
    rows = cam_rows(5)
    view = review(qtbot, write_log(tmp_path, rows))
    photos = tmp_path / "photos"
    names = shoot(photos, rows[:4] + cam_rows(7)[5:7])      # 6 photos: the last two have no event
    qtbot.mouseClick(view.geotag_button, Qt.LeftButton)
    dialog = view.geotag_dialog
    assert dialog is not None and dialog.isVisible()
    dialog.folder.setText(str(photos))
    assert dialog.output.placeholderText() == str(photos / "geotagged")
    dialog.offset.setValue(CAMERA_AHEAD)
    with qtbot.waitSignal(dialog.finished_run, timeout=30_000) as done:
        qtbot.mouseClick(dialog.run_button, Qt.LeftButton)
        assert not dialog.run_button.isEnabled()          # the run is on the worker: the window is not held
        release.set()
    report = done.args[0]
    assert isinstance(report, GeotagReport) and len(report.tagged) == 4
    assert dialog.run_button.isEnabled()
    assert dialog.status.text() == "4 photos tagged from CAM events; 2 photos untagged, 1 event without a photo"
    text = dialog.report.toPlainText()
    assert f"untagged {names[4]}: more photos than events" not in text      # photo 5 meets event 5, off in time
    assert f"untagged {names[4]}: time mismatch" in text
    assert f"untagged {names[5]}: more photos than events (6 photos, 5 CAM events)" in text
    assert "CAM 5 (image 5" in text
    for name, row in zip(names[:4], rows):
        assert_tagged(photos / "geotagged" / name, row)


@pytest.mark.parametrize("in_place", [False, True])
def test_the_dialog_writes_where_it_is_told(qtbot, tmp_path, in_place):
    rows = cam_rows(2)
    view = review(qtbot, write_log(tmp_path, rows))
    photos = tmp_path / "photos"
    names = shoot(photos, rows)
    dialog = view.open_geotag()
    dialog.folder.setText(str(photos))
    dialog.output.setText(str(tmp_path / "tagged"))
    dialog.in_place.setChecked(in_place)
    assert dialog.output.isEnabled() is not in_place
    dialog.offset.setValue(CAMERA_AHEAD)
    with qtbot.waitSignal(dialog.finished_run, timeout=30_000) as done:
        dialog.run()
    assert len(done.args[0].tagged) == 2
    for name, row in zip(names, rows):
        assert_tagged((photos if in_place else tmp_path / "tagged") / name, row)


def test_a_log_without_camera_events_says_why(qtbot, tmp_path):
    view = review(qtbot, write_log(tmp_path, cam_rows(2), with_cam=False))
    photos = tmp_path / "photos"
    shoot(photos, cam_rows(2))
    dialog = view.open_geotag()
    dialog.run()
    assert "choose the folder" in dialog.status.text() and dialog.future is None
    dialog.folder.setText(str(photos))
    with qtbot.waitSignal(dialog.finished_run, timeout=30_000) as done:
        dialog.run()
    assert "no CAM or TRIG records in this log" in done.args[0]
    assert "no CAM or TRIG records" in dialog.status.text() and dialog.run_button.isEnabled()
    assert not (photos / "geotagged").exists()
    view.close()
