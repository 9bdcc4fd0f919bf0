"""Issue 21, "Small things": each checked on the real window (or the real console and rules)."""
from __future__ import annotations

import io

import pytest
from PyQt5.QtCore import QPoint, Qt
from PyQt5.QtGui import QColor, QIcon
from PyQt5.QtWidgets import QApplication, QMessageBox

from driver.console.console import Console
from driver.vehicle.rules import TAKEOFF_ALTITUDE_RANGE, takeoff_altitude_problem
from driver.version import __version__
from uavviewer.input.keys_dialog import KeysDialog
from uavviewer.preferences.dialog import SettingsDialog
from uavviewer.flight.phase import NO_VEHICLE
from uavviewer.settings import ViewerSettings
from uavviewer.widgets.icons import DISABLED_COLOUR

from test_viewer_window import silent_vehicle  # noqa: F401  (fixture)
from viewer_fixtures import app_style, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


def test_help_keys_shows_its_last_row(qtbot, app_style, silent_vehicle, window_factory):
    w = window_factory(silent_vehicle)
    w.actionKeys.trigger()
    qtbot.waitUntil(lambda: any(isinstance(t, KeysDialog) and t.isVisible()
                                for t in QApplication.topLevelWidgets()), timeout=3000)
    dialog = next(t for t in QApplication.topLevelWidgets() if isinstance(t, KeysDialog))
    try:
        table = dialog.table
        free = dialog.screen().availableGeometry()
        assert free.contains(dialog.frameGeometry()) or dialog.height() <= free.height(), (dialog.geometry(), free)
        if table.verticalScrollBar().maximum() > 0:        # a screen too short for every row (offscreen: 600 px)
            assert dialog.height() >= free.height() - 160  # ... and only then: as tall as the screen allows
            table.scrollToBottom()
        last = table.visualItemRect(table.item(table.rowCount() - 1, 1))
        assert table.viewport().rect().contains(last), (last, table.viewport().rect())
    finally:
        dialog.reject()


def test_r_returns_to_launch_like_the_rtl_button(qtbot, sim, flying, window_factory):
    w = window_factory(flying)
    qtbot.waitUntil(lambda: w.flightControls.rtl_button.isEnabled(), timeout=20000)
    qtbot.keyClick(w, Qt.Key_R)
    qtbot.waitUntil(lambda: sim.truth().mode == "RTL", timeout=10000)


def test_about_shows_the_version(qtbot, silent_vehicle, window_factory):
    w = window_factory(silent_vehicle)
    w.actionAbout.trigger()
    box = w.findChild(QMessageBox, "aboutBox")
    qtbot.waitUntil(lambda: box is not None and box.isVisible(), timeout=3000)
    assert f"UavViewerPy {__version__}" in box.text() and "pymavlink" in box.text()
    box.close()


def test_one_wording_for_no_vehicle_yet(qtbot, silent_vehicle, window_factory):
    w = window_factory(silent_vehicle)
    qtbot.waitUntil(lambda: w.linkBanner.isVisible(), timeout=3000)
    assert w.phaseLabel.text() == NO_VEHICLE
    assert w.linkBanner.text().startswith(NO_VEHICLE)
    assert w.leftStick._hint == NO_VEHICLE and w.rightStick._hint == NO_VEHICLE
    qtbot.waitUntil(lambda: w.attitude.values["flag"] == NO_VEHICLE.upper(), timeout=3000)
    assert w.statusStrip.link.text() == NO_VEHICLE


def test_telemetry_is_titled_once(qtbot, silent_vehicle, window_factory):
    w = window_factory(silent_vehicle)
    from PyQt5.QtWidgets import QLabel
    titles = [label for label in w.telemetryDock.findChildren(QLabel)
              if label.isVisible() and label.text().upper() == "TELEMETRY"]
    assert titles == [] and w.telemetryDock.windowTitle() == "Telemetry"


def test_the_mode_list_is_not_clipped(qtbot, app_style, silent_vehicle, window_factory):
    w = window_factory(silent_vehicle)
    combo = w.modeSelector
    frame = combo.parentWidget()
    right = combo.mapTo(frame, QPoint(combo.width(), 0)).x()
    assert right <= frame.contentsRect().right() + 1
    for name in ("STABILIZE", "SMART_RTL", "POSHOLD"):         # the longest names fit beside the arrow
        assert combo.fontMetrics().horizontalAdvance(name) + 20 + 16 <= combo.width(), name


