"""File › Connect, Disconnect and Open flight log in the window, against the real simulated vehicle over real
sockets and a real ArduCopter recording: switching needs no restart, and a finished replay shows no live link."""
from __future__ import annotations

from dataclasses import replace

import pytest
from PyQt5.QtCore import Qt

from driver.mission.plan import Plan, PlanKind
from driver.vehicle.rules import unattended
from driver.vehicle.state import LinkStatus
from driver.sim.clock import ManualClock
from recordings import FLIGHT
from uavviewer.alerts.model import AlertKind
from uavviewer.connect.choice import Choice, Kind, parse_key, sim_name
from uavviewer.connect.dialog import KINDS
from uavviewer.settings import load_settings
from fleet_fixtures import fleet, lab  # noqa: F401  (fixtures)
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(90)


@pytest.fixture
def connecting(window_factory):
    """A window whose connection controller owns what it opens; everything it opened is closed afterwards."""
    windows = []

    def make(drone):
        w = window_factory(drone)
        w.connections.adopt(drone)
        windows.append(w)
        return w
    yield make
    for w in windows:
        w.connections.close()


def test_connect_from_the_dialog_switches_vehicle_then_disconnect(qtbot, sim_factory, vehicle_factory, connecting):
    first, second = sim_factory(), sim_factory()
    v1 = vehicle_factory(f"tcp:127.0.0.1:{first.tcp_port}")
    w = connecting(v1)
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=10000)

    w.actionConnect.trigger()                            # File › Connect…
    dialog = w.tools.connect_dialog
    qtbot.waitExposed(dialog)
    dialog.kind.setCurrentIndex(KINDS.index("TCP"))
    dialog.tcp_host.setText("")                          # a typo is said in the dialog, nothing is opened
    qtbot.mouseClick(dialog.connect_button, Qt.LeftButton)
    assert "HOST:PORT" in dialog.problem.text() and w.adapter.drone is v1
    dialog.tcp_host.setText("127.0.0.1")
    dialog.tcp_port.setValue(second.tcp_port)
    qtbot.mouseClick(dialog.connect_button, Qt.LeftButton)

    qtbot.waitUntil(lambda: w.adapter.drone is not v1 and w.adapter.state.connected, timeout=10000)
    assert str(second.tcp_port) in w.windowTitle()
    qtbot.waitUntil(lambda: v1.state().link.status is LinkStatus.CLOSED, timeout=10000)   # the old link let go
    qtbot.waitUntil(lambda: w.connections.recent()[:1] == [Choice(Kind.MAVLINK, f"tcp:127.0.0.1:{second.tcp_port}")],
                    timeout=5000)                        # remembered once a vehicle answered on it
    assert load_settings(w._qsettings).last_connection == f"tcp:127.0.0.1:{second.tcp_port}"   # the next run's
    qtbot.waitUntil(lambda: w.flightControls.arm_button.isEnabled(), timeout=15000)     # and it can be flown

    v2 = w.adapter.drone
    w.actionDisconnect.trigger()
    qtbot.waitUntil(lambda: w.adapter.description == "Not connected", timeout=5000)
    assert not w.flightControls.main_button.isEnabled() and not w.flightControls.arm_button.isEnabled()
    assert w.linkBanner.isVisible() and w.linkBanner.text().startswith("Not connected")
    qtbot.waitUntil(lambda: v2.state().link.status is LinkStatus.CLOSED, timeout=10000)

    w.tools.show_connect()                                     # the recent connection is offered first
    dialog = w.tools.connect_dialog
    assert dialog.recent_list.count() == 1 and dialog.chosen() == w.connections.recent()[0]
    dialog.reject()
    recent, = w.menuRecent.actions()                     # and in File › Recent connections: one click
    assert recent.text() == f"tcp:127.0.0.1:{second.tcp_port}"
    recent.trigger()
    qtbot.waitUntil(lambda: w.adapter.state.connected and str(second.tcp_port) in w.windowTitle(), timeout=10000)


