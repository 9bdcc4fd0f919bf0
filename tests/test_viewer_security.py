"""Only the pilot flies it: the window shows the link's protection (signing, datagrams from strangers),
Preferences sets signing up, and Disarm in the air is an emergency motor stop, asked first.

Real simulator (signing as ArduPilot does it), real driver, real window; waits are on conditions.
"""
from __future__ import annotations

import pytest
from PyQt5.QtCore import QPoint, QRect, Qt, QTimer
from PyQt5.QtWidgets import QDialogButtonBox, QLineEdit, QMessageBox

from driver.link.signing import SigningConfig, key_from_passphrase, write_key_file
from driver.vehicle.state import LinkHealth, LinkStatus, Signing, SigningStatus, VehicleState
from uavviewer.preferences.dialog import SettingsDialog
from uavviewer.connect.security import signing_warning
from uavviewer.settings import load_settings
from uavviewer.connect.link_banner import LinkBanner
from uavviewer.telemetry.panel import DIM, GOOD, NORMAL, WARN, TelemetryPanel

from ice_fixtures import drone_factory, server_factory  # noqa: F401  (fixtures)
from test_driver_pinned_link import Spoofer
from test_driver_solo import free_udp_port
from test_viewer_safety import sent_commands, wait_flying
from viewer_fixtures import pick_mode, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)

PASSPHRASE = "only the pilot flies it"
KEY = key_from_passphrase(PASSPHRASE)


def signing_driver(vehicle_factory, connection: str, **kw):
    """The driver with no key yet, keeping its signing timestamps nowhere (never in the user's home)."""
    return vehicle_factory(connection, signing=SigningConfig(timestamp_path=None), **kw)


def open_link_security(qtbot, w) -> SettingsDialog:
    w.actionPreferences.trigger()
    qtbot.waitUntil(lambda: w.preferences.dialog is not None and w.preferences.dialog.isVisible(), timeout=3000)
    dialog = w.preferences.dialog
    dialog.pages.setCurrentWidget(dialog.signingPage)
    return dialog


def ask_setup(qtbot, dialog) -> QMessageBox:
    qtbot.mouseClick(dialog.setupSigning, Qt.LeftButton)
    qtbot.waitUntil(lambda: dialog.setup_box is not None and dialog.setup_box.isVisible(), timeout=3000)
    return dialog.setup_box


def saved_text(qsettings) -> str:
    qsettings.sync()
    with open(qsettings.fileName(), encoding="utf-8") as f:
        return f.read()


# -- what the window shows ---------------------------------------------------------------------------------------
EXPECTED_COLOUR = {SigningStatus.OFF: NORMAL, SigningStatus.SIGNING: GOOD, SigningStatus.SETTING_UP: NORMAL,
                   SigningStatus.REQUIRED: WARN, SigningStatus.MISMATCH: WARN, SigningStatus.UNAVAILABLE: WARN}


@pytest.mark.parametrize("status", list(SigningStatus), ids=lambda s: s.name)
def test_each_signing_state_reads_in_the_panel_and_the_ones_that_cut_the_link_warn(qtbot, status):
    panel, banner = TelemetryPanel(), LinkBanner()
    qtbot.addWidget(panel)
    qtbot.addWidget(banner)
    signing = Signing(status, "what the driver says", 7, signed_accepted=1200, bad_signature=2, unsigned_rejected=1)
    link = LinkHealth(status=LinkStatus.OK, address="udpin:0.0.0.0:14550", heartbeat_age=0.2)
    panel.set_state(VehicleState(link=link, mode="GUIDED", signing=signing))
    assert panel.text("signing") == status.value
    assert panel.color("signing") == EXPECTED_COLOUR[status]
    assert panel.tooltip("signing") == signing.summary
    assert "what the driver says" in panel.tooltip("signing") and "1200 verified" in panel.tooltip("signing")
    assert panel.text("signed") == "1200 verified · 3 dropped"
    banner.set_link(link.status, link.address, link.heartbeat_age, warning=signing_warning(signing))
    assert banner.isHidden() == (EXPECTED_COLOUR[status] != WARN)
    assert banner.text() == signing_warning(signing)


