"""Logs › Flight logs: the window lists the simulated vehicle's DataFlash logs, downloads one with its
progress, rate and time left shown and Open once saved (byte-identical to the vehicle's file), Cancel keeps a
.part that Resume finishes, armed the vehicle's own "Disarm for log download" is shown while Land stays at hand,
Erase all asks first, and a connection without logs says why. Real simulator, real sockets, real widgets."""
from __future__ import annotations

import os

import pytest
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QAction, QMenu, QMessageBox

from uavviewer.connect.opener import Disconnected
from uavviewer.logs.controller import NO_LOGS, NOT_CONNECTED, REPLAYED
from uavviewer.logs.rows import RowState, date_text, size_text

from ice_fixtures import drone_factory, eventually, server_factory  # noqa: F401  (fixtures)
from test_logs_download import logs_sim, same_bytes
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)
RECORDING = os.path.join(os.path.dirname(__file__), "data", "recordings", "arducopter-4.7-sitl-flight.tlog")
#: the vehicle's link: slow enough (one sim second a second) for a download to be watched under way
SLOW_LINK = dict(speedup=1.0, radio_baud=1_000_000)


def open_logs(qtbot, w, tmp_path):
    """Logs › Flight logs…, as the pilot picks it; the logs are saved in this test's logs folder."""
    w.connections.log_dir = str(tmp_path / "station-logs")
    menu = w.findChild(QMenu, "menuLogs")
    assert menu is not None and menu.title() == "&Logs"
    action = w.findChild(QAction, "actionFlightLogs")
    assert action in menu.actions()
    action.trigger()
    dialog = w.flight_logs.dialog
    qtbot.waitUntil(dialog.isVisible, timeout=3000)
    return dialog


def logs_window(qtbot, sim_factory, vehicle_factory, window_factory, tmp_path, sizes, **sim_config):
    sim, folder = logs_sim(sim_factory, tmp_path, sizes, **sim_config)
    v = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert v.wait_for(lambda s: s.connected, 10)
    w = window_factory(v, takeoff_altitude=3.0)
    dialog = open_logs(qtbot, w, tmp_path)
    qtbot.waitUntil(lambda: dialog.table.rowCount() == len(sizes), timeout=20000)
    return sim, v, w, dialog, folder


def row(dialog, log_id):
    return next(r for r in dialog.controller.rows if r.log_id == log_id)


def test_the_list_shows_number_date_and_size(qtbot, sim_factory, vehicle_factory, window_factory, tmp_path):
    _sim, _v, _w, dialog, folder = logs_window(qtbot, sim_factory, vehicle_factory, window_factory, tmp_path,
                                               [4_000, 9_000])
    table = dialog.table
    for number, size, stamp in folder.entries():
        assert table.text(number, 0) == str(number)
        assert table.text(number, 1) == date_text(stamp) != "no date"
        assert table.text(number, 2) == size_text(size)
        assert table.button(number).text() == "Download"
    assert dialog.status.text() == "2 logs on the vehicle"
    assert str(tmp_path / "station-logs") in dialog.folder.text()


def test_a_download_shows_its_progress_then_opens_byte_identical(qtbot, sim_factory, vehicle_factory,
                                                                window_factory, tmp_path):
    _sim, _v, w, dialog, folder = logs_window(qtbot, sim_factory, vehicle_factory, window_factory, tmp_path,
                                              [5_000, 400_000], **SLOW_LINK)
    table = dialog.table
    qtbot.mouseClick(table.button(2), Qt.LeftButton)
    assert table.button(2).text() == "Cancel"
    bar = table.bar(2)
    qtbot.waitUntil(lambda: 0 < bar.value() < 1000 and table.text(2, 4).endswith("/s") and bool(table.text(2, 5)),
                    timeout=30000)
    assert "%" in bar.format() and bar.format().endswith(f"of {size_text(os.path.getsize(folder.path(2)))}")
    assert w.flightControls.main_button.isEnabled()          # the window flies on: Take off is a click away
    qtbot.waitUntil(lambda: table.button(2).text() == "Open", timeout=60000)
    saved = os.path.join(str(tmp_path / "station-logs"), "00000002.BIN")
    assert same_bytes(saved, folder, 2)
    assert bar.value() == 1000 and table.text(2, 4) == "" and table.text(2, 5) == ""
    assert dialog.status.text().startswith(f"log 2 saved: {saved}")
    assert f"Flight log 2 saved: {saved}" in w.messages.texts()      # said where the pilot looks, window closed too
    with qtbot.waitSignal(w.review.opened, timeout=20000) as opened:
        qtbot.mouseClick(table.button(2), Qt.LeftButton)
    view = opened.args[0]
    assert view.isVisible()
    view.close()