def test_connect_to_the_built_in_simulator_and_a_bad_link_keeps_the_old_one(qtbot, sim, vehicle, connecting):
    w = connecting(vehicle)
    w.name_vehicle("the first vehicle")                  # as --sim names it
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=10000)
    failures = []
    w.connections.failed.connect(failures.append)
    assert not w.connections.connect_to(Choice(Kind.MAVLINK, "tcp:127.0.0.1"))
    assert failures and "HOST:PORT" in failures[0] and w.adapter.drone is vehicle

    assert w.connections.connect_to(Choice(Kind.SIM, options={"speedup": 4.0, "ready_after": 1.0}))
    qtbot.waitUntil(lambda: w.adapter.drone is not vehicle and w.adapter.state.connected, timeout=15000)
    assert w.connections.current.sim is not None                      # started for it, stopped with it
    assert w.camera.uris == ["sim"]                                    # and its camera shown, as with --sim
    assert w.window_name() == sim_name(w.connections.current.sim.config.speedup) and "first" not in w.windowTitle()   # About too
    w.actionDisconnect.trigger()
    qtbot.waitUntil(lambda: w.adapter.description == "Not connected", timeout=5000)
    assert w.window_name() == "Not connected"                         # no vehicle: no name left over
    qtbot.waitUntil(lambda: vehicle.state().link.status is LinkStatus.CLOSED, timeout=10000)
    assert parse_key(Choice(Kind.SIM).key) == Choice(Kind.SIM)


def test_open_flight_log_seeks_restarts_and_ends_without_a_live_heartbeat(qtbot, sim, vehicle, connecting):
    w = connecting(vehicle)
    w.tools.open_flight_log(f"{FLIGHT}.tlog")                 # File › Open flight log…, the file picked
    qtbot.waitUntil(lambda: w.adapter.replay is not None and w.adapter.state.connected, timeout=15000)
    assert w.replayBar.isVisible() and not w.controlsRow.isEnabled()
    replay = w.adapter.replay
    assert [w.replayBar.speed.itemData(i) for i in range(w.replayBar.speed.count())] == [0.5, 1.0, 2.0, 4.0, 8.0]
    w.replayBar.speed.setCurrentIndex(4)
    w.replayBar.speed.activated.emit(4)
    assert replay.speed == 8.0
    qtbot.waitUntil(lambda: replay.duration > 0 and w.replayBar._duration > 0, timeout=5000)
    w.replayBar.seek_to(replay.duration - 4.0)          # the seek bar, near the end
    assert replay.position >= replay.duration - 4.5

    qtbot.waitUntil(lambda: replay.finished, timeout=15000)
    qtbot.waitUntil(lambda: w.adapter.state.link.status is LinkStatus.CLOSED, timeout=5000)   # no live heartbeat
    qtbot.waitUntil(lambda: "Replay ended" in w.linkBanner.text(), timeout=5000)
    qtbot.waitUntil(lambda: not w.replayBar.play_button.isEnabled(), timeout=5000)   # its own refresh: Restart
    assert any("Replay ended" in t for t in w.messages.texts())
    qtbot.waitUntil(lambda: w.telemetry.text("heartbeat") == "none (replay ended)", timeout=5000)

    qtbot.mouseClick(w.replayBar.restart_button, Qt.LeftButton)      # from the start again
    assert not replay.finished and replay.position < 2.0
    qtbot.waitUntil(lambda: w.adapter.state.link.status is LinkStatus.OK, timeout=10000)
    qtbot.waitUntil(lambda: w.replayBar.play_button.text() == "Pause", timeout=5000)


def test_connect_to_a_labs_registry_shows_its_fleet_and_leaving_it_closes_it(qtbot, sim, vehicle, connecting,
                                                                            fleet, lab):
    fleet(2)                                             # solo-1 and solo-2, each a simulated vehicle behind Ice
    w = connecting(vehicle)
    w.tools.show_connect()
    dialog = w.tools.connect_dialog
    dialog.kind.setCurrentIndex(KINDS.index("Lab registry"))
    dialog.registry.setText(lab.address)
    qtbot.mouseClick(dialog.connect_button, Qt.LeftButton)
    qtbot.waitUntil(lambda: getattr(w, "fleet", None) is not None, timeout=30000)
    panel = w.fleet_panel
    qtbot.waitUntil(lambda: [r[0] for r in panel.row_texts()] == ["▶ solo-1", "solo-2"], timeout=15000)
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=15000)      # solo-1, through its MAVLinkServer
    assert "solo-1" in w.windowTitle() and w.adapter.drone is not vehicle
    ice_fleet = w.connections.current.fleet
    assert w.camera.uris == ["ice:Camera@solo-1"]                      # its camera, found through the registry
    raised = []
    w.alerts.alerted.connect(lambda a: raised.append(a.kind))
    w.fleet.pick("solo-2")                                # another vehicle: its state is a baseline, not news
    qtbot.waitUntil(lambda: AlertKind.CONNECTED in raised, timeout=15000)
    assert set(raised) == {AlertKind.CONNECTED}
    qtbot.waitUntil(lambda: w.connections.recent()[:1] == [Choice(Kind.REGISTRY, lab.address)], timeout=5000)

    assert w.connections.connect_to(Choice(Kind.MAVLINK, f"tcp:127.0.0.1:{sim.tcp_port}"))
    qtbot.waitUntil(lambda: getattr(w, "fleet", None) is None and w.adapter.state.connected, timeout=15000)
    assert w.findChild(type(panel)) is None or not w.findChild(type(panel)).isVisible()
    qtbot.waitUntil(lambda: ice_fleet.closed, timeout=10000)                 # the fleet left behind is closed


