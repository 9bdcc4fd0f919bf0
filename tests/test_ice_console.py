"""The standalone server: its console on the real driver, and ``python -m driver`` as a process."""
from __future__ import annotations

import io
import logging
import os
import pty
import re
import select
import signal
import socket
import subprocess
import sys
import threading

import Ice

from driver.console.console import Console, vertical_speed
from driver.vehicle.state import SequencePhase

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
                           ("mode GUIDED LOITER", "usage: mode [NAME [confirm]]"),
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


def test_console_arm_check_safety_and_parachute_reach_the_vehicle(vehicle, sim):
    autopilot = sim.autopilot
    # the vehicle starts from the opposite of what the commands ask: each must reach it to show
    autopilot.params["ARMING_CHECK"] = 0
    autopilot.params["CHUTE_ENABLED"] = 0
    autopilot.safety_on = True
    console, out = console_for(vehicle)
    console.onecmd("arm check all")
    console.onecmd("arm safetyoff")
    console.onecmd("parachute enable")
    assert eventually(lambda: autopilot.params["ARMING_CHECK"] == 1 and not autopilot.safety_on
                      and autopilot.params["CHUTE_ENABLED"] == 1, 15), (autopilot.params, autopilot.safety_on)
    # and the console says what the vehicle answered: confirmed, acknowledged, or (the safety switch has no
    # acknowledgement) just sent, not "accepted (sent (not acknowledged))"
    assert eventually(lambda: "param ARMING_CHECK=1: accepted\n" in out.getvalue()
                      and "parachute enable: accepted\n" in out.getvalue(), 15), out.getvalue()
    assert "safety off: sent (not acknowledged)\n" in out.getvalue(), out.getvalue()


def test_console_refuses_at_once_what_cannot_fly(vehicle):
    """On the ground: an out-of-range takeoff and a velocity are refused with the reason, nothing "started"."""
    console, out = console_for(vehicle)
    console.onecmd("takeoff -3")
    assert out.getvalue() == "takeoff: rejected (altitude must be 1 to 50 m)\n"
    console.onecmd("velocity 1 0 0")
    assert out.getvalue().endswith("velocity not sent: take off to fly\n"), out.getvalue()
    assert not any(t.name == "console-velocity" for t in threading.enumerate())     # no 3 s hold
    assert vehicle.state().setpoint.is_zero and not vehicle.state().takeoff.active


def test_console_in_flight_refuses_a_second_takeoff_and_velocity_outside_guided(flying):
    console, out = console_for(flying)
    console.onecmd("takeoff 3")
    assert out.getvalue() == "takeoff: rejected (already flying)\n"
    console.onecmd("mode LOITER")
    assert flying.wait_for(lambda s: s.mode == "LOITER", 10), out.getvalue()
    console.onecmd("velocity 1 0 0")
    assert out.getvalue().endswith("velocity not sent: velocity flies only in GUIDED (mode is LOITER)\n"), \
        out.getvalue()
    assert not any(t.name == "console-velocity" for t in threading.enumerate())
    console.onecmd("alt")
    assert "-0.0" not in out.getvalue() and " m/s\n" in out.getvalue(), out.getvalue()


def test_vertical_speed_never_shows_minus_zero():
    assert vertical_speed(-0.04) == "climbing 0.0 m/s"
    assert vertical_speed(0.36) == "climbing 0.4 m/s"
    assert vertical_speed(-0.5) == "descending 0.5 m/s"


def test_status_while_the_takeoff_waits_says_what_is_missing(sim_factory, vehicle_factory):
    sim = sim_factory(ready_after=120.0)                 # GPS and EKF still starting
    vehicle = vehicle_factory(f"tcp:127.0.0.1:{sim.tcp_port}")
    assert vehicle.wait_for(lambda s: s.connected, 10)
    console, out = console_for(vehicle)
    console.onecmd("takeoff")
    assert out.getvalue() == "takeoff started\n"
    assert vehicle.wait_for(lambda s: s.takeoff.phase is SequencePhase.WAITING_READY and s.takeoff.detail, 10)
    console.onecmd("status")
    line = next(ln for ln in out.getvalue().splitlines() if ln.startswith("takeoff: "))
    assert line.startswith("takeoff: waiting until ready to arm (still missing: ") and "GPS fix" in line, line
    assert line.count("waiting") == 1, line
    console.onecmd("land")                               # aborts the sequence
    assert vehicle.wait_for(lambda s: not s.takeoff.active, 10)


