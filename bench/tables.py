"""One way every bench prints its tables, and one writer of docs/benchmarks.md.

Every bench that prints figures takes ``--write-docs`` (:func:`add_write_docs`) and runs its ``main`` inside
:func:`publishing`: what it prints to stdout goes to the terminal as before and, with ``--write-docs``, also
replaces that bench's own marked section of docs/benchmarks.md, under the exact command that made it, the commit
(``git rev-parse --short HEAD``, "+dirty" when tracked files differ from it), the date and the machine's load. While
a bench publishes, :func:`render` gives Markdown whatever ``--markdown`` says, so its tables stay tables there.
Nothing else writes that file: it is never edited by hand.

    python bench/tables.py --placeholders     # the file with a "not yet run" section for every bench missing
    python bench/tables.py --merge OTHER/docs/benchmarks.md   # the sections another checkout's benches wrote
"""
from __future__ import annotations

import contextlib
import io
import os
import re
import shlex
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOCS = os.path.join(ROOT, "docs", "benchmarks.md")

#: (section, title): the order of docs/benchmarks.md. A section "name/options" not listed (one bench run with other
#: options, kept apart: :func:`variant`) follows its "name".
SECTIONS = (
    ("ingest", "Telemetry ingest against raw pymavlink parsing (`bench/bench_ingest.py`)"),
    ("setpoints", "The velocity stream and the deadman at the vehicle (`bench/bench_setpoints.py`)"),
    ("ice", "JdeRobot calls against the empty Ice call; stick to wire (`bench/bench_ice.py`)"),
    ("ice_flood", "Ice clients flooding the server against the flight threads (`bench/bench_ice_flood.py`)"),
    ("camera", "Camera: 720p30 through the viewer, Ice getImageData (`bench/bench_camera.py`)"),
    ("video_latency", "Glass-to-glass video latency (`bench/bench_video_latency.py`)"),
    ("viewer", "The window while flying: UI lateness, redraws, CPU (`bench/bench_viewer.py`)"),
    ("pilot_tools", "Switching connections, alerts, preflight (`bench/bench_pilot_tools.py`)"),
    ("plan_map", "The plan on the map (`bench/bench_plan_map.py`)"),
    ("fleet_map", "The fleet on the map (`bench/bench_fleet_map.py`)"),
    ("fleet", "Observers of a MAVLinkServer: polling against IceStorm (`bench/bench_fleet.py`)"),
    ("gimbal", "Gimbal and camera on the vehicle (`bench/bench_gimbal.py`)"),
    ("mission", "Mission upload over a slow, lossy link (`bench/bench_mission.py`)"),
    ("params", "The whole parameter list against the link's floor (`bench/bench_params.py`)"),
    ("params_page", "The Parameters page with 1,392 parameters (`bench/bench_params_page.py`)"),
    ("setup", "Calibrations and the motor test (`bench/bench_setup.py`)"),
    ("review", "A 100 MB DataFlash log in the review (`bench/bench_review.py`)"),
    ("logs", "Log download: the driver against the link's floor (`bench/bench_logs.py`)"),
    ("logs/mavproxy", "Log download: the driver against MAVProxy 1.8.75, on the simulator (`bench/bench_logs.py`)"),
    ("logs/sitl", "Log download: the driver against MAVProxy 1.8.75, on ArduCopter 4.6.3 SITL "
                  "(`bench/bench_logs.py --sitl`)"),
    ("hostile", "Hostile inputs against a signed, pinned link (`bench/hostile.py`)"),
    ("chaos", "Pilot chaos: random pilot sequences under random faults, every rule judged (`bench/chaos.py`)"),
    ("transfer_matrix", "Plans through every fault (`bench/transfer_matrix.py`)"),
    ("fault_matrix", "The fault matrix: every answer checked against the vehicle (`bench/fault_matrix.py`)"),
    ("real_sitl", "Against real firmware: ArduCopter 4.6.3 SITL (`bench/real_sitl.py`)"),
    ("real_sitl_setup", "Setup procedures on ArduCopter 4.6.3 SITL's calibration model (`bench/real_sitl_setup.py`)"),
    ("mission_start", "A mission started through a lossy link, on ArduCopter 4.6.3 SITL (`bench/mission_start.py`)"),
    ("chaos_sitl", "Pilot chaos on ArduCopter 4.6.3 SITL (`bench/chaos_sitl.py`, or `bench/chaos.py --sitl`)"),
)
TITLES = dict(SECTIONS)
#: The commands that write a section, for the sections whose bench takes long or needs more than this checkout.
COMMANDS = {
    "logs": ["python bench/bench_logs.py --sizes 2,20 --paths log_data,ftp --loss 0,10,30 --links tcp,radio,solo "
             "--cell-limit 1800 --write-docs"],
    "logs/mavproxy": ["python bench/bench_logs.py --sizes 2 --paths log_data,mavproxy --loss 0,10,30 "
                      "--loss-at sim,relay --runs 3 --cell-limit 900 --write-docs"],
    "logs/sitl": ["python bench/bench_logs.py --sitl /work/sitl/ardupilot/build/sitl/bin/arducopter --sizes 2 "
                  "--paths log_data,mavproxy --loss 0,10,30 --loss-at sim,relay --runs 3 --cell-limit 900 "
                  "--write-docs"],
    "fault_matrix": ["python bench/fault_matrix.py --write-docs"],
    "real_sitl": ["python bench/real_sitl.py --sitl /work/sitl/ardupilot/build/sitl/bin/arducopter --write-docs",
                  "python bench/real_sitl.py --sitl /work/sitl/ardupilot/build/sitl/bin/arducopter --loss 0 "
                  "--write-docs"],
    "video_latency": ["python bench/bench_video_latency.py --seconds 20 --write-docs"],
    "chaos": ["python bench/chaos.py --write-docs"],
    "real_sitl_setup": ["python bench/real_sitl_setup.py --sitl /work/sitl/ardupilot/build/sitl/bin/arducopter "
                        "--write-docs"],
    "mission_start": ["python bench/mission_start.py --sitl /work/sitl/ardupilot/build/sitl/bin/arducopter "
                      "--shim /work/sitl/bind_loopback.so --write-docs"],
    "chaos_sitl": ["python bench/chaos.py --sitl /work/sitl/ardupilot/build/sitl/bin/arducopter "
                   "--shim /work/sitl/bind_loopback.so --sequences 20 --write-docs"],
}