def test_the_command_lines_choice_is_a_recent_connection_too(tmp_path):
    from uavviewer.app import build_parser
    from uavviewer.connect.choice import from_command_line
    parse = build_parser().parse_args
    assert from_command_line(parse(["--sim"]), "tcp:127.0.0.1:1") == Choice(Kind.SIM)
    assert from_command_line(parse(["--connect", "/dev/ttyACM0", "--baud", "115200"]), "/dev/ttyACM0") == \
        Choice(Kind.MAVLINK, "/dev/ttyACM0", 115200)
    assert from_command_line(parse(["--ice-host", "10.1.1.10"]), "") == Choice(Kind.ICE, "10.1.1.10")
    assert from_command_line(parse(["--registry", "10.1.1.5:4061"]), "") == Choice(Kind.REGISTRY, "10.1.1.5:4061")
    for choice in (Choice(Kind.MAVLINK, "/dev/ttyACM0", 115200), Choice(Kind.REGISTRY, "10.1.1.5:4061"),
                   Choice(Kind.ICE, "10.1.1.10"), Choice(Kind.MAVLINK, "udpin:0.0.0.0:14550")):
        assert parse_key(choice.key) == choice                       # kept as a line, read back the same


def test_the_dialog_offers_the_systems_serial_ports_and_the_sitl_preset(qtbot):
    from uavviewer.connect.choice import serial_ports
    from uavviewer.connect.dialog import ConnectDialog
    dialog = ConnectDialog([])
    qtbot.addWidget(dialog)
    dialog.kind.setCurrentIndex(KINDS.index("Serial"))
    ports = serial_ports()                               # pyserial's list, through mavutil
    assert [dialog.serial_port.itemData(i) for i in range(dialog.serial_port.count())] == [p for p, _ in ports]
    dialog.serial_port.setEditText("/dev/ttyUSB7")       # a radio plugged in later: typed, the link retries
    dialog.baud.setCurrentIndex(dialog.baud.findData(115200))
    assert dialog.chosen() == Choice(Kind.MAVLINK, "/dev/ttyUSB7", 115200) and dialog.chosen().problem() is None
    dialog.kind.setCurrentIndex(KINDS.index("TCP"))
    dialog.tcp_host.setText("10.0.0.9")
    qtbot.mouseClick(dialog.sitl_button, Qt.LeftButton)
    assert dialog.chosen() == Choice(Kind.MAVLINK, "tcp:127.0.0.1:5760")
    dialog.kind.setCurrentIndex(KINDS.index("UDP"))
    assert dialog.chosen() == Choice(Kind.MAVLINK, "udpin:0.0.0.0:14550")   # a Solo, or any vehicle sending to us


def test_leaving_a_flying_vehicle_is_asked_first(qtbot, sim, flying, connecting):
    w = connecting(flying)
    qtbot.waitUntil(lambda: w.adapter.state.flying and w.adapter.state.connected, timeout=10000)
    w.actionDisconnect.trigger()
    qtbot.waitUntil(lambda: w.tools.leave_box is not None and w.tools.leave_box.isVisible(), timeout=3000)
    box = w.tools.leave_box
    assert "in GUIDED" in box.text() and box.defaultButton() is box.button(box.Cancel)
    s = w.adapter.state                                  # the same words as the quit question: its GCS failsafe's
    assert unattended(s.mode, s.gcs_failsafe) in box.text()
    box.button(box.Cancel).click()                       # Cancel: still flying it
    assert w.adapter.drone is flying and w.connections.connected
    w.actionDisconnect.trigger()
    box = w.tools.leave_box
    qtbot.waitUntil(box.isVisible, timeout=3000)
    leave = next(b for b in box.buttons() if b.text() == "Leave it flying")
    leave.click()
    qtbot.waitUntil(lambda: w.adapter.description == "Not connected", timeout=5000)
    assert sim.truth().armed and -sim.truth().down > 1.0   # let go of, still in the air: it hovers in GUIDED


