"""The standalone server: its console on the real driver, and ``python -m driver`` as a process."""
from __future__ import annotations

import io
import os
import signal
import socket
import subprocess
import sys

import Ice

from driver.console import Console

from ice_fixtures import eventually, free_port, jderobot, mavlinkserver

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def console_for(vehicle) -> tuple[Console, io.StringIO]:
    out = io.StringIO()
    return Console(vehicle, stdout=out), out


def test_console_takes_off_moves_and_lands(vehicle):
    console, out = console_for(vehicle)
    console.onecmd("takeoff 3")
    assert eventually(lambda: "takeoff: accepted" in out.getvalue(), 60), out.getvalue()
    console.onecmd("alt")
    assert "m above home" in out.getvalue()
    console.onecmd("mode")
    assert "mode GUIDED; available:" in out.getvalue()
    assert vehicle.wait_for(lambda s: s.velocity.ground_speed < 0.3, 15)
    start = vehicle.state().local
    console.onecmd("velocity 1.5 0 0 4")                 # held by the console, not one packet
    assert eventually(lambda: vehicle.state().distance_from_home is not None and math_dist(
        vehicle.state().local, start) > 2.0, 20), out.getvalue()
    console.onecmd("land")
    assert eventually(lambda: "mode LAND: accepted" in out.getvalue(), 10), out.getvalue()
    assert vehicle.wait_for(lambda s: not s.armed, 60)
    console.onecmd("status")
    console.onecmd("bat")
    text = out.getvalue()
    assert "link ok" in text and "disarmed" in text and "battery " in text and " V" in text


def math_dist(a, b) -> float:
    return ((a.north - b.north) ** 2 + (a.east - b.east) ** 2) ** 0.5


def test_console_answers_bad_input_clearly(vehicle):
    console, out = console_for(vehicle)
    for line, expected in (("fly away", "unknown command 'fly'"),
                           ("velocity a 0 0", "error: X must be a number"),
                           ("velocity 1 2", "usage: velocity X Y Z"),
                           ("velocity 1 0 0 99", "SECONDS must be between"),
                           ("velocity nan 0 0", "must be a finite number"),
                           ("takeoff high", "error: ALT must be a number"),
                           ("parachute open", "usage: parachute enable|disable|release"),
                           ("arm sideways", "usage: arm"),
                           ("disarm now", "usage: disarm [force]"),
                           ("mode GUIDED LOITER", "usage: mode [NAME]"),
                           ("arm check", "ARMING_CHECK"),
                           ("arm list", "arm safetyon")):
        before = len(out.getvalue())
        assert not console.onecmd(line)          # the console goes on
        assert expected in out.getvalue()[before:], (line, out.getvalue()[before:])
    assert not console.onecmd("")
    assert vehicle.state().setpoint.is_zero and not vehicle.state().armed
    console.onecmd("help")
    for command in ("reboot", "arm", "disarm", "takeoff", "land", "mode", "velocity", "parachute", "bat", "alt",
                    "status"):
        assert command in out.getvalue()


def test_console_arm_check_safety_and_parachute_reach_the_vehicle(vehicle):
    console, out = console_for(vehicle)
    console.onecmd("arm check all")
    console.onecmd("arm safetyoff")
    console.onecmd("parachute enable")
    assert eventually(lambda: "param ARMING_CHECK=1" in out.getvalue() and "safety off" in out.getvalue()
                      and "parachute enable" in out.getvalue(), 15), out.getvalue()


def _server(port: int, *extra: str, stdin=None) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "driver", "--sim", "--sim-speedup", "4", "--sim-ready-after", "1", "--no-log",
         "--one-port", str(port), *extra],
        cwd=ROOT, stdin=stdin, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_python_m_driver_daemon_runs_cmd_and_serves_jderobot(tmp_path):
    port = free_port()
    proc = _server(port, "--daemon", "--cmd", "takeoff 2")
    com = Ice.initialize(["--Ice.Default.InvocationTimeout=3000"])
    try:
        pose3d = jderobot.Pose3DPrx.uncheckedCast(com.stringToProxy(f"Pose3D:tcp -h 127.0.0.1 -p {port}"))
        status = mavlinkserver.VehiclePrx.uncheckedCast(com.stringToProxy(f"Vehicle:tcp -h 127.0.0.1 -p {port}"))

        def altitude():
            try:
                return pose3d.getPose3DData().z > 1.7
            except Ice.ConnectionRefusedException:
                return False
        assert eventually(altitude, 60, interval=0.2)
        assert status.getStatus(-1, -1).mode == "GUIDED"
    finally:
        com.destroy()
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=20)
    assert proc.returncode == 0, err
    assert f"-p {port}" in out and "serving Pose3D" in out


def test_python_m_driver_console_reads_commands_from_stdin():
    proc = _server(free_port(), stdin=subprocess.PIPE)
    out, err = proc.communicate("help\nbogus\nvelocity x 0 0\nstatus\nexit\n", timeout=60)
    assert proc.returncode == 0, err
    assert "Documented commands" in out and "unknown command 'bogus'" in out
    assert "error: X must be a number" in out and "link " in out


def test_python_m_driver_says_when_its_port_is_taken():
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        proc = _server(taken.getsockname()[1], "--daemon")
        out, err = proc.communicate(timeout=60)
    assert proc.returncode == 1
    assert "cannot serve the Ice interfaces" in err and "Traceback" not in err
