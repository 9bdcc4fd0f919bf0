"""``python -m driver`` and ``python -m driver.sim`` as a fresh user runs them: bad input is one usage error
(exit 2) at once, never a traceback or a link retried forever; a taken port is named; SIGTERM cleans up."""
from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys

import pytest

from driver.__main__ import parser
from driver.ice.server import DEFAULT_PORTS

from ice_fixtures import eventually, free_port
from patience import patient
from test_ice_console import Output

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def run(module: str, *args: str, cwd, timeout: float = 30) -> subprocess.CompletedProcess:
    """The program in a scratch directory (a log it might write stays there); killed if it outlives ``timeout``
    stretched by PATIENCE (a program started on a loaded machine takes seconds to import)."""
    timeout = patient(timeout)
    proc = subprocess.Popen([sys.executable, "-m", module, *args], cwd=cwd, stdin=subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONPATH": ROOT})
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        pytest.fail(f"still running after {timeout} s:\n{out}\n{err}")
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def run_here(main, args, cwd, capsys, monkeypatch) -> subprocess.CompletedProcess:
    """The program's ``main(args)`` in this process, for the cases that end before anything starts: what a fresh
    process would print and exit with, without its second of start-up (a traceback fails the test). The first
    case of each list runs as a fresh user runs it, in a process of its own."""
    monkeypatch.chdir(cwd)
    try:
        code = main(list(args))
    except SystemExit as exc:
        code = exc.code
    out, err = capsys.readouterr()
    return subprocess.CompletedProcess(args, code, out, err)


@pytest.mark.parametrize("args, reason", [
    (["--sim", "--sim-speedup", "0"], "argument --sim-speedup: '0': a positive number is needed"),
    (["--sim", "--sim-ready-after", "-1"], "argument --sim-ready-after: '-1': zero or a positive number is needed"),
    (["--sim", "--Ice.Config=/nope.cfg"], "cannot read the Ice configuration /nope.cfg: no such file or directory"),
    (["--sim", "--streamrate", "-1"], "argument --streamrate: '-1': a whole number from 1 to 50 is needed"),
    (["--sim", "--one-port", "99999"], "argument --one-port: '99999': a whole number from 1 to 65535 is needed"),
    (["--sim", "--takeoff-alt", "-3"], "argument --takeoff-alt: '-3': altitude must be 1 to 50 m"),
    (["--sim", "--MAVLinkServer.TakeoffAltitude=500"],
     "MAVLinkServer.TakeoffAltitude=500: altitude must be 1 to 50 m"),
    (["--master", "/nope.tlog"], "argument --master: no such flight log: /nope.tlog"),
    (["--master", "foo:bar"], "argument --master: 'foo:bar' is not a connection string: a link is udpin:HOST:PORT, "
     "udpout:HOST:PORT, tcp:HOST:PORT, a serial device such as /dev/ttyUSB0, or a .tlog file"),
    (["--sim", "--out", "udp:localhost"], "argument --out: 'udp:localhost': udp needs HOST:PORT"),
    (["--sim", "--signing-key-file", "/nope.key"], "--signing-key-file: /nope.key: No such file or directory"),
    (["--sim", "--signing-key-file", "OPEN"], "--signing-key-file: OPEN can be read by other users: chmod 600 OPEN"),
    (["--sim", "--signing-passphrase", "a", "--signing-key-file", "b"],
     "argument --signing-key-file: not allowed with argument --signing-passphrase"),
    (["--sim", "--allow", "10.1.1.1:port"], "--allow '10.1.1.1:port': expected ADDRESS or ADDRESS:PORT"),
    (["--sim", "--count", "2"], "--count needs --registry (the vehicles are told apart by name: "
     "python -m driver registry)"),
])
def test_bad_options_are_one_usage_error(args, reason, tmp_path, capsys, monkeypatch):
    if "OPEN" in args:                                    # a key file every user of the machine can read
        key = tmp_path / "open.key"
        key.write_text("a passphrase\n")
        os.chmod(key, 0o644)
        args = [str(key) if a == "OPEN" else a for a in args]
        reason = reason.replace("OPEN", str(key))
    if reason.startswith("argument --sim-speedup"):
        done = run("driver", *args, "--daemon", cwd=tmp_path)
    else:
        from driver.__main__ import main
        done = run_here(main, [*args, "--daemon"], tmp_path, capsys, monkeypatch)
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr and "exception ::Ice" not in done.stderr, done.stderr
    assert done.stderr.splitlines()[-1] == f"python -m driver: error: {reason}", done.stderr


@pytest.mark.parametrize("args, reason", [
    (["--speedup", "0"], "argument --speedup: '0': a positive number is needed"),
    (["--ready-after", "-2"], "argument --ready-after: '-2': zero or a positive number is needed"),
    (["--tcp", "127.0.0.1:99999"], "argument --tcp: '127.0.0.1:99999': the port must be a number from 0 to 65535"),
])
def test_simulator_bad_options_are_one_usage_error(args, reason, tmp_path, capsys, monkeypatch):
    if args[0] == "--speedup":
        done = run("driver.sim", *args, cwd=tmp_path)
    else:
        from driver.sim.__main__ import main
        done = run_here(main, args, tmp_path, capsys, monkeypatch)
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert done.stderr.splitlines()[-1] == f"python -m driver.sim: error: {reason}", done.stderr


def test_a_taken_port_is_named_for_each_interface(tmp_path):
    """Each interface on its own port: the one that cannot bind is named, with its address, in one line."""
    ports = {name: free_port() for name in DEFAULT_PORTS}
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        ports["Pose3D"] = taken.getsockname()[1]
        endpoints = [f"--MAVLinkServer.{name}.Endpoints=default -h 127.0.0.1 -p {port}"
                     for name, port in ports.items()]
        done = run("driver", "--sim", "--sim-speedup", "4", "--no-log", "--daemon", *endpoints, cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    assert f"cannot serve Pose3D on 127.0.0.1:{ports['Pose3D']}: address already in use\n" in done.stderr, \
        done.stderr
    assert "Traceback" not in done.stderr and "Ice.SocketException" not in done.stderr


def test_simulator_names_the_address_it_cannot_serve(tmp_path):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        address = f"127.0.0.1:{taken.getsockname()[1]}"
        done = run("driver.sim", "--tcp", address, cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    assert f"cannot serve MAVLink on tcp:{address}: address already in use" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr


def test_sigterm_stops_the_interactive_server_cleanly(tmp_path):
    """SIGTERM while the console waits for a line ends main() like exit does: clean-up, then exit status 0."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "driver", "--sim", "--sim-speedup", "4", "--no-log", "--one-port", str(free_port())],
        cwd=tmp_path, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "PYTHONPATH": ROOT})
    output = Output(proc)
    try:
        assert eventually(lambda: output.line("serving Vehicle") or proc.poll() is not None, 30), output
        assert proc.poll() is None, output
        proc.send_signal(signal.SIGTERM)                 # stdin stays open: the console is waiting in input()
        proc.wait(timeout=patient(20))
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        proc.stdin.close()
        output.join()
    assert proc.returncode == 0, output
    assert "Traceback" not in "".join(output.err), output


def test_the_demo_simulator_is_ready_in_seconds():
    """``python -m driver --sim`` and the viewer's ``--sim`` share one demo readiness delay: a few seconds, not a
    real vehicle's GPS and EKF start-up (SimConfig's own default)."""
    from uavviewer import app as main
    from driver.sim import SimConfig
    server = parser().parse_args(["--sim"]).sim_ready_after
    viewer = main.build_parser().parse_args(["--sim"]).ready_after
    assert server == viewer
    assert 0 < server <= 5.0 < SimConfig().ready_after, server
