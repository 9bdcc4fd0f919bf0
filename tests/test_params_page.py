"""The Parameters page end to end: the real window on the real driver and simulated ArduCopter (docs/parameters.md).

Download with progress, search and groups, an edit reviewed and written (and confirmed by the vehicle's echo),
a write the vehicle never confirms, an out-of-bounds value that needs confirming, a .param file compared and
applied selectively, and Fix… on the FS_GCS_ENABLE warning.
"""
from __future__ import annotations

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QMessageBox

from driver.sim.faults import LinkFaults
from uavviewer.params.mentions import named_parameter
from uavviewer.params.table_model import Column, WriteState
from ice_fixtures import drone_factory, server_factory  # noqa: F401  (fixtures)
from lockstep_fixtures import lockstep_window  # noqa: F401  (fixtures)
from viewer_fixtures import viewer_settings, window, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)

DOWNLOAD_MS = 8000


@pytest.fixture(autouse=True)
def _first_connection(monkeypatch, tmp_path):
    """Every test meets its vehicle for the first time: no parameter table kept from another test."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))


def open_page(qtbot, w):
    """Vehicle › Parameters…, as the pilot opens it; returns the page once every parameter is in."""
    action = w.findChild(type(w.menuBar().actions()[0]), "actionParameters")
    action.trigger()
    page = w.params.page
    qtbot.waitUntil(lambda: page.isVisible(), timeout=3000)
    qtbot.waitUntil(lambda: w.params.model.table.complete, timeout=DOWNLOAD_MS)
    return page


def stage(qtbot, page, name: str, text: str) -> None:
    """Pick ``name`` in the table, type ``text`` in the editor and press Stage change."""
    assert page.select(name)
    page.editor.value.clear()
    qtbot.keyClicks(page.editor.value, text)
    qtbot.mouseClick(page.editor.stage_button, Qt.LeftButton)


def review_and_write(qtbot, w, page):
    qtbot.mouseClick(page.review_button, Qt.LeftButton)
    review = w.params.review
    assert review is not None and review.isVisible()
    qtbot.mouseClick(review.write_button, Qt.LeftButton)
    return review


def test_download_shows_progress_then_every_parameter(qtbot, lockstep_window):
    """In lockstep the window is shown each state of the download: over a socket a loaded machine's window
    polled once the list was in, and never showed it going."""
    steps = lockstep_window(downlink=LinkFaults(loss=0.1), radio_baud=460800)     # a real radio, lossy
    window = steps.window
    seen: list[str] = []
    window.adapter.stateChanged.connect(lambda _s: window.params.page is not None
                                        and seen.append(window.params.page.status.text()))
    page = open_page_in_lockstep(steps)
    steps.until(lambda: window.params.model.table.complete and not window.params.model.table.downloading, 60,
                "every parameter read")
    table = window.params.model.table
    assert table.expected == len(steps.autopilot.params.names) == window.params.model.rowCount() == 1392
    assert any(text.startswith("Downloading parameters") for text in seen), sorted(set(seen))
    assert page.status.text().startswith("1,392 parameters, all read"), page.status.text()
    assert not page.progress.isVisible()
    assert page.groups.item(0).text() == "All (1,392)"

    assert page.select("WPNAV_SPEED")
    seen.clear()
    qtbot.mouseClick(page.refresh_button, Qt.LeftButton)                   # everything again
    steps.until(lambda: any(t.startswith("Downloading") for t in seen), 5, "the download again")
    steps.until(lambda: page.status.text().startswith("1,392 parameters, all read"), 60, "every parameter again")
    assert page.current_name() == "WPNAV_SPEED"                          # the rows were not reset under the pilot


def test_search_groups_and_modified_only(qtbot, sim, window):
    page = open_page(qtbot, window)
    qtbot.keyClicks(page.search, "rtl alt")
    names = page.visible_names()
    assert "RTL_ALT" in names and "RTL_ALT_FINAL" in names
    assert all("RTL" in n and "ALT" in n for n in names)
    page.search.clear()
    page.pick_group("FENCE")
    names = page.visible_names()
    assert names == sorted(names) and names and all(n.startswith("FENCE_") for n in names)
    assert set(names) == {n for n in sim.autopilot.params.names if n.split("_")[0] == "FENCE"}
    page.pick_group("")
    page.modified_only.setChecked(True)
    assert page.visible_names() == []                  # nothing changed yet
    page.modified_only.setChecked(False)
    stage(qtbot, page, "WPNAV_SPEED", "750")
    page.modified_only.setChecked(True)
    assert page.visible_names() == ["WPNAV_SPEED"]     # a pending change counts as modified


def test_edit_review_write_and_see_it_confirmed(qtbot, sim, window):
    page = open_page(qtbot, window)
    model = window.params.model
    before = sim.autopilot.params["WPNAV_SPEED"]
    stage(qtbot, page, "WPNAV_SPEED", "800")
    stage(qtbot, page, "RTL_ALT", "2500")
    row = model.row_of("WPNAV_SPEED")
    assert model.index(row, Column.VALUE).data() == f"{before:g} → 800"
    assert model.index(row, Column.STATUS).data() == "pending"
    assert sim.autopilot.params["WPNAV_SPEED"] == before          # nothing written before the review
    assert page.pending_label.text().startswith("2 change(s) pending")

    review = review_and_write(qtbot, window, page)
    qtbot.waitUntil(lambda: review.result("WPNAV_SPEED") == WriteState.CONFIRMED.value
                    and review.result("RTL_ALT") == WriteState.CONFIRMED.value, timeout=15000)
    assert sim.autopilot.params["WPNAV_SPEED"] == 800 and sim.autopilot.params["RTL_ALT"] == 2500
    qtbot.waitUntil(lambda: model.index(row, Column.VALUE).data() == "800", timeout=3000)
    assert model.index(row, Column.STATUS).data() == WriteState.CONFIRMED.value
    assert model.modified("WPNAV_SPEED") and model.pending == {}
    assert not page.review_button.isEnabled()


def test_a_write_the_vehicle_never_echoes_is_not_confirmed(qtbot, sim, window, monkeypatch):
    from driver.params import setter
    monkeypatch.setattr(setter, "KNOWN_TRIES", 3)                  # the driver gives up after 3 s, not 10
    page = open_page(qtbot, window)
    stage(qtbot, page, "LAND_SPEED", "40")
    sim.faults.uplink.loss = 1.0              # the vehicle hears nothing more; its heartbeats still come
    review = review_and_write(qtbot, window, page)
    assert review.result("LAND_SPEED") == WriteState.WRITING.value
    qtbot.waitUntil(lambda: review.result("LAND_SPEED").startswith(WriteState.FAILED.value), timeout=30000)
    # not confirmed, said once, and why: no echo, and the reads by name that followed went unanswered too
    assert review.result("LAND_SPEED").startswith("not confirmed: no answer to 3 PARAM_SET and ")
    assert review.result("LAND_SPEED").count("not confirmed") == 1
    assert sim.autopilot.params["LAND_SPEED"] == 50
    model = window.params.model
    assert model.pending == {"LAND_SPEED": 40.0}                  # still pending: it may be written again
    assert model.index(model.row_of("LAND_SPEED"), Column.STATUS).data().startswith(WriteState.FAILED.value)


def test_a_value_the_type_cannot_hold_is_refused(qtbot, sim, window):
    page = open_page(qtbot, window)
    stage(qtbot, page, "FS_GCS_ENABLE", "300")                    # an int8
    assert "int8" in page.editor.error.text()
    stage(qtbot, page, "FS_GCS_ENABLE", "1.5")
    assert page.editor.error.text().startswith("Not staged")
    assert window.params.model.pending == {}


def test_fix_on_the_gcs_failsafe_warning_opens_the_parameter(qtbot, sim, window):
    messages = window.messages
    qtbot.waitUntil(lambda: any("FS_GCS_ENABLE=0" in t for t in messages.texts()), timeout=15000)
    row = next(i for i, t in enumerate(messages.texts()) if "FS_GCS_ENABLE=0" in t)
    fix = messages.fix_button(row)
    assert fix is not None and fix.text() == "Fix…"
    assert all(messages.fix_button(i) is None for i, t in enumerate(messages.texts()) if "_" not in t)
    qtbot.mouseClick(fix, Qt.LeftButton)
    page = window.params.page
    qtbot.waitUntil(lambda: page.isVisible() and page.current_name() == "FS_GCS_ENABLE", timeout=DOWNLOAD_MS)
    assert page.editor.name == "FS_GCS_ENABLE"
    stage(qtbot, page, "FS_GCS_ENABLE", "1")
    review = review_and_write(qtbot, window, page)
    qtbot.waitUntil(lambda: review.result("FS_GCS_ENABLE") == WriteState.CONFIRMED.value, timeout=15000)
    assert sim.autopilot.params["FS_GCS_ENABLE"] == 1


def row_in_sight(page, name: str) -> bool:
    """``name`` is the row picked and the table shows it whole."""
    table = page.table
    return page.current_name() == name and table.viewport().rect().contains(table.visualRect(table.currentIndex()))


def fix_gcs_failsafe(qtbot, window):
    messages = window.messages
    qtbot.waitUntil(lambda: any("FS_GCS_ENABLE=0" in t for t in messages.texts()), timeout=15000)
    row = next(i for i, t in enumerate(messages.texts()) if "FS_GCS_ENABLE=0" in t)
    qtbot.mouseClick(messages.fix_button(row), Qt.LeftButton)
    return window.params.page


def test_fix_before_the_list_is_read_shows_the_row_once_it_is(qtbot, sim, window):
    """Fix… as the vehicle connects: the driver has read FS_GCS_ENABLE alone, the page picks it among a few rows,
    then the whole list comes in around it; the row is in sight at the end (it was left at row 401 of 1,392, the
    table at its top)."""
    page = fix_gcs_failsafe(qtbot, window)
    assert not window.params.model.table.complete
    qtbot.waitUntil(lambda: window.params.model.table.complete, timeout=DOWNLOAD_MS)
    qtbot.waitUntil(lambda: row_in_sight(page, "FS_GCS_ENABLE"), timeout=3000)


def test_messages_naming_parameters():
    assert named_parameter("GCS failsafe is off on the vehicle (FS_GCS_ENABLE=0): if") == "FS_GCS_ENABLE"
    assert named_parameter("Fence breached: above FENCE_ALT_MAX; (FENCE_ACTION: RTL or land)") == "FENCE_ALT_MAX"
    assert named_parameter("FENCE_STATUS from the vehicle") == ""          # a MAVLink message
    assert named_parameter("Mode GUIDED_NOGPS refused") == ""                # a flight mode
    assert named_parameter("PreArm: Check FS_THR_VALUE", {"RTL_ALT"}, complete=True) == ""
    assert named_parameter("PreArm: Check FS_THR_VALUE", {"FS_THR_VALUE"}, complete=True) == "FS_THR_VALUE"


def test_out_of_bounds_needs_explicit_confirmation(qtbot, sim, window):
    page = open_page(qtbot, window)
    controller = window.params
    qtbot.waitUntil(lambda: controller.model.meta("RTL_ALT") is not None, timeout=10000)   # the shipped metadata
    meta = controller.model.meta("RTL_ALT")
    assert page.select("RTL_ALT") and meta.units in page.editor.facts.text()
    assert meta.description and page.editor.description.text() == meta.description
    assert not page.editor.reboot.isVisible() and not page.editor.warning.isVisible()
    assert page.select("FRAME_CLASS") and page.editor.reboot.isVisible()            # RebootRequired in the metadata
    assert page.select("FS_OPTIONS") and page.editor.bits.isVisible() and not page.editor.choices.isVisible()
    assert page.editor.value.text() == "16"
    page.editor.bits.item(0).setCheckState(Qt.Checked)                              # bit 0 ticked: 16 + 1
    assert page.editor.value.text() == "17"

    stage(qtbot, page, "RTL_ALT", "1000000000")                   # what the recorded vehicle stored unchecked
    qtbot.waitUntil(lambda: controller.question is not None and controller.question.isVisible(), timeout=3000)
    box = controller.question
    assert "outside" in box.text() and box.defaultButton() is box.button(QMessageBox.Cancel)
    box.button(QMessageBox.Cancel).click()
    qtbot.waitUntil(lambda: controller.question is None, timeout=3000)
    assert controller.model.pending == {}                         # cancelled: nothing staged

    stage(qtbot, page, "RTL_ALT", "1000000000")
    qtbot.waitUntil(lambda: controller.question is not None and controller.question.isVisible(), timeout=3000)
    controller.question.button(QMessageBox.Yes).click()
    qtbot.waitUntil(lambda: controller.model.pending == {"RTL_ALT": 1e9}, timeout=3000)
    review = review_and_write(qtbot, window, page)
    assert "confirmed" in review.table.item(0, 3).text()
    qtbot.waitUntil(lambda: review.result("RTL_ALT") == WriteState.CONFIRMED.value, timeout=15000)
    assert sim.autopilot.params["RTL_ALT"] == 1000000000


def test_save_a_file_then_compare_it_and_apply_selectively(qtbot, sim, window, tmp_path):
    page = open_page(qtbot, window)
    controller = window.params
    saved = str(tmp_path / "solo.param")
    qtbot.mouseClick(page.save_button, Qt.LeftButton)
    dialog = page.file_dialog
    dialog.selectFile(saved)
    dialog.accept()
    lines = open(saved).read().splitlines()
    assert len(lines) == 1392 and lines[0].split() == ["ACRO_BAL_PITCH", "1"]

    edited = str(tmp_path / "tuned.param")
    text = open(saved).read()
    for name, value in (("WPNAV_SPEED", "1200"), ("LOIT_SPEED", "900"), ("RTL_ALT", "1000000000")):
        text = "\n".join(f"{name},{value}" if line.split()[0] == name else line for line in text.splitlines())
    open(edited, "w").write(text + "\nNOT_A_PARAM,5\nthis line is not a parameter\n")
    qtbot.mouseClick(page.compare_button, Qt.LeftButton)
    page.file_dialog.selectFile(edited)
    page.file_dialog.accept()
    compare = controller.compare
    assert compare is not None and compare.isVisible()
    assert compare.names() == ["LOIT_SPEED", "NOT_A_PARAM", "RTL_ALT", "WPNAV_SPEED"]
    summary = compare.summary.text()                               # 3 counters MAVProxy never loads are left out
    assert "1386 the same" in summary and "not a parameter" in summary and "FORMAT_VERSION" in summary
    assert "on the vehicle only" not in summary
    assert "NOT_A_PARAM" not in compare.ticked()                   # the vehicle has none: it cannot be applied
    compare.set_ticked("LOIT_SPEED", False)
    compare.set_ticked("RTL_ALT", False)
    assert compare.apply_button.text() == "Stage 1 for review"
    qtbot.mouseClick(compare.apply_button, Qt.LeftButton)

    qtbot.waitUntil(lambda: controller.review is not None and controller.review.isVisible(), timeout=3000)
    assert controller.model.pending == {"WPNAV_SPEED": 1200.0}
    review = controller.review
    qtbot.mouseClick(review.write_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: review.result("WPNAV_SPEED") == WriteState.CONFIRMED.value, timeout=15000)
    assert sim.autopilot.params["WPNAV_SPEED"] == 1200
    assert sim.autopilot.params["LOIT_SPEED"] != 900 and sim.autopilot.params["RTL_ALT"] != 1000000000


def test_another_vehicle_gets_none_of_the_changes_staged_for_the_first(qtbot, sim, sim_factory, vehicle_factory,
                                                                       window):
    page = open_page(qtbot, window)
    stage(qtbot, page, "WPNAV_SPEED", "900")
    assert window.params.model.pending == {"WPNAV_SPEED": 900.0}
    other_sim = sim_factory(system_id=2)
    other = vehicle_factory(f"tcp:127.0.0.1:{other_sim.tcp_port}")
    assert other.wait_for(lambda s: s.connected, 10)
    window.adapter.use(other)                                       # as the fleet does when the pilot picks it
    qtbot.waitUntil(lambda: window.params.model.pending == {} and not page.review_button.isEnabled(), timeout=3000)
    qtbot.waitUntil(lambda: window.params.model.table.complete, timeout=DOWNLOAD_MS)   # its own list, read anew
    assert page.select("WPNAV_SPEED") and page.editor.value.text() == "1000"


def open_page_in_lockstep(steps):
    """Vehicle › Parameters… on a window in lockstep; the page, before the download has gone anywhere."""
    w = steps.window
    w.findChild(type(w.menuBar().actions()[0]), "actionParameters").trigger()
    steps.until(lambda: w.params.page is not None and w.params.page.isVisible(), 1, "the page shown")
    return w.params.page


def test_download_over_a_lossy_radio_shows_how_far_it_is_and_ends_complete(lockstep_window):
    """In lockstep the window is shown every state the driver publishes: on a loaded machine too it sees the
    download going, which over a socket it only did when it happened to poll in time."""
    steps = lockstep_window(seed=7, downlink=LinkFaults(loss=0.3))
    w = steps.window
    seen: list[str] = []
    w.adapter.stateChanged.connect(lambda _s: w.params.page is not None and seen.append(w.params.page.status.text()))
    page = open_page_in_lockstep(steps)
    steps.until(lambda: w.params.model.table.complete and not w.params.model.table.downloading, 60,
                "every parameter read")
    assert w.params.model.rowCount() == 1392
    # the driver's own progress (the list's count and re-asks, or MAVLink FTP's bytes read again), as it goes
    assert any(text.startswith("Downloading parameters") and " of " in text for text in seen), sorted(set(seen))
    assert page.status.text().startswith("1,392 parameters, all read"), page.status.text()


def test_a_reconnect_shows_the_kept_table_at_once_then_reads_it_again(lockstep_window, window_factory):
    steps = lockstep_window(downlink=LinkFaults(loss=0.2))
    open_page_in_lockstep(steps)
    steps.until(lambda: steps.window.params.model.table.complete and not steps.vehicle.state().parameters.downloading,
                60, "every parameter read")
    steps.window.quit_without_asking()
    steps.autopilot.params["WPNAV_SPEED"] = 1100                  # changed while we were away
    again = steps.lockstep.reconnect()
    steps.until(lambda: again.state().connected and again.state().firmware, 10, "the firmware heard")
    w = steps.window = window_factory(again)                        # the cache is per system id and firmware
    w.adapter.stop()
    seen: list[str] = []
    w.adapter.stateChanged.connect(lambda _s: w.params.page is not None and seen.append(w.params.page.status.text()))
    page = open_page_in_lockstep(steps)
    steps.until(lambda: w.params.model.table.complete and not w.params.model.table.downloading, 60,
                "the list read again")
    assert any(t.startswith("1,392 parameters shown, reading them again") for t in seen), sorted(set(seen))
    assert page.select("WPNAV_SPEED") and page.editor.value.text() == "1100"
    steps.until(lambda: any("changed since" in t and "WPNAV_SPEED" in t for t in w.messages.texts()), 3,
                "the change named")                               # the driver names it once the list is read


def test_the_page_over_ice(qtbot, sim, vehicle, window_factory, server_factory, drone_factory):
    """The same page on a remote vehicle: the list, the metadata and a confirmed write through the Ice server."""
    w = window_factory(drone_factory(server_factory(vehicle)))
    page = open_page(qtbot, w)
    assert w.params.model.rowCount() == 1392
    qtbot.waitUntil(lambda: w.params.model.meta("WPNAV_SPEED") is not None, timeout=10000)
    stage(qtbot, page, "WPNAV_SPEED", "650")
    review = review_and_write(qtbot, w, page)
    qtbot.waitUntil(lambda: review.result("WPNAV_SPEED") == WriteState.CONFIRMED.value, timeout=15000)
    assert sim.autopilot.params["WPNAV_SPEED"] == 650


def test_fix_on_a_go_to_refused_by_the_fence_opens_its_parameter(qtbot, sim_factory, vehicle_factory,
                                                                 window_factory):
    sim = sim_factory()
    sim.autopilot.params["FENCE_ENABLE"] = 1                        # the vehicle's ceiling at 50 m
    sim.autopilot.params["FENCE_ALT_MAX"] = 50
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.fence.ceiling == 50, 15)
    w = window_factory(vehicle)
    w.adapter.send(w.adapter.drone.go_to, 10.0, 0.0, 60.0)    # what the map's Fly here sends
    messages = w.messages
    qtbot.waitUntil(lambda: any("FENCE_ALT_MAX" in t for t in messages.texts()), timeout=5000)
    row = next(i for i, t in enumerate(messages.texts()) if "FENCE_ALT_MAX" in t)
    assert "rejected" in messages.texts()[row]
    qtbot.mouseClick(messages.fix_button(row), Qt.LeftButton)
    page = w.params.page
    qtbot.waitUntil(lambda: page.isVisible() and page.current_name() == "FENCE_ALT_MAX", timeout=DOWNLOAD_MS)
    assert page.editor.value.text() == "50"


def test_an_ftp_read_that_stalls_says_why_the_list_is_read_instead(qtbot, lockstep_window):
    """The vehicle offers MAVLink FTP, then goes silent on it after ten packets: the page's progress says FTP
    stalled and the list is read instead, the messages say so too, and the table still ends complete. In
    lockstep: the window is shown each state of it, however quick the list is read."""
    sent = []
    steps = lockstep_window(driver={"param_ftp": True})
    autopilot = steps.autopilot
    send = autopilot._ftp_send
    autopilot._ftp_send = lambda reply: sent.append(reply) or len(sent) > 10 or send(reply)
    w = steps.window
    seen: list[str] = []
    w.adapter.stateChanged.connect(lambda _s: w.params.page is not None and seen.append(w.params.page.status.text()))
    page = open_page_in_lockstep(steps)
    steps.until(lambda: page.status.text().startswith("1,392 parameters, all read"), 60, "every parameter read")
    assert len(sent) > 10
    assert any("MAVLink FTP stalled at byte" in t and "reading the list instead" in t for t in seen), sorted(set(seen))
    steps.until(lambda: any("Parameters: MAVLink FTP stalled" in t for t in w.messages.texts()), 3, "the message")