def _server(port: int, *extra: str, stdin=None, speedup: float = 4) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "driver", "--sim", "--sim-speedup", str(speedup), "--sim-ready-after", "1",
         "--no-log", "--one-port", str(port), *extra],
        cwd=ROOT, stdin=stdin, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


class Output:
    """A child's stdout and stderr read as they come: the pipes never fill, and a failure shows them."""

    def __init__(self, proc: subprocess.Popen):
        self.out: list[str] = []
        self.err: list[str] = []
        self._threads = [threading.Thread(target=self._read, args=(pipe, lines), daemon=True)
                         for pipe, lines in ((proc.stdout, self.out), (proc.stderr, self.err))]
        for t in self._threads:
            t.start()

    @staticmethod
    def _read(pipe, lines: list[str]) -> None:
        for line in pipe:
            lines.append(line)

    def line(self, start: str) -> str | None:
        return next((line for line in list(self.out) if line.startswith(start)), None)

    def join(self) -> None:
        for t in self._threads:
            t.join(10)

    def __str__(self) -> str:
        return "stdout:\n" + "".join(self.out) + "\nstderr:\n" + "".join(self.err)


def test_python_m_driver_daemon_runs_cmd_and_serves_jderobot(sim_factory):
    # The vehicle is this test's, with no disarm of its own after arming (DISARM_DELAY 0): however slowly a busy
    # machine runs the server's takeoff, the vehicle waits for it, at any speed-up.
    sim = sim_factory(auto_disarm_after=0)
    port = free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "driver", "--master", f"tcp:127.0.0.1:{sim.tcp_port}", "--no-log",
         "--one-port", str(port), "--daemon", "--cmd", "takeoff 2"],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    output = Output(proc)
    com = Ice.initialize(["--Ice.Default.InvocationTimeout=3000"])
    try:
        result = eventually(lambda: output.line("takeoff: ") or proc.poll() is not None, 90, interval=0.2)
        assert result and output.line("takeoff: accepted"), output        # the sequence's own answer
        pose3d = jderobot.Pose3DPrx.uncheckedCast(com.stringToProxy(f"Pose3D:tcp -h 127.0.0.1 -p {port}"))
        status = mavlinkserver.VehiclePrx.uncheckedCast(com.stringToProxy(f"Vehicle:tcp -h 127.0.0.1 -p {port}"))
        assert eventually(lambda: pose3d.getPose3DData().z > 1.7, 10), (pose3d.getPose3DData(), output)
        assert status.getStatus(-1, -1).mode == "GUIDED"
        truth = sim.truth()
        assert truth.armed and truth.mode == "GUIDED" and truth.altitude > 1.7, truth
    finally:
        com.destroy()
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=20)
        output.join()
    assert proc.returncode == 0, output
    text = "".join(output.out)
    assert f"-p {port}" in text and "serving Pose3D" in text
    # the takeoff waited for the vehicle: it ran once, and succeeded the first time
    assert text.count("takeoff: ") == 1, output


def test_python_m_driver_console_reads_commands_from_stdin():
    proc = _server(free_port(), "--cmd", "bat; alt", stdin=subprocess.PIPE)
    out, err = proc.communicate("help\nbogus\nvelocity x 0 0\nmode XYZ\nstatus\nexit\n", timeout=60)
    assert proc.returncode == 0, err
    assert "Documented commands" in out and "unknown command 'bogus'" in out
    assert "error: X must be a number" in out and "link " in out
    # --cmd waited for the vehicle: the battery is known, not "voltage unknown"
    assert "> bat\nbattery " in out and "voltage unknown" not in out, out
    assert "m above home" in out
    # a rejection is shown once, not again by the driver's log
    assert (out + err).count("mode XYZ: rejected") == 1, out + err


def test_console_prints_each_result_and_message_once(vehicle):
    console, out = console_for(vehicle)
    handler = console.log_handler()                     # as python -m driver installs it
    root = logging.getLogger()
    root.addHandler(handler)
    try:
        assert vehicle.wait_for(lambda s: s.connected, 10)
        console.watch_messages(interval=0.05)
        console.onecmd("mode XYZ")                      # typed here
        vehicle.set_mode("ABC")                         # asked for elsewhere (an Ice client)
        vehicle.command_long(31000, (0,) * 7, "user command")   # the vehicle's own refusal, later
        assert eventually(lambda: "mode ABC: rejected" in out.getvalue()
                          and "user command: " in out.getvalue(), 15), out.getvalue()
        logging.getLogger("driver.ice.servants").warning("Extra.ledAnimation(1, 1.0, 1.0): not supported")
    finally:
        console.stop_watching()
        root.removeHandler(handler)
    text = out.getvalue()
    for line in ("mode XYZ: rejected", "mode ABC: rejected", "user command: "):
        assert text.count(line) == 1, text
    assert "WARNING driver.ice.servants: Extra.ledAnimation(1, 1.0, 1.0): not supported" in text


