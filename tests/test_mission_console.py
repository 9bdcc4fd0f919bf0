"""The console's wp, fence and rally verbs (MAVProxy's) on the real driver and the simulated vehicle."""
from __future__ import annotations

import io
import time
from dataclasses import replace

from pymavlink import mavwp

from driver.console.console import Console
from driver.mission.files import save_plan_file
from driver.mission.plan import Plan, PlanKind
from test_mission_files import fence, rally
from test_mission_transfer import homed, place, survey_mission  # noqa: F401


def wait_text(out: io.StringIO, text: str, timeout: float = 20.0) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if text in out.getvalue():
            return out.getvalue()
        time.sleep(0.02)
    raise AssertionError(f"{text!r} never printed:\n{out.getvalue()}")


def test_wp_fence_and_rally_verbs(homed, sim, tmp_path):  # noqa: F811
    out = io.StringIO()
    console = Console(homed, stdout=out)
    home = homed.state().home
    save_plan_file(tmp_path / "m.waypoints", (survey_mission(homed, 5),), (home.lat, home.lon, home.alt))
    console.onecmd(f"wp load {tmp_path / 'm.waypoints'}")
    wait_text(out, "upload mission: accepted")
    console.onecmd("wp list")
    text = wait_text(out, "mission on the vehicle, 5 items:")
    assert "    1 TAKEOFF" in text and "    5 RETURN_TO_LAUNCH" in text
    console.onecmd(f"wp save {tmp_path / 'back.waypoints'}")
    wait_text(out, "saved the mission (5 items)")
    assert mavwp.MAVWPLoader().load(str(tmp_path / "back.waypoints")) == 6

    # a .plan with the recording's fence (around ArduPilot's SITL home: a fence may be anywhere) and a rally
    # point near the vehicle (rally points are checked against the distance limit like waypoints)
    lat, lon = place(homed, 20, 10)
    near = Plan(PlanKind.RALLY, (replace(rally().items[0], lat=lat, lon=lon),))
    save_plan_file(tmp_path / "f.plan", (fence(), near))
    console.onecmd(f"fence load {tmp_path / 'f.plan'}")
    wait_text(out, "upload fence: accepted")
    console.onecmd("fence list")
    wait_text(out, "fence on the vehicle, 5 items:")
    console.onecmd(f"rally load {tmp_path / 'f.plan'}")
    wait_text(out, "upload rally points: accepted")
    assert len(sim.autopilot.plans[PlanKind.RALLY]) == 1
    console.onecmd("fence clear")
    wait_text(out, "clear fence: accepted")
    console.onecmd("wp clear")
    wait_text(out, "clear mission: accepted")
    assert sim.autopilot.plans[PlanKind.FENCE] == [] and sim.autopilot.plans[PlanKind.MISSION] == []
    console.onecmd("wp set x")
    wait_text(out, "error: wp set N")
    console.onecmd(f"wp load {tmp_path / 'missing.plan'}")
    wait_text(out, "No such file")
