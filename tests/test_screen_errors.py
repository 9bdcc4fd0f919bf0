"""Errors said where the pilot took the action: a plan file that cannot be read (corrupt JSON, an empty file) was
said only in Messages (behind the map at 1024×600), and after "Discard edits" the old plan stayed without a word; a
truncated .BIN opened in the review as if whole. Real window, real driver and simulated vehicle, real files.
"""
from __future__ import annotations

import pytest

from driver.mission.plan import PlanKind
from driver.review.writer import sample_flight

from test_mission_viewer_plan import click, planning_window
from test_plan_never_loses_work import answer
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)


@pytest.mark.parametrize("content", [b'{"fileType": "Plan", "mission": {"items": [', b""],
                                     ids=["corrupt JSON", "empty file"])
def test_a_plan_that_cannot_be_read_is_said_over_the_window_and_the_plan_stays(qtbot, vehicle, window_factory,
                                                                                  tmp_path, content):
    w, view, plan = planning_window(qtbot, vehicle, window_factory)
    for n, e in ((30, 0), (30, 30)):
        click(qtbot, view, n, e)                                    # edits, not saved
    edited = plan.doc.plan(PlanKind.MISSION)
    bad = tmp_path / "bad.plan"
    bad.write_bytes(content)
    plan.open_action.trigger()                                      # File › Open plan…
    answer(qtbot, lambda: plan.discard_question, "Discard edits")
    qtbot.waitUntil(lambda: plan.files.dialog is not None and plan.files.dialog.isVisible(), timeout=3000)
    plan.files.dialog.selectFile(str(bad))
    plan.files.dialog.accept()
    qtbot.waitUntil(lambda: getattr(plan.files, "error_box", None) is not None
                    and plan.files.error_box.isVisible(), timeout=3000)
    box = plan.files.error_box
    assert "bad.plan" in box.text() and "nothing was discarded" in box.text(), box.text()
    assert box.parentWidget() is w and plan.doc.plan(PlanKind.MISSION) == edited
    answer(qtbot, lambda: plan.files.error_box, "Close")
    assert plan.files.error_box is None


def test_a_truncated_bin_opens_with_a_warning(qtbot, vehicle, window_factory, tmp_path):
    w = window_factory(vehicle)
    whole = tmp_path / "flight.BIN"
    sample_flight(seconds=20, rate_hz=10).save(str(whole))
    data = whole.read_bytes()
    cut = tmp_path / "cut.BIN"
    cut.write_bytes(data[:len(data) // 2 + 7])                      # a record cut in half: the copy stopped there
    with qtbot.waitSignal(w.review.opened, timeout=20000) as opened:
        w.review.open(str(cut))
    view = opened.args[0]
    warning = getattr(view, "warning", None)
    assert warning is not None and warning.isVisible(), "the review opened a truncated log without a word"
    assert "cut short" in warning.text() and "skipped" in warning.text()
    view.close()
    with qtbot.waitSignal(w.review.opened, timeout=20000) as opened:
        w.review.open(str(whole))                                   # a whole log: no warning
    assert not opened.args[0].warning.isVisible()
    opened.args[0].close()