def test_disabled_buttons_grey_their_icons(qtbot, silent_vehicle, window_factory):
    w = window_factory(silent_vehicle)
    stop = w.flightControls.stop_button
    assert not stop.isEnabled()
    image = stop.icon().pixmap(20, 20, QIcon.Disabled).toImage()
    colours = [QColor(image.pixel(x, y)) for x in range(20) for y in range(20)
               if QColor.fromRgba(image.pixel(x, y)).alpha() > 200]
    assert colours and all(max(abs(c.red() - DISABLED_COLOUR.red()), abs(c.green() - DISABLED_COLOUR.green()),
                               abs(c.blue() - DISABLED_COLOUR.blue())) <= 3 for c in colours)


def test_disabled_map_controls_say_why(qtbot, silent_vehicle, window_factory):
    w = window_factory(silent_vehicle)
    panel = w.mapPanel
    assert not panel.downloadButton.isEnabled() and not panel.offlineCheck.isEnabled()
    assert panel.downloadButton.toolTip().startswith("Needs the Tiles layer")
    assert panel.offlineCheck.toolTip().startswith("Needs the Tiles layer")


def test_held_keys_move_the_on_screen_knobs(qtbot, sim, flying, window_factory):
    w = window_factory(flying)
    qtbot.waitUntil(lambda: w.leftStick.isEnabled(), timeout=20000)
    qtbot.keyPress(w, Qt.Key_W)                                # mode 2: forward is the right pad, up
    assert w.rightStick.shown_position == (0.0, 1.0) and w.rightStick.position == (0.0, 0.0)
    qtbot.keyPress(w, Qt.Key_Left)                             # yaw left: the left pad, left
    assert w.leftStick.shown_position == (-1.0, 0.0)
    qtbot.keyRelease(w, Qt.Key_W)
    qtbot.keyRelease(w, Qt.Key_Left)
    assert w.rightStick.shown_position == (0.0, 0.0) and w.leftStick.shown_position == (0.0, 0.0)


def test_deadband_and_expo_have_units_and_tooltips(qtbot):
    dialog = SettingsDialog(ViewerSettings(deadband=0.05, expo=0.3))
    qtbot.addWidget(dialog)
    assert dialog.deadband.suffix().strip() == "% of travel" and dialog.deadband.value() == 5
    assert dialog.expo.suffix().strip() == "%" and dialog.expo.value() == 30
    assert dialog.deadband.toolTip() and dialog.expo.toolTip()
    chosen = dialog.chosen()
    assert chosen.deadband == pytest.approx(0.05) and chosen.expo == pytest.approx(0.3)


def test_one_takeoff_altitude_range_for_window_and_console(qtbot):
    low, high = TAKEOFF_ALTITUDE_RANGE
    dialog = SettingsDialog(ViewerSettings())
    qtbot.addWidget(dialog)
    assert (dialog.takeoffAltitude.minimum(), dialog.takeoffAltitude.maximum()) == (low, high)
    assert takeoff_altitude_problem(low) is None and takeoff_altitude_problem(high) is None
    assert takeoff_altitude_problem(high + 1) == f"altitude must be {low:g} to {high:g} m"


def test_console_help_lists_no_undocumented_commands():
    out = io.StringIO()
    Console(object(), stdout=out, stdin=io.StringIO()).onecmd("help")
    assert "Undocumented" not in out.getvalue() and "EOF" not in out.getvalue()


def test_the_plots_have_a_time_unit_and_one_line_legends(qtbot, silent_vehicle, window_factory):
    w = window_factory(silent_vehicle)
    bottom = w.plots.plots[-1].getAxis("bottom")
    assert bottom.labelText == "time before now" and bottom.labelUnits == "s"
    for plot in w.plots.plots:
        assert plot.legend.columnCount == 3


def test_the_sim_is_named_not_its_socket(qtbot, sim, vehicle, window_factory):
    from uavviewer.app import sim_name
    w = window_factory(vehicle)
    assert "tcp:127.0.0.1" in w.windowTitle()                 # what the driver calls its link
    w.name_vehicle(sim_name(2.0))                              # what main.py --sim --speedup 2 does
    assert w.windowTitle() == "UavViewerPy — simulated ArduCopter (built in), 2× time"
    assert "tcp:" not in w.windowTitle()