def test_python_m_driver_says_when_its_port_is_taken():
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        proc = _server(port, "--daemon")
        out, err = proc.communicate(timeout=60)
    assert proc.returncode == 1
    # one line that names the address (every interface shares the one port here)
    assert f"\ncannot serve the Ice interfaces on 127.0.0.1:{port}: address already in use\n" in err, err
    assert "Traceback" not in err


def test_console_on_a_terminal_shows_extra_events_above_the_typed_line():
    """At the default level (WARNING) an Ice client's unsupported request is shown, on a fresh line, and the
    prompt with the half-typed command is drawn again below it."""
    port = free_port()
    master, terminal = pty.openpty()
    proc = subprocess.Popen(
        [sys.executable, "-m", "driver", "--sim", "--sim-speedup", "4", "--sim-ready-after", "1", "--no-log",
         "--one-port", str(port)],
        cwd=ROOT, stdin=terminal, stdout=terminal, stderr=terminal, env={**os.environ, "TERM": "dumb"})
    os.close(terminal)
    seen = bytearray()

    def screen() -> str:
        while select.select([master], [], [], 0)[0]:
            try:
                chunk = os.read(master, 65536)
            except OSError:                             # the child closed the terminal
                break
            if not chunk:
                break
            seen.extend(chunk)
        return seen.decode(errors="replace")

    com = Ice.initialize(["--Ice.Default.InvocationTimeout=3000"])
    try:
        assert eventually(lambda: re.search(r"\n[A-Z_]+> $", screen()), 30), screen()
        os.write(master, b"sta")                       # half a command, no Enter
        assert eventually(lambda: screen().endswith("sta"), 10), screen()
        extra = jderobot.ArDroneExtraPrx.uncheckedCast(com.stringToProxy(f"Extra:tcp -h 127.0.0.1 -p {port}"))
        extra.ledAnimation(1, 1.0, 1.0)
        extra.flightAnimation(2, 1.0)
        shown = re.compile(r"\r\x1b\[K[^\n]*flightAnimation\(2, 1\.0\): not supported on ArduCopter\r?\n"
                           r"[A-Z_]+> sta$")
        assert eventually(lambda: shown.search(screen()), 10), screen()
        assert "ledAnimation(1, 1.0, 1.0): not supported on ArduCopter" in screen()
        os.write(master, b"tus\n")                     # the typed text is still there: "status" runs
        assert eventually(lambda: "link ok" in screen() or "link waiting" in screen(), 10), screen()
        os.write(master, b"exit\n")
        assert proc.wait(timeout=20) == 0, screen()
    finally:
        com.destroy()
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        os.close(master)


def test_console_sets_up_signing_and_shows_it(vehicle, sim):
    console, out = console_for(vehicle)
    console.onecmd("signing status")
    assert out.getvalue() == "signing off\n"
    console.onecmd("signing setup uavviewer-test")
    assert eventually(lambda: "signing setup: accepted (the vehicle now signs with the new key)" in out.getvalue(),
                      20), out.getvalue()
    assert sim.signing.key is not None
    assert vehicle.wait_for(lambda s: s.signing.signed_accepted > 0, 10)
    console.onecmd("signing status")
    assert "signing signing (both ends sign; link id " in out.getvalue(), out.getvalue()
    console.onecmd("status")
    assert out.getvalue().count("signing signing (both ends sign") == 2
    console.onecmd("signing frobnicate")
    assert "error: usage: signing setup PASSPHRASE" in out.getvalue()
    console.onecmd("signing remove")
    assert eventually(lambda: "signing remove: accepted" in out.getvalue(), 20), out.getvalue()
    assert sim.signing.key is None


def test_console_stops_the_motors_in_flight_only_when_told_it_is_an_emergency(flying, sim):
    console, out = console_for(flying)
    console.onecmd("disarm force")
    assert "disarm (forced): rejected (the vehicle may be airborne" in out.getvalue()
    console.onecmd("disarm force now")
    assert "error: usage: disarm [force] | disarm force emergency" in out.getvalue()
    assert sim.truth().armed
    console.onecmd("disarm force emergency")
    assert eventually(lambda: "emergency motor stop: accepted" in out.getvalue(), 10), out.getvalue()
    assert eventually(lambda: not sim.truth().armed, 10)