def test_a_lost_link_says_when_signing_is_the_cause(qtbot):
    banner = LinkBanner()
    qtbot.addWidget(banner)
    banner.set_link(LinkStatus.LOST, "tcp:x", 6.2, warning=signing_warning(Signing(SigningStatus.MISMATCH)))
    assert banner.text().startswith("Link lost — 6 s since the last heartbeat — ")
    assert "key mismatch" in banner.text() and banner.property("kind") == "lost"


def test_setting_signing_up_on_the_vehicle_from_preferences(qtbot, sim, vehicle_factory, window_factory,
                                                            viewer_settings):
    v = signing_driver(vehicle_factory, f"tcp:127.0.0.1:{sim.tcp_port}")
    w = window_factory(v)
    qtbot.waitUntil(lambda: w.adapter.state.connected and w.telemetry.text("signing") == "off", timeout=10000)
    assert w.telemetry.color("signing") == NORMAL
    assert w.telemetry.text("signed") == "--" and w.telemetry.color("signed") == DIM
    assert w.linkBanner.isHidden()
    dialog = open_link_security(qtbot, w)
    assert dialog.signingStatus.text() == "off" and not dialog.signingUnavailable.isVisible()
    assert not dialog.setupSigning.isEnabled() and not dialog.removeSigning.isEnabled()     # nothing named yet
    assert dialog.signingPassphrase.echoMode() == QLineEdit.Password
    qtbot.keyClicks(dialog.signingPassphrase, PASSPHRASE)
    assert dialog.keyFromPassphrase.isChecked() and dialog.setupSigning.isEnabled()
    sent = sent_commands(w)

    box = ask_setup(qtbot, dialog)                      # first the warning: the key travels in clear
    assert "in clear" in box.text() and "USB or a cable" in box.text()
    assert box.defaultButton() is box.button(QMessageBox.Cancel)
    assert box.button(QMessageBox.Yes).focusPolicy() == Qt.NoFocus
    qtbot.mouseClick(box.button(QMessageBox.Cancel), Qt.LeftButton)
    qtbot.waitUntil(lambda: dialog.setup_box is None, timeout=3000)
    assert sent == [] and sim.signing.key is None

    box = ask_setup(qtbot, dialog)
    qtbot.mouseClick(box.button(QMessageBox.Yes), Qt.LeftButton)
    assert sent == ["setup_signing"]
    qtbot.waitUntil(lambda: "signing setup: accepted" in dialog.signingResult.text(), timeout=15000)
    assert sim.signing.key == KEY
    qtbot.waitUntil(lambda: w.telemetry.text("signing") == "signing" and "verified" in w.telemetry.text("signed"),
                    timeout=10000)
    assert w.telemetry.color("signing") == GOOD
    assert "both ends sign" in w.telemetry.tooltip("signing")
    assert dialog.signingStatus.text().startswith("signing (both ends sign")
    assert dialog.signing_status_color == GOOD
    assert dialog.removeSigning.isEnabled() and dialog.stopSigning.isEnabled()

    accepted = sim.signing.counters.accepted_signed       # the vehicle now obeys our signed frames
    pick_mode(qtbot, w.modeSelector, "ALT_HOLD")
    qtbot.waitUntil(lambda: sim.truth().mode == "ALT_HOLD", timeout=10000)
    assert sim.signing.counters.accepted_signed > accepted

    qtbot.mouseClick(dialog.removeSigning, Qt.LeftButton)
    qtbot.waitUntil(lambda: "signing remove: accepted" in dialog.signingResult.text(), timeout=15000)
    assert sim.signing.key is None
    qtbot.waitUntil(lambda: w.telemetry.text("signing") == "off", timeout=5000)

    dialog.buttons.button(QDialogButtonBox.Ok).click()
    text = saved_text(viewer_settings)
    assert PASSPHRASE not in text and KEY.hex() not in text
    assert load_settings(viewer_settings).signing_key_file == ""


