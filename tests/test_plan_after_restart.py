"""A vehicle that restarts may come back without the plans it held (a SITL started afresh, a wiped or swapped
autopilot): the driver sees the restart in the vehicle's clock, forgets what it held, and the Plan panel reads
its plans again instead of showing the mission it no longer has."""
from __future__ import annotations

import pytest
from PyQt5.QtCore import Qt
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.mission.plan import MissionItem, PlanKind

from test_mission_transfer import waypoint
from viewer_fixtures import viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)


def test_after_a_restart_the_plan_panel_reads_what_the_vehicle_holds(qtbot, sim_factory, vehicle_factory,
                                                                     window_factory):
    sim = sim_factory()
    sim.autopilot.boot_time -= 600.0                    # it has been up for ten minutes
    port = sim.tcp_port
    v = vehicle_factory(f"tcp:127.0.0.1:{port}", loss_timeout=1.0)
    w = window_factory(v)
    plan = w.plan
    qtbot.waitUntil(lambda: plan.home is not None, timeout=15000)
    entries = [MissionItem(mavlink.MAV_CMD_NAV_TAKEOFF, alt=10)] + [waypoint(v, 10.0 * i, 5.0, 10) for i in range(4)]
    plan.editor.load_entries(entries)
    plan.show_plan(True)
    qtbot.mouseClick(plan.panel.uploadButton, Qt.LeftButton)
    qtbot.waitUntil(lambda: plan.panel.syncLabel.text() == "Same as the vehicle's mission (5 items)", timeout=20000)
    assert v.state().boot.seconds > 600 and v.state().boot.restarts == 0

    sim.stop()                                          # the vehicle goes; another starts on its port, empty
    assert v.wait_for(lambda s: s.link.status.value == "lost", 10)
    sim_factory(tcp_port=port)
    s = v.wait_for(lambda s: s.connected and s.boot.restarts == 1, 20)
    assert s is not None, v.state().boot
    assert any(m.text.startswith("The vehicle restarted") for m in s.messages)
    qtbot.waitUntil(lambda: plan.vehicle_plan(PlanKind.MISSION) is not None
                    and len(plan.vehicle_plan(PlanKind.MISSION)) == 0, timeout=20000)
    qtbot.waitUntil(lambda: plan.panel.syncLabel.text() == "Differs from the vehicle's: 0 items there, 5 here",
                    timeout=5000)
    assert len(plan.doc.plan(PlanKind.MISSION)) == 5     # the plan being edited is untouched
    assert plan.progress_text(w.adapter.state) != "Mission of 5 items on the vehicle, not flying"
