"""MAVProxy's own log download, driven as a pilot drives it: the real MAVProxy (1.8.75, from PyPI) in a process of
its own, its console fed ``log download N FILE`` once it has found the vehicle, timed to its "Finished downloading".

MAVProxy is installed beside the project, never into its ``.venv`` (it pins its own pymavlink and pulls in
wxPython's and matplotlib's dependencies)::

    python3 -m venv /work/mavproxy-venv && /work/mavproxy-venv/bin/pip install MAVProxy==1.8.75

and found as ``$UAV_MAVPROXY``, else ``mavproxy.py`` on the PATH, else that venv's.

What MAVProxy does (MAVProxy/modules/mavproxy_log.py): one LOG_REQUEST_DATA for the whole log; each LOG_DATA
written at its offset; after 0.7 s without LOG_DATA, up to 20 requests for the lowest missing runs (or, with none
missing, for everything after the highest packet held); done on a short packet once every packet below it is held.
It never starts again from byte 0, and it never asks again for a first request that got no answer at all.
"""
from __future__ import annotations

import os
import queue
import re
import shutil
import signal
import subprocess
import tempfile
import threading
import time

VENV = "/work/mavproxy-venv/bin/mavproxy.py"
FOUND = re.compile(r"Detected vehicle \d+:\d+")
FINISHED = re.compile(r"Finished downloading .*\((\d+) bytes ([\d.]+) seconds, ([\d.]+) kbyte/sec (\d+) retries\)")
PARAMETERS = re.compile(r"Received \d+ parameters")
STATUS = re.compile(r"\((\d+) retries (\d+) missing\)")


def find() -> str | None:
    """The mavproxy.py to run, or None."""
    for candidate in (os.environ.get("UAV_MAVPROXY"), shutil.which("mavproxy.py"), VENV):
        if candidate and os.path.exists(candidate):
            return candidate
    return None


def download(mavproxy: str, master: str, number: int, out: str, limit: float, mavlink1: bool = False) -> dict:
    """Log ``number`` into ``out`` through MAVProxy on ``master`` (its --master: tcp:..., udpin:...), within
    ``limit`` s from the command. Returns ok, seconds (command to MAVProxy's "Finished"), retries (its gap
    requests) and why."""
    home = tempfile.mkdtemp(prefix="mavproxy-")        # its HOME: no ~/.mavinit.scr, no state of the user's
    cmd = [mavproxy, f"--master={master}", "--no-state"]      # its default modules, as a pilot runs it
    if mavlink1:
        cmd.append("--mav10")                          # the Solo's 3.3 reads MAVLink 1 only
    proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, cwd=home, env=dict(os.environ, PYTHONUNBUFFERED="1", HOME=home),
                            start_new_session=True)
    lines: queue.Queue = queue.Queue()
    threading.Thread(target=lambda: [lines.put((time.monotonic(), line.rstrip())) for line in proc.stdout],
                     daemon=True).start()

    def say(command: str) -> None:
        proc.stdin.write(command + "\n")
        proc.stdin.flush()

    def wait_for(pattern: re.Pattern, until: float):
        while time.monotonic() < until and proc.poll() is None:
            try:
                at, line = lines.get(timeout=0.5)
            except queue.Empty:
                continue
            found = pattern.search(line)
            if found:
                return at, found
        return None, None

    try:
        at, _ = wait_for(FOUND, time.monotonic() + 60)
        if at is None:
            return {"ok": False, "why": "MAVProxy found no vehicle in 60 s"}
        wait_for(PARAMETERS, time.monotonic() + 60)    # its start-up parameter fetch is over: the link is the log's
        start = time.monotonic()
        say(f"log download {number} {out}")
        at, done = wait_for(FINISHED, start + limit)
        if at is not None:
            return {"ok": True, "seconds": at - start, "retries": int(done.group(4)),
                    "why": f"{done.group(4)} retries; MAVProxy's own clock {float(done.group(2)):.1f} s"}
        say("log status")
        _, status = wait_for(STATUS, time.monotonic() + 5)
        told = f" ({status.group(1)} retries, {status.group(2)} packets missing)" if status else ""
        return {"ok": False, "why": f"not finished in {limit:.0f} s{told}"}
    finally:
        _stop(proc)
        shutil.rmtree(home, ignore_errors=True)


def _stop(proc: subprocess.Popen) -> None:
    """MAVProxy and its helper processes (its own session): asked, then killed, by this process group's id."""
    if proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGTERM)
            proc.wait(5)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(5)
        except ProcessLookupError:
            pass
