"""The firmware and the board the vehicle tells (issue 32, Summary): its banner (GCS_MAVLINK::send_banner's STATUSTEXT
lines) and AUTOPILOT_VERSION, kept in ``state().autopilot``; the simulator says what 4.6.3 SITL says (the recordings)
and what the Solo's 3.3 says (3drobotics/ardupilot-solo); the Summary page shows "ArduCopter V4.6.3, board: ...".
"""
from __future__ import annotations

import re

import pytest
from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from driver.core.results import CommandStatus
from driver.setup.banner import Autopilot, heard_text
from recordings import MISSION, PARAMS
from setup_fixtures import bench  # noqa: F401  (fixture)
from test_setup_sim import Bench
from viewer_fixtures import app_style, viewer_settings, window_factory  # noqa: F401  (fixtures)

pytestmark = pytest.mark.timeout(120)
T = 20


def recorded(path: str, kind: str) -> list:
    log = mavutil.mavlink_connection(path + ".tlog", dialect="ardupilotmega")
    out = []
    while (m := log.recv_match(type=kind)) is not None:
        if m.get_srcSystem() == 1:
            out.append(m)
    return out


def recorded_banner() -> list[str]:
    """The first banner of the params recording: the lines from the firmware's to the frame's."""
    texts = [m.text for m in recorded(PARAMS, "STATUSTEXT")]
    start = next(i for i, t in enumerate(texts) if t.startswith("ArduCopter V"))
    end = next(i for i in range(start, len(texts)) if texts[i].startswith("Frame: "))
    return texts[start:end + 1]


def test_the_recorded_banner_and_boards_are_read():
    a = Autopilot()
    for line in recorded_banner():               # 'ArduCopter V4.6.3 (92b0cd78)', '3d1219c7…', 'Frame: QUAD/PLUS'
        a = heard_text(a, line) or a
    assert (a.firmware_line, a.frame_line, a.simulated, a.board) == \
        ("ArduCopter V4.6.3 (92b0cd78)", "Frame: QUAD/PLUS", True, "")
    assert a.board_words().startswith("SITL, ArduPilot's simulator")
    cube = heard_text(a, "CubeOrange 003F0026 3439510B 30363934")          # AP_HAL_ChibiOS get_system_id
    assert (cube.board, cube.simulated, cube.board_words()) == ("CubeOrange", False, "CubeOrange")
    assert heard_text(Autopilot(), "PX4v2 0030001F 3133470C 35363834").board == "PX4v2"     # AP_HAL_PX4 (3.3)
    assert heard_text(Autopilot(), "EKF3 IMU0 initialised") is None
    assert heard_text(Autopilot(), "7d1219c7c4c5404aaa1f6d2a48adfda4") is None           # a machine id alone
    assert Autopilot().board_words().startswith("not reported yet")


def sim_lines(b: Bench, message) -> tuple[list[str], list]:
    b.out.clear()
    b.ap.handle(message, 2)
    b.run(0.2)
    return [m.text for m in b.out if m.get_type() == "STATUSTEXT"], b.out[:]


def test_the_simulator_says_the_banner_463_sitl_says():
    b = Bench()
    b.run(2.0)
    b.ap.params["FRAME_TYPE"] = 0                 # the recording's SITL: QUAD/PLUS
    b.ap.reboot()
    b.run(2.0)
    texts, _ = sim_lines(b, b.factory.param_request_list_encode(1, 1))
    recorded_lines = recorded_banner()
    assert texts[:len(recorded_lines)][0] == recorded_lines[0] == "ArduCopter V4.6.3 (92b0cd78)"
    assert re.fullmatch(r"[0-9a-f]{32}", texts[1]) and texts[2] == recorded_lines[2] == "Frame: QUAD/PLUS"
    texts, out = sim_lines(b, b.factory.command_long_encode(1, 1, mavlink.MAV_CMD_DO_SEND_BANNER, 0, 0, 0, 0, 0, 0, 0, 0))
    assert texts == [recorded_lines[0], texts[1], "Frame: QUAD/PLUS"]
    assert [m.result for m in out if m.get_type() == "COMMAND_ACK"] == [mavlink.MAV_RESULT_ACCEPTED]
    _, out = sim_lines(b, b.factory.command_long_encode(1, 1, mavlink.MAV_CMD_REQUEST_MESSAGE, 0,
                                                        mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION, 0, 0, 0, 0, 0, 0))
    sent = next(m for m in out if m.get_type() == "AUTOPILOT_VERSION")
    real = recorded(MISSION, "AUTOPILOT_VERSION")[0]
    for field in ("flight_sw_version", "board_version", "vendor_id", "product_id", "uid", "flight_custom_version",
                  "os_sw_version", "middleware_sw_version"):
        assert getattr(sent, field) == getattr(real, field), field
    assert bytes(sent.uid2).rstrip(b"\0").decode() == texts[1][:17]          # uid2: the machine id's first 17


def test_the_driver_keeps_the_firmware_and_the_board_on_both_profiles(bench):
    _sim, v = bench()
    result = v.setup.request_banner().result(T)
    assert result.status is CommandStatus.ACCEPTED, result
    s = v.wait_for(lambda s: s.autopilot.banner and (s.autopilot.board or s.autopilot.simulated), T)
    assert s is not None, v.state().autopilot
    a = s.autopilot
    if bench.profile == "copter-4":
        assert (s.firmware, a.firmware_line, a.git_hash) == ("4.6.3", "ArduCopter V4.6.3 (92b0cd78)", "92b0cd78")
        assert a.simulated and a.board == "" and a.board_version == 0 and a.frame_line == "Frame: QUAD/X"
        assert a.board_words().startswith("SITL")
    else:                                          # 3.3: "PX4v2 ..." only on DO_SEND_BANNER, "Frame: QUAD"
        assert s.firmware == "3.3.1" and a.firmware_line.startswith("APM:Copter solo-1.3.1")
        assert (a.board, a.os_line.startswith("PX4: "), a.frame_line) == ("PX4v2", True, "Frame: QUAD")


def test_a_refused_banner_says_why_the_board_is_unknown(bench):
    sim, v = bench()
    sim.autopilot._cmd_do_send_banner = lambda *_: (mavlink.MAV_RESULT_UNSUPPORTED, None)
    v.setup.request_banner().result(T)
    s = v.wait_for(lambda s: s.autopilot.asked, T)
    assert s is not None
    if not s.autopilot.board and not s.autopilot.simulated:
        assert s.autopilot.board_words().startswith("not reported: the vehicle would not send its banner")
        assert "UNSUPPORTED" in s.autopilot.board_words().upper()


def test_the_summary_names_the_firmware_and_the_board(qtbot, bench, window_factory):
    _sim, v = bench()
    w = window_factory(v)
    w.setup.open("Summary")
    page = w.setup.dialog.pages["Summary"]
    if bench.profile == "copter-4":
        qtbot.waitUntil(lambda: page.firmware.text().startswith("ArduCopter V4.6.3, board: SITL, ArduPilot's simulator"),
                        timeout=T * 1000)
        assert "QUAD/X" in page.firmware.text()
    else:
        qtbot.waitUntil(lambda: page.firmware.text().startswith("APM:Copter solo-1.3.1, board: PX4v2"),
                        timeout=T * 1000)
    assert "not reported" not in page.firmware.text()