def test_a_vehicle_that_requires_signing_is_flagged_until_the_pilot_signs_with_its_key_file(
        qtbot, sim_factory, vehicle_factory, window_factory, viewer_settings, tmp_path):
    sim = sim_factory(signing_key=KEY)
    v = signing_driver(vehicle_factory, f"tcp:127.0.0.1:{sim.tcp_port}")
    w = window_factory(v)
    qtbot.waitUntil(lambda: w.telemetry.text("signing") == "vehicle requires signing", timeout=10000)
    assert w.telemetry.color("signing") == WARN
    qtbot.waitUntil(lambda: w.linkBanner.isVisible(), timeout=3000)
    assert "requires signing" in w.linkBanner.text() and "Link security" in w.linkBanner.text()
    key_file = tmp_path / "pilot.key"
    write_key_file(str(key_file), KEY)

    dialog = open_link_security(qtbot, w)
    assert dialog.signingStatus.text().startswith("vehicle requires signing")
    assert dialog.signing_status_color == WARN
    qtbot.keyClicks(dialog.signingKeyFile, str(key_file))
    assert dialog.keyFromFile.isChecked() and not dialog.saveKeyFile.isEnabled()
    sent = sent_commands(w)
    qtbot.mouseClick(dialog.signWithKey, Qt.LeftButton)
    assert sent == ["use_signing_key"]
    assert dialog.signingResult.text() == "signing key: accepted (signing with the new key)"
    qtbot.waitUntil(lambda: w.telemetry.text("signing") == "signing"
                    and "both ends sign" in w.telemetry.tooltip("signing")
                    and "verified" in w.telemetry.text("signed"), timeout=10000)
    assert w.telemetry.color("signing") == GOOD
    qtbot.waitUntil(lambda: w.linkBanner.isHidden(), timeout=3000)
    pick_mode(qtbot, w.modeSelector, "ALT_HOLD")             # the vehicle now hears the pilot
    qtbot.waitUntil(lambda: sim.truth().mode == "ALT_HOLD", timeout=10000)

    dialog.buttons.button(QDialogButtonBox.Ok).click()        # the key file's path is kept, never the key
    assert load_settings(viewer_settings).signing_key_file == str(key_file)
    assert KEY.hex() not in saved_text(viewer_settings)
    again = open_link_security(qtbot, w)
    assert again.signingKeyFile.text() == str(key_file) and again.keyFromFile.isChecked()
    assert again.signingPassphrase.text() == ""
    again.reject()


def test_a_passphrase_saved_as_a_private_key_file_is_remembered_by_its_path_only(
        qtbot, sim, vehicle_factory, window_factory, viewer_settings, tmp_path):
    v = signing_driver(vehicle_factory, f"tcp:127.0.0.1:{sim.tcp_port}")
    w = window_factory(v)
    dialog = open_link_security(qtbot, w)
    assert not dialog.saveKeyFile.isEnabled()
    qtbot.keyClicks(dialog.signingPassphrase, PASSPHRASE)
    chooser = dialog.choose_key_file_to_save()
    qtbot.waitUntil(chooser.isVisible, timeout=3000)
    path = tmp_path / "saved.key"
    chooser.selectFile(str(path))
    chooser.accept()
    qtbot.waitUntil(lambda: path.exists(), timeout=3000)
    assert path.stat().st_mode & 0o777 == 0o600
    assert path.read_text().strip() == KEY.hex()
    assert dialog.keyFromFile.isChecked() and dialog.signingKeyFile.text() == str(path)
    assert dialog.signingPassphrase.text() == "" and "readable only by you" in dialog.signingResult.text()
    dialog.buttons.button(QDialogButtonBox.Ok).click()
    assert load_settings(viewer_settings).signing_key_file == str(path)
    text = saved_text(viewer_settings)
    assert PASSPHRASE not in text and KEY.hex() not in text