HEADER = """<!-- Generated by the bench scripts (bench/tables.py). Never edit this file by hand: run the bench again. -->
# Benchmarks

**This file is generated.** Each section below is written by its bench script, run with `--write-docs`, and
replaced whole when the bench runs again; nobody edits it by hand. A section gives the exact command that made
it, the commit it ran on (`+dirty`: with changes to tracked files not yet committed), the date (UTC) and the
machine's load average when it started. The development machine has 2 cores shared with other jobs, so figures
move by about ±10 % from run to run; the load says how busy it was. What each bench measures, and why, is in its
own docstring (`python bench/NAME.py --help`) and in the docs each section links from.
"""

_START = "<!-- bench:{} -->"
_END = "<!-- /bench:{} -->"
_SECTION = re.compile(r"<!-- bench:(?P<name>[^>]+?) -->\n.*?<!-- /bench:(?P=name) -->\n", re.S)

_publishing = False


def render(head, rows, markdown_asked: bool) -> list[str]:
    """The table's lines: ``head`` and ``rows`` are sequences of strings. Markdown when asked, or while the bench
    publishes to docs/benchmarks.md."""
    if markdown(markdown_asked):
        return (["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
                + ["| " + " | ".join(r) + " |" for r in rows])
    widths = [max(len(x) for x in col) for col in zip(head, *rows)]
    return ["  ".join(x.ljust(w) for x, w in zip(r, widths)) for r in (head, *rows)]


def markdown(asked: bool) -> bool:
    """Whether a bench prints Markdown: when asked, and whenever it publishes."""
    return asked or _publishing


def add_write_docs(parser) -> None:
    """The one flag every bench takes to publish what it prints."""
    parser.add_argument("--write-docs", action="store_true",
                        help="also replace this bench's section of docs/benchmarks.md with what it prints")


def variant(section: str, *options: str) -> str:
    """``section``, or ``section/a,b=v`` naming those of ``options`` this command gives (with the value of one that
    takes a value): a bench run with other options keeps a section of its own instead of replacing the other's."""
    argv, given = sys.argv[1:], []
    for i, arg in enumerate(argv):
        name, _, value = arg.partition("=")
        if name not in options:
            continue
        if not value and i + 1 < len(argv) and not argv[i + 1].startswith("-"):
            value = argv[i + 1]
        given.append(name.lstrip("-") + (f"={value}" if value else ""))
    return section + ("/" + ",".join(given) if given else "")


@contextlib.contextmanager
def publishing(section: str, enabled: bool | None = None):
    """Run a bench's main inside this: with ``--write-docs`` on its command line (or ``enabled``), what it prints
    to stdout also becomes ``section`` of docs/benchmarks.md when it ends, by returning or by ``sys.exit`` (its
    verdict, given with the section). A bench that fails with an exception, or prints nothing, writes nothing."""
    global _publishing
    if enabled is None:
        enabled = "--write-docs" in sys.argv[1:]
    if not enabled:
        yield
        return
    command, started, load = _command(), time.gmtime(), os.getloadavg()[0]
    revision = commit()
    captured = io.StringIO()
    real = sys.stdout
    sys.stdout = _Tee(real, captured)
    _publishing = True
    status, failed = 0, False
    try:
        yield
    except SystemExit as exc:
        status = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        raise
    except BaseException:
        failed = True
        raise
    finally:
        sys.stdout = real
        _publishing = False
        text = captured.getvalue()
        if text.strip() and not failed:
            write_section(section, markdown_of(text), command, revision, started, load, status)
            print(f"(docs/benchmarks.md: section {section} written)", file=sys.stderr)


class _Tee(io.TextIOBase):
    def __init__(self, *streams) -> None:
        self._streams = streams

    def write(self, text: str) -> int:
        for s in self._streams:
            s.write(text)
        return len(text)

    def flush(self) -> None:
        for s in self._streams:
            s.flush()


def commit() -> str:
    """The short commit, "+dirty" when tracked files differ from it; "unknown" outside a git checkout."""
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                              check=True).stdout.strip()
        changes = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=ROOT,
                                 capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + ("+dirty" if changes else "")