def test_file_connect_judges_the_new_vehicle_by_the_pilots_battery_thresholds(qtbot, sim, vehicle, sim_factory,
                                                                               vehicle_factory, connecting):
    w = connecting(vehicle)
    other = vehicle_factory(f"tcp:127.0.0.1:{sim_factory().tcp_port}")
    told = []
    original = other.set_battery_thresholds
    other.set_battery_thresholds = lambda thresholds: told.append(thresholds) or original(thresholds)
    w.use_connection(other)                              # File › Connect's path, as a fleet's pick is
    assert told == [w.settings.battery_thresholds]


def test_another_vehicle_starts_with_nothing_known_of_the_previous_one(qtbot, sim, vehicle, sim_factory,
                                                                        vehicle_factory, connecting):
    w = connecting(vehicle)
    qtbot.waitUntil(lambda: w.adapter.state.connected, timeout=10000)
    w.gimbal.point(-30.0)                                # asked of the first vehicle
    w.flight_timer.update(replace(w.adapter.state, armed=True))
    w.plan.on_vehicle[PlanKind.MISSION] = Plan()
    w.use_connection(vehicle_factory(f"tcp:127.0.0.1:{sim_factory().tcp_port}"))
    assert w.gimbal._target is None and not w.flight_timer.started and w.flight_timer.seconds == 0
    assert not w.plan.on_vehicle


def _dead_tcp_address() -> str:
    """A local TCP port nobody listens on (bound, then let go)."""
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp:127.0.0.1:{s.getsockname()[1]}"


def test_a_dead_address_keeps_the_flying_vehicle_flown_and_ends_in_a_clear_error(qtbot, sim, flying, connecting):
    w = connecting(flying)
    qtbot.waitUntil(lambda: w.adapter.state.flying and w.adapter.state.gcs_failsafe is not None, timeout=10000)
    w.connections.answer_timeout = 2.0                  # ANSWER_TIMEOUT (15 s), shortened for the test
    clock = ManualClock()                               # and counted on the test's clock: it runs out when the
    w.connections.clock = clock.now                     # test has flown beside it, however slow the machine
    failures = []
    w.connections.failed.connect(failures.append)
    dead = _dead_tcp_address()
    w.tools.connect_to(Choice(Kind.MAVLINK, dead))      # File › Connect to an address where nothing answers
    qtbot.waitUntil(lambda: w.tools.leave_box is not None and w.tools.leave_box.isVisible(), timeout=3000)
    text = w.tools.leave_box.text()                      # asked first, naming its state and its own failsafe
    assert "airborne at 3 m in GUIDED" in text and "GCS failsafe: FS_GCS_ENABLE = 0, none" in text
    leave = next(b for b in w.tools.leave_box.buttons() if b.text() == "Leave it flying")
    qtbot.mouseClick(leave, Qt.LeftButton)
    assert w.connections.busy and w.adapter.drone is flying          # tried beside it: the old link stays
    assert "Connecting to" in w.statusbar.currentMessage()
    w.flight.request_mode("LOITER")                                         # and keeps flying meanwhile
    qtbot.waitUntil(lambda: sim.truth().mode == "LOITER", timeout=10000)
    assert w.connections.busy and w.adapter.drone is flying

    clock.advance(2.1)
    qtbot.waitUntil(lambda: bool(failures), timeout=20000)                 # a clear error after the stated time
    assert dead in failures[0] and "no heartbeat in 2 s" in failures[0] and "still connected to" in failures[0]
    assert w.adapter.drone is flying and w.connections.current.drone is flying and not w.connections.busy
    assert any("no heartbeat" in t for t in w.messages.texts())
    qtbot.mouseClick(w.flightControls.rtl_button, Qt.LeftButton)     # still controllable
    qtbot.waitUntil(lambda: sim.truth().mode == "RTL", timeout=10000)
    assert flying.state().connected


def test_an_outgoing_tcp_link_says_connecting_never_listening(qtbot, vehicle_factory, window_factory):
    dead = _dead_tcp_address()
    w = window_factory(vehicle_factory(dead))
    qtbot.waitUntil(w.linkBanner.isVisible, timeout=5000)
    assert f"connecting to {dead[len('tcp:'):]}" in w.linkBanner.text() and "listening" not in w.linkBanner.text()