def test_cancel_keeps_a_part_that_resume_finishes(qtbot, sim_factory, vehicle_factory, window_factory, tmp_path):
    _sim, v, w, dialog, folder = logs_window(qtbot, sim_factory, vehicle_factory, window_factory, tmp_path,
                                             [600_000], **SLOW_LINK)
    table = dialog.table
    dialog.table.selectRow(0)
    qtbot.mouseClick(dialog.download_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: row(dialog, 1).held > 60_000, timeout=30000)
    w.adapter.send(w.adapter.drone.set_mode, "LOITER")    # commands and their answers go on meanwhile
    qtbot.waitUntil(lambda: w.adapter.state.mode == "LOITER", timeout=10000)
    assert row(dialog, 1).state is RowState.DOWNLOADING
    qtbot.mouseClick(table.button(1), Qt.LeftButton)         # Cancel
    qtbot.waitUntil(lambda: table.button(1).text() == "Resume", timeout=10000)
    kept = row(dialog, 1).held
    saved = os.path.join(str(tmp_path / "station-logs"), "00000001.BIN")
    assert os.path.exists(saved + ".part") and os.path.exists(saved + ".part.json") and not os.path.exists(saved)
    assert kept > 60_000 and table.bar(1).format().startswith("cancelled: ")
    assert 0 < table.bar(1).value() < 1000
    qtbot.mouseClick(table.button(1), Qt.LeftButton)         # Resume
    qtbot.waitUntil(lambda: table.button(1).text() == "Open", timeout=60000)
    assert same_bytes(saved, folder, 1) and not os.path.exists(saved + ".part")


def test_armed_the_vehicle_refuses_in_its_own_words_and_land_stays_at_hand(qtbot, sim_factory, vehicle_factory,
                                                                         window_factory, tmp_path):
    _sim, v, w, dialog, _folder = logs_window(qtbot, sim_factory, vehicle_factory, window_factory, tmp_path,
                                              [5_000, 8_000])
    assert v.takeoff(3.0).result(60).ok
    qtbot.mouseClick(dialog.download_all_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: row(dialog, 1).state is RowState.FAILED, timeout=20000)
    assert "Disarm for log download" in dialog.table.bar(1).format()
    assert "Disarm for log download" in dialog.status.text()
    assert any(t.startswith("Flight log 1 not downloaded: Disarm for log download") for t in w.messages.texts())
    assert row(dialog, 2).state is RowState.ON_VEHICLE           # the next one is not asked to be refused again
    assert not dialog.controller.busy
    land = w.flightControls.main_button
    qtbot.waitUntil(lambda: land.text() == "Land" and land.isEnabled(), timeout=10000)
    qtbot.mouseClick(land, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.adapter.state.mode == "LAND", timeout=10000)


def test_erase_all_asks_first_then_empties_the_list(qtbot, sim_factory, vehicle_factory, window_factory,
                                                     tmp_path):
    _sim, _v, _w, dialog, folder = logs_window(qtbot, sim_factory, vehicle_factory, window_factory, tmp_path,
                                               [4_000, 6_000, 8_000])
    qtbot.mouseClick(dialog.erase_button, Qt.LeftButton)
    box = dialog.erase_box
    qtbot.waitUntil(box.isVisible, timeout=3000)
    assert "Erase all 3 logs" in box.text()
    qtbot.mouseClick(box.button(QMessageBox.Cancel), Qt.LeftButton)
    assert not dialog.controller.busy and dialog.table.rowCount() == 3 and folder.numbers() == [1, 2, 3]
    qtbot.mouseClick(dialog.erase_button, Qt.LeftButton)
    box = dialog.erase_box
    qtbot.waitUntil(box.isVisible, timeout=3000)
    qtbot.mouseClick(box.button(QMessageBox.Yes), Qt.LeftButton)
    qtbot.waitUntil(lambda: dialog.table.rowCount() == 0 and not dialog.controller.busy, timeout=20000)
    assert folder.numbers() == []
    assert dialog.status.text().startswith("logs erased on the vehicle; 0 there now")
    assert not dialog.erase_button.isEnabled() and not dialog.download_all_button.isEnabled()


@pytest.mark.parametrize("connection", ["replay", "ice"])
def test_a_connection_without_logs_says_why(qtbot, connection, sim_factory, vehicle_factory, window_factory,
                                             server_factory, drone_factory, tmp_path):  # noqa: F811
    if connection == "replay":
        drone, why = vehicle_factory(RECORDING, tlog_path=None), REPLAYED
    else:
        vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim_factory().tcp_port}")
        assert vehicle.wait_for(lambda s: s.connected, 10)
        drone, why = drone_factory(server_factory(vehicle)), NO_LOGS
    w = window_factory(drone)
    dialog = open_logs(qtbot, w, tmp_path)
    assert dialog.status.text() == why
    assert dialog.table.rowCount() == 0
    for button in (dialog.refresh_button, dialog.download_button, dialog.download_all_button, dialog.erase_button):
        assert not button.isEnabled()
    dialog.controller.refresh()                             # asked anyway: the same words, nothing breaks
    assert dialog.status.text() == why and not dialog.controller.busy


def test_leaving_the_vehicle_stops_its_download_resumable_and_clears_its_list(qtbot, sim_factory, vehicle_factory,
                                                                               window_factory, tmp_path):
    _sim, _v, w, dialog, _folder = logs_window(qtbot, sim_factory, vehicle_factory, window_factory, tmp_path,
                                               [600_000], **SLOW_LINK)
    qtbot.mouseClick(dialog.table.button(1), Qt.LeftButton)
    qtbot.waitUntil(lambda: row(dialog, 1).held > 30_000, timeout=30000)
    w.use_connection(Disconnected())                        # File › Disconnect (or another vehicle picked)
    qtbot.waitUntil(lambda: dialog.table.rowCount() == 0, timeout=5000)
    assert dialog.status.text() == NOT_CONNECTED and not dialog.controller.busy
    assert not dialog.refresh_button.isEnabled() and not dialog.download_all_button.isEnabled()
    saved = os.path.join(str(tmp_path / "station-logs"), "00000001.BIN")
    assert eventually(lambda: os.path.exists(saved + ".part.json") and not os.path.exists(saved), 10)
