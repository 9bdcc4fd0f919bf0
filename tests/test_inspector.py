"""The MAVLink inspector (issue 31): the reader counts every message from every component of the real simulated
vehicle, with its rate and newest fields; Tools › MAVLink inspector shows them updating in place and plots a field
in one double-click; a drone that does not see the link (the Ice client) says so."""
from __future__ import annotations

from driver.ice.client import IceDrone
from driver.vehicle.inspector import Inspection
from uavviewer.inspector.view import InspectorWindow
from viewer_fixtures import viewer_settings, window_factory, window  # noqa: F401  (fixtures)


def _stat(inspection, system, component, name):
    return next((m for m in inspection.messages if (m.system, m.component, m.name) == (system, component, name)),
                None)


def test_the_vehicle_counts_every_message_with_its_rate_and_fields(vehicle):
    def rates_known(_s) -> bool:              # the first rate comes once a second has passed between snapshots
        seen = vehicle.inspection()
        return all(_stat(seen, 1, 1, n) is not None and _stat(seen, 1, 1, n).rate_hz > 0
                   for n in ("ATTITUDE", "HEARTBEAT"))
    assert vehicle.wait_for(rates_known, 10)
    seen = vehicle.inspection()
    assert seen.available
    heartbeat = _stat(seen, 1, 1, "HEARTBEAT")
    attitude = _stat(seen, 1, 1, "ATTITUDE")
    assert heartbeat.count >= 1 and attitude.rate_hz > heartbeat.rate_hz > 0
    fields = dict(attitude.fields)
    assert set(fields) >= {"time_boot_ms", "roll", "pitch", "yaw"}
    before = fields["time_boot_ms"]
    assert vehicle.wait_for(lambda s: dict(_stat(vehicle.inspection(), 1, 1, "ATTITUDE").fields)["time_boot_ms"]
                            > before, 5)
    assert isinstance(dict(_stat(seen, 1, 1, "STATUSTEXT").fields)["text"], str) if _stat(seen, 1, 1, "STATUSTEXT") \
        else True


def test_a_drone_that_does_not_see_the_link_says_so(qtbot):
    assert IceDrone.inspector is None
    why = "a remote drone: its server reads the link"
    view = InspectorWindow(lambda: Inspection.unavailable(why))
    qtbot.addWidget(view)
    view.show()
    assert "No inspector for this connection" in view.note.text() and why in view.note.text()
    assert view.tree.topLevelItemCount() == 0


def test_tools_mavlink_inspector_updates_in_place_and_plots_a_field(qtbot, window):
    action = window.inspector.action
    assert action in window.findChild(type(window.menuFile), "menuTools").actions()
    action.trigger()
    view = window.inspector.view
    qtbot.waitUntil(lambda: view.isVisible() and (1, 1, "ATTITUDE") in view._messages, timeout=10000)
    assert "system 1, component 1" in view._components[(1, 1)].text(0)
    assert view.select(1, 1, "ATTITUDE")
    rows = {view.fields.item(r, 0).text(): r for r in range(view.fields.rowCount())}
    assert "roll" in rows
    cell = view.fields.item(rows["time_boot_ms"], 1)
    first = cell.text()
    qtbot.waitUntil(lambda: cell.text() != first, timeout=5000)          # the same cell, its value updated
    assert view.fields.item(rows["time_boot_ms"], 1) is cell
    view.fields.cellDoubleClicked.emit(rows["roll"], 0)
    assert view.field_plot.key == (1, 1, "ATTITUDE", "roll")
    qtbot.waitUntil(lambda: len(view.field_plot.points) >= 3, timeout=5000)
    count = view._messages[(1, 1, "ATTITUDE")].text(2)
    qtbot.waitUntil(lambda: view._messages[(1, 1, "ATTITUDE")].text(2) != count, timeout=5000)
    qtbot.waitUntil(lambda: float(view._messages[(1, 1, "ATTITUDE")].text(1)) > 0, timeout=5000)


def test_rates_come_from_the_counts_between_snapshots():
    from pymavlink.dialects.v20 import ardupilotmega as mavlink
    from driver.vehicle.inspector import MessageInspector
    now = [100.0]
    inspector = MessageInspector(clock=lambda: now[0])
    for k in range(50):
        inspector.seen(mavlink.MAVLink_attitude_message(k, 0.1, 0.0, 0.0, 0, 0, 0), 1, 1, "ATTITUDE")
    inspector.seen(mavlink.MAVLink_statustext_message(4, b"Hello\0\0", 0, 0), 1, 1, "STATUSTEXT")
    first = inspector.snapshot()
    assert [m.rate_hz for m in first.messages] == [0.0, 0.0]          # no second has passed yet
    now[0] = 102.0
    for k in range(40):
        inspector.seen(mavlink.MAVLink_attitude_message(k, 0.2, 0.0, 0.0, 0, 0, 0), 1, 1, "ATTITUDE")
    attitude, text = inspector.snapshot().messages
    assert attitude.rate_hz == 45.0 and attitude.count == 90 and dict(attitude.fields)["roll"] == 0.2
    assert dict(text.fields)["text"] == "Hello" and text.age_s == 2.0
    now[0] = 104.0
    assert inspector.snapshot().messages[0].rate_hz == 0.0          # it stopped: the rate falls to 0


def test_the_plot_follows_its_field_when_another_message_is_selected(qtbot):
    """The plot was fed from the selected message only: picking another froze it. It follows its own key."""
    from pymavlink.dialects.v20 import ardupilotmega as mavlink
    from driver.vehicle.inspector import MessageInspector
    inspector = MessageInspector()
    view = InspectorWindow(inspector.snapshot)
    qtbot.addWidget(view)

    def arrive(roll: float) -> None:
        inspector.seen(mavlink.MAVLink_attitude_message(0, roll, 0.0, 0.0, 0, 0, 0), 1, 1, "ATTITUDE")
        inspector.seen(mavlink.MAVLink_heartbeat_message(2, 3, 81, 4, 3, 3), 1, 1, "HEARTBEAT")
        view.refresh()
    arrive(0.1)
    assert view.select(1, 1, "ATTITUDE")
    rows = {view.fields.item(r, 0).text(): r for r in range(view.fields.rowCount())}
    view.fields.cellDoubleClicked.emit(rows["roll"], 0)
    arrive(0.2)
    assert view.select(1, 1, "HEARTBEAT") and view.fields.item(0, 0).text() == "type"
    arrive(0.3)
    arrive(0.4)
    assert view.field_plot.key == (1, 1, "ATTITUDE", "roll")
    assert [round(v, 3) for _t, v in view.field_plot.points] == [0.2, 0.3, 0.4]