def test_a_refused_setup_shows_why_and_disarm_on_the_ground_asks_nothing(qtbot, sim_factory, vehicle_factory,
                                                                       window_factory):
    sim = sim_factory(auto_disarm_after=0)                   # armed on the ground until told otherwise
    v = signing_driver(vehicle_factory, f"tcp:127.0.0.1:{sim.tcp_port}")
    w = window_factory(v)
    fc = w.flightControls
    qtbot.waitUntil(lambda: fc.arm_button.isEnabled() and w.adapter.state.readiness.ready_to_arm, timeout=15000)
    sent = sent_commands(w)
    qtbot.mouseClick(fc.arm_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: w.flight.arm_box is not None and w.flight.arm_box.isVisible(), timeout=3000)  # Arm asks first
    qtbot.mouseClick(w.flight.arm_box.button(QMessageBox.Yes), Qt.LeftButton)
    qtbot.waitUntil(lambda: w.adapter.state.armed and fc.arm_button.text() == "Disarm", timeout=10000)

    dialog = open_link_security(qtbot, w)
    qtbot.keyClicks(dialog.signingPassphrase, PASSPHRASE)
    qtbot.mouseClick(ask_setup(qtbot, dialog).button(QMessageBox.Yes), Qt.LeftButton)
    qtbot.waitUntil(lambda: "signing setup: rejected" in dialog.signingResult.text(), timeout=10000)
    assert "disarm first" in dialog.signingResult.text()
    assert sim.signing.key is None and w.telemetry.text("signing") == "off"
    dialog.reject()

    w.activateWindow()
    qtbot.mouseClick(fc.arm_button, Qt.LeftButton)          # on the ground: a plain disarm, no question
    assert w.flight.emergency_box is None
    assert sent == ["arm", "setup_signing", "disarm"]
    qtbot.waitUntil(lambda: not sim.truth().armed and not w.adapter.state.armed, timeout=10000)


def test_foreign_packets_are_counted_and_the_vehicles_address_shown(qtbot, sim_factory, vehicle_factory,
                                                                   window_factory):
    port = free_udp_port()
    v = signing_driver(vehicle_factory, f"udpin:127.0.0.1:{port}")        # listening before the vehicle pushes
    sim_factory(udp_out=f"127.0.0.1:{port}", tcp_port=None)
    w = window_factory(v)
    qtbot.waitUntil(lambda: bool(w.adapter.state.connected and w.adapter.state.mode
                                 and w.adapter.state.link.pinned_to), timeout=10000)
    pinned = w.adapter.state.link.pinned_to
    mode = w.adapter.state.mode
    # the panel's numbers redraw at reading speed (refresh.TEXT_HZ), not with every snapshot
    qtbot.waitUntil(lambda: pinned in w.telemetry.tooltip("foreign"), timeout=3000)
    assert w.telemetry.text("foreign") == "0" and w.telemetry.color("foreign") == NORMAL
    qtbot.waitUntil(lambda: f"vehicle at {pinned}" in w.link_status.text(), timeout=3000)
    spoofer = Spoofer(port)
    try:
        spoofer.spoof()                                  # "LAND", a takeoff ACK and a text, from a stranger
        qtbot.waitUntil(lambda: w.telemetry.text("foreign") == f"{spoofer.sent} ignored", timeout=10000)
        assert w.telemetry.color("foreign") == WARN
        assert pinned in w.telemetry.tooltip("foreign") and f"({spoofer.sent} so far)" in w.telemetry.tooltip("foreign")
        qtbot.waitUntil(lambda: any(f"Ignored MAVLink from 127.0.0.1:{spoofer.address[1]}" in t
                                    for t in w.messages.texts()), timeout=5000)
        assert w.adapter.state.mode == mode and not any("spoofed" in t for t in w.messages.texts())
    finally:
        spoofer.close()


# -- the emergency motor stop ------------------------------------------------------------------------------------
def emergency_from_menu(qtbot, w) -> None:
    """In the air a click on Disarm opens its menu, and only the menu's item (clicked with the mouse) asks."""
    fc = w.flightControls
    seen = []

    def pick() -> None:                               # the menu runs its own loop: answer it from inside
        menu = fc.arm_button.menu()
        seen.append(menu is not None and menu.isVisible() and w.flight.emergency_box is None)
        if menu is not None and menu.isVisible():
            qtbot.mouseClick(menu, Qt.LeftButton, pos=menu.actionGeometry(fc.emergency_action).center())
    QTimer.singleShot(300, pick)
    qtbot.mouseClick(fc.arm_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: bool(seen), timeout=3000)
    assert seen == [True], "Disarm in the air asked at once instead of opening its menu"