def _command() -> str:
    """This process's command line as typed from the checkout's root."""
    python = sys.executable
    venv = os.path.join(ROOT, ".venv")
    if os.path.abspath(python).startswith(venv + os.sep):
        python = os.path.relpath(python, ROOT)
    elif os.path.basename(python).startswith("python"):
        python = "python"
    script = os.path.relpath(os.path.abspath(sys.argv[0]), ROOT)
    env = [f"{k}={os.environ[k]}" for k in ("QT_QPA_PLATFORM",) if k in os.environ]
    return shlex.join([*env, python, script, *sys.argv[1:]])


def markdown_of(text: str) -> str:
    """A bench's output as Markdown: its Markdown tables as they are, every other run of lines as a text block."""
    out: list[str] = []
    plain: list[str] = []

    def flush_plain() -> None:
        while plain and not plain[-1].strip():
            plain.pop()
        if plain:
            out.extend(["", "```text", *plain, "```", ""])
        plain.clear()

    in_table = False
    for line in text.splitlines():
        if line.startswith("|"):
            if not in_table:
                flush_plain()
                out.append("")
                in_table = True
            out.append(line)
            continue
        if in_table:
            out.append("")
            in_table = False
        if plain or line.strip():
            plain.append(line.rstrip())
    flush_plain()
    body = "\n".join(out).strip("\n")
    return re.sub(r"\n{3,}", "\n\n", body)


def title_of(section: str) -> str:
    base = section.split("/", 1)[0]
    title = TITLES.get(section) or TITLES.get(base, f"`{base}`")
    if section not in TITLES and "/" in section:
        title += ", with " + ", ".join(f"`--{o.replace('=', ' ')}`" for o in section.split("/", 1)[1].split(","))
    return title


def section_text(section: str, body: str) -> str:
    return f"{_START.format(section)}\n## {title_of(section)}\n\n{body}\n{_END.format(section)}\n"


def write_section(section: str, body: str, command: str, revision: str, started: time.struct_time, load: float,
                  status: int = 0) -> None:
    """Replace ``section`` of docs/benchmarks.md (or add it in its place), keeping every other section."""
    stamp = time.strftime("%Y-%m-%d %H:%M UTC", started)
    head = (f"Command: `{command}`  \nRun on commit `{revision}`, {stamp}; load average {load:.1f} at the start "
            f"({os.cpu_count()} cores)" + (f"; the bench exited with status {status}" if status else "") + ".")
    with _locked():                        # two benches ending together must not drop each other's section
        sections = read_sections()
        sections[section] = section_text(section, f"{head}\n\n{body}")
        _write(sections)


@contextlib.contextmanager
def _locked():
    import fcntl
    with open(DOCS + ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def read_sections(path: str | None = None) -> dict[str, str]:
    try:
        with open(path or DOCS, encoding="utf-8") as f:
            text = f.read()
    except FileNotFoundError:
        return {}
    return {m.group("name"): m.group(0) for m in _SECTION.finditer(text)}


def placeholder(section: str) -> str:
    commands = " and ".join(f"`{c}`" for c in COMMANDS.get(section, ())) or "its bench run with `--write-docs`"
    return section_text(section, f"Not yet run on this commit; written by {commands}.")


def _write(sections: dict[str, str]) -> None:
    order = [name for name, _ in SECTIONS]

    def key(name: str) -> tuple:
        if name in order:
            return (order.index(name), 0, name)
        base = name.split("/", 1)[0]
        return (order.index(base) if base in order else len(order), 1, name)
    def titled(name: str) -> str:              # the heading is this file's own: the current title, kept in step
        start, _, rest = sections[name].partition("\n")
        heading, _, body = rest.partition("\n")
        return f"{start}\n## {title_of(name)}\n{body}" if heading.startswith("## ") else sections[name]
    parts = [HEADER] + [titled(name) for name in sorted(sections, key=key)]
    tmp = DOCS + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        f.write("\n".join(parts))
    os.replace(tmp, DOCS)


def main() -> None:
    import argparse
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--placeholders", action="store_true",
                   help="add a 'not yet run on this commit' section for every bench that has none")
    p.add_argument("--not-run", metavar="SECTION", action="append", default=[],
                   help="mark SECTION 'not yet run on this commit' (a bench whose figures no longer hold)")
    p.add_argument("--merge", metavar="FILE", action="append", default=[],
                   help="take every section of FILE, as written by the benches of another checkout (a long bench "
                        "run apart), over this file's")
    args = p.parse_args()
    with _locked():
        sections = read_sections()
        for path in args.merge:
            sections.update(read_sections(path))
        if args.placeholders:
            for name, _ in SECTIONS:
                sections.setdefault(name, placeholder(name))
        for name in args.not_run:
            sections[name] = placeholder(name)
        _write(sections)


if __name__ == "__main__":
    main()