def test_disarm_in_the_air_asks_for_an_emergency_motor_stop(qtbot, sim, flying, window_factory):
    """In the air Disarm is the emergency motor stop: not in Stop's row (it sat one slip from it), behind a menu,
    and asked."""
    w = window_factory(flying, takeoff_altitude=3.0)
    wait_flying(qtbot, w)
    fc = w.flightControls
    assert fc.arm_button.text() == "Disarm" and fc.arm_button.isEnabled()
    assert fc.arm_button.property("action") == "emergency" and "falls" in fc.arm_button.toolTip()
    arm = QRect(fc.arm_button.mapTo(w, QPoint(0, 0)), fc.arm_button.size())
    stop = QRect(fc.stop_button.mapTo(w, QPoint(0, 0)), fc.stop_button.size())
    assert arm.top() > stop.bottom() and arm.left() > stop.right(), (arm, stop)   # neither beside Stop nor under it
    sent = sent_commands(w)

    emergency_from_menu(qtbot, w)
    qtbot.waitUntil(lambda: w.flight.emergency_box is not None and w.flight.emergency_box.isVisible(), timeout=3000)
    box = w.flight.emergency_box
    assert box.text().startswith("Stop the motors now? The drone will fall.")
    assert box.defaultButton() is box.button(QMessageBox.Cancel)
    assert box.button(QMessageBox.Yes).focusPolicy() == Qt.NoFocus
    qtbot.mouseClick(box.button(QMessageBox.Cancel), Qt.LeftButton)
    qtbot.waitUntil(lambda: w.flight.emergency_box is None, timeout=3000)
    assert sent == []
    answered = w.adapter.state.time                     # a later snapshot: still armed, in the air, flyable
    qtbot.waitUntil(lambda: w.adapter.state.time > answered and w.adapter.state.can_fly_velocity, timeout=5000)
    assert sim.truth().armed and sim.truth().altitude > 2.0

    emergency_from_menu(qtbot, w)
    qtbot.waitUntil(lambda: w.flight.emergency_box is not None and w.flight.emergency_box.isVisible(), timeout=3000)
    qtbot.mouseClick(w.flight.emergency_box.button(QMessageBox.Yes), Qt.LeftButton)
    assert sent == ["disarm"]
    qtbot.waitUntil(lambda: not sim.truth().armed, timeout=10000)
    qtbot.waitUntil(lambda: not w.adapter.state.armed and fc.arm_button.text() == "Arm", timeout=10000)
    assert any("emergency motor stop: accepted" in t for t in w.messages.texts()), w.messages.texts()


def test_land_and_stop_stay_one_click_in_the_air(qtbot, sim, flying, window_factory):
    w = window_factory(flying, takeoff_altitude=3.0)
    wait_flying(qtbot, w)
    sent = sent_commands(w)
    qtbot.mouseClick(w.flightControls.stop_button, Qt.LeftButton)
    qtbot.mouseClick(w.flightControls.main_button, Qt.LeftButton)
    assert sent == ["stop", "land"] and w.flight.emergency_box is None
    qtbot.waitUntil(lambda: sim.truth().mode == "LAND", timeout=10000)


# -- a remote drone ---------------------------------------------------------------------------------------------
def test_a_remote_drone_says_why_link_security_is_set_up_on_its_server(qtbot, vehicle, server_factory,
                                                                       drone_factory, window_factory):
    w = window_factory(drone_factory(server_factory(vehicle)))
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=15000)
    qtbot.waitUntil(lambda: "MAVLinkServer" in w.telemetry.tooltip("signing"), timeout=3000)   # its next redraw
    for row in ("signing", "signed", "foreign"):
        assert w.telemetry.text(row) == "--" and "MAVLinkServer" in w.telemetry.tooltip(row)
    dialog = open_link_security(qtbot, w)
    assert dialog.signingUnavailable.isVisible() and "MAVLinkServer" in dialog.signingUnavailable.text()
    for control in (dialog.signingPassphrase, dialog.signingKeyFile, dialog.signWithKey, dialog.setupSigning,
                    dialog.removeSigning, dialog.allowUnsigned, dialog.saveKeyFile):
        assert not control.isEnabled()
    dialog.reject()
