"""The installed form: the wheel built from pyproject.toml, installed into a fresh venv outside the checkout, gives
``uavviewer``, ``mavlinkserver`` and ``python -m uavviewer`` that answer and fly; and the set-up's ZeroC Ice is
the one pinned, seen without the rest of the system's packages."""
from __future__ import annotations

import fcntl
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import tomllib
import zipfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Callable

import pytest

ROOT = Path(__file__).resolve().parent.parent
BOOTSTRAP = (ROOT / "scripts" / "bootstrap").read_text()
PINS = {name: re.search(rf'^{name}=(\S+)', BOOTSTRAP, re.M).group(1) for name in ("DEBIAN_ICE", "SOURCE_ICE")}
ICE_STAMP = Path(sys.prefix) / ".ice"                   # written by scripts/bootstrap: "debian 3.7.8", "source 3.7.11"


def bootstrap_ice() -> tuple[str, str] | None:
    """(origin, version) of the venv the suite runs in, or None outside one made by scripts/bootstrap."""
    if not ICE_STAMP.is_file():
        return None
    origin, version = ICE_STAMP.read_text().split()
    return origin, version


def test_the_suite_runs_on_the_ice_the_set_up_pinned():
    import Ice
    assert Ice.stringVersion() in (PINS["DEBIAN_ICE"], PINS["SOURCE_ICE"])
    made = bootstrap_ice()
    if os.environ.get("CI"):
        assert made is not None, f"CI runs in scripts/bootstrap's venv, which writes {ICE_STAMP}"
    if made is not None:
        origin, version = made
        assert Ice.stringVersion() == version == PINS[f"{origin.upper()}_ICE"]
        if origin == "debian":                           # the module is Debian's, reached through the venv's link
            assert Path(Ice.__file__).resolve().is_relative_to("/usr/lib/python3/dist-packages")
            assert Path(Ice.__file__).is_relative_to(Path(sys.prefix) / "debian-ice")


@pytest.mark.skipif((bootstrap_ice() or ("",))[0] != "debian", reason="the suite runs on an Ice built from source")
def test_only_ice_comes_from_the_systems_packages():
    assert not any(p.rstrip("/").endswith(("dist-packages", "site-packages")) and not p.startswith(sys.prefix)
                   for p in sys.path), sys.path
    linked = sorted(p.name for p in (Path(sys.prefix) / "debian-ice").iterdir())
    assert linked == sorted(["Glacier2", "Ice", "IceBox", "IceGrid", "IceMX", "IcePatch2", "IceStorm",
                             "IcePy" + sysconfig.get_config_var("EXT_SUFFIX")])
    import importlib.metadata
    assert importlib.metadata.version("zeroc-ice") == PINS["DEBIAN_ICE"]      # pip knows what is there


def plan(env: dict[str, str]) -> str:
    out = subprocess.run(["bash", str(ROOT / "scripts" / "bootstrap"), "--plan"], env=env, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return out.stdout.strip()


def test_the_source_build_is_taken_when_asked_or_without_apt(tmp_path):
    assert plan({**os.environ, "UAV_ICE": "source"}) == f"source {PINS['SOURCE_ICE']}"
    bare = tmp_path / "bin"                               # a machine with no apt-get (another distribution)
    bare.mkdir()
    for tool in ("bash", "cat", "dpkg", "dirname", "id", "awk"):
        (bare / tool).symlink_to(subprocess.run(["bash", "-c", f"command -v {tool}"], capture_output=True,
                                                text=True).stdout.strip())
    assert plan({**os.environ, "PATH": str(bare)}) == f"source {PINS['SOURCE_ICE']}"
    if bootstrap_ice() and bootstrap_ice()[0] == "debian":
        assert plan(dict(os.environ)) == f"debian {PINS['DEBIAN_ICE']}"


def test_the_packages_pins_are_the_requirements():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    required = dict(line.split("==") for line in (ROOT / "requirements.txt").read_text().splitlines()
                    if "==" in line and not line.startswith("#"))
    pinned = [d for d in project["project"]["dependencies"] if "==" in d]
    assert pinned and all(required[name] == version for name, version in (d.split("==") for d in pinned))
    assert [d for d in project["project"]["dependencies"] if "==" not in d] == \
        [f"zeroc-ice>={PINS['DEBIAN_ICE']},<3.8"]
    backend, = project["build-system"]["requires"]
    assert backend == f"hatchling=={required['hatchling']}"


def built_once(tmp_path_factory, name: str, build: Callable[[Path], None]) -> Path:
    """A folder this test run builds once, in whichever worker asks first; the others wait on a lock and use it.
    (``xdist_group`` cannot keep its users on one worker: pytest-xdist 3.8 tags ``item._nodeid``, which pytest 9
    no longer reads, so ``--dist loadgroup`` spread them and each worker built its own.)"""
    run = os.environ.get("PYTEST_XDIST_TESTRUNUID")
    if run is None:                                          # one process: nothing to share
        folder = tmp_path_factory.mktemp(name)
        build(folder)
        return folder
    root = tmp_path_factory.getbasetemp().parent / f"{name}-{run}"       # this run's, shared by its workers
    root.mkdir(exist_ok=True)
    folder = root / "built"
    with open(root / "lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (root / "done").exists():
            shutil.rmtree(folder, ignore_errors=True)        # a worker that failed half-way
            folder.mkdir()
            build(folder)
            (root / "done").touch()
    return folder


@pytest.fixture(scope="session")
def wheel(tmp_path_factory) -> Path:
    def build(out: Path) -> None:
        subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation",
                        "--disable-pip-version-check", "-w", str(out), str(ROOT)], check=True, timeout=120)
    found, = built_once(tmp_path_factory, "wheel", build).glob("uavviewerpy-*.whl")
    return found


def required_here(wheel: Path) -> list[Path]:
    """The top-level files of every distribution the wheel requires (and they require), as installed in the
    suite's own venv: exactly what pip would unpack from the same pinned wheels, and nothing else."""
    import importlib.metadata
    from packaging.requirements import Requirement
    from packaging.utils import canonicalize_name
    metadata = zipfile.ZipFile(wheel).read(next(n for n in zipfile.ZipFile(wheel).namelist()
                                                if n.endswith(".dist-info/METADATA"))).decode()
    todo = [line.split(":", 1)[1].strip() for line in metadata.splitlines() if line.startswith("Requires-Dist:")]
    seen, tops = set(), set()
    while todo:
        req = Requirement(todo.pop())
        if (req.marker and not req.marker.evaluate({"extra": ""})) or canonicalize_name(req.name) in seen:
            continue
        seen.add(canonicalize_name(req.name))
        dist = importlib.metadata.distribution(req.name)
        assert dist.version in req.specifier, (req, dist.version)
        for f in dist.files or ():
            top = Path(dist.locate_file(f.parts[0]))
            if f.parts[0] not in ("..", "__pycache__") and top.exists() and top.parent == Path(dist.locate_file("")):
                tops.add(top)
        todo += dist.requires or []
    return sorted(tops)


@pytest.fixture(scope="session")
def installed(wheel, tmp_path_factory) -> Path:
    """A fresh venv (this Python's base interpreter) with the wheel installed by pip, which finds each of its
    dependencies (and theirs) at its pinned version already there: linked from the suite's venv, one link per
    top-level module of a required distribution, through one .pth file (copying PyQt5, numpy and OpenCV again
    took 14 s of this 22 s set-up). Built once per test run."""
    def build(folder: Path) -> None:
        venv = folder / "venv"
        subprocess.run([getattr(sys, "_base_executable", sys.executable), "-m", "venv", "--without-pip", str(venv)],
                       check=True, timeout=120)
        if (bootstrap_ice() or ("",))[0] == "debian":         # as scripts/bootstrap did for .venv
            subprocess.run([str(ROOT / "scripts" / "link-debian-ice"), str(venv), PINS["DEBIAN_ICE"]], check=True)
        deps = venv / "dependencies"
        deps.mkdir()
        for top in required_here(wheel):
            if not (deps / top.name).exists():
                (deps / top.name).symlink_to(top)
        purelib = sysconfig.get_path("purelib", vars={"base": str(venv), "platbase": str(venv)})
        Path(purelib, "dependencies.pth").write_text(f"{deps}\n")
        subprocess.run([sys.executable, "-m", "pip", "--python", str(venv / "bin" / "python"), "install", "-q",
                        "--disable-pip-version-check", str(wheel)], check=True, timeout=600)
    return built_once(tmp_path_factory, "installed", build) / "venv"


def run_installed(venv: Path, *argv: str, cwd: Path, timeout: float = 60, **env: str) -> subprocess.CompletedProcess:
    """A command of the installed venv, from a folder outside the checkout, with the checkout off the path."""
    clean = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    clean.update(PATH=f"{venv / 'bin'}:{os.environ['PATH']}", QT_QPA_PLATFORM="offscreen",
                 XDG_CONFIG_HOME=str(cwd / "config"), XDG_DATA_HOME=str(cwd / "data"),
                 XDG_CACHE_HOME=str(cwd / "cache"), **env)
    return subprocess.run(list(argv), cwd=cwd, env=clean, capture_output=True, text=True, timeout=timeout)


def test_the_wheel_carries_the_files_the_program_loads(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    for folder, inside in ((ROOT / "resources", "uavviewer/resources"), (ROOT / "slice", "driver/slice"),
                           (ROOT / "config", "driver/config")):
        files = [p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()]
        assert files and all(f"{inside}/{f}" in names for f in files), sorted(names)
    assert not any("__pycache__" in n or n.startswith("tests/") for n in names)
    code = [p.relative_to(ROOT).as_posix() for package in ("driver", "uavviewer") for p in (ROOT / package).rglob("*.py")
            if "__pycache__" not in p.parts]                 # every feature folder, with or without an __init__.py
    assert "uavviewer/flight/commands.py" in code and not set(code) - names, sorted(set(code) - names)
    entry_points = zipfile.ZipFile(wheel).read(next(n for n in names if n.endswith("entry_points.txt"))).decode()
    assert "uavviewer = uavviewer.app:main" in entry_points and "mavlinkserver = driver.__main__:main" in entry_points


@pytest.mark.xdist_group("installed")
@pytest.mark.parametrize("name", ["uavviewer", "mavlinkserver", "python -m uavviewer"])
def test_the_installed_commands_answer(installed, tmp_path, name):
    """--version and --help (the server's sub-commands' too) answer; each command is a test of its own, so the
    suite's workers share the starts (eleven in one test took 11-32 s on the loaded machine)."""
    from driver.version import __version__
    argv = [str(installed / "bin" / "python"), "-m", "uavviewer"] if name == "python -m uavviewer" else [name]
    asked = {(name, option): [*argv, option] for option in ("--version", "--help")}
    if name == "mavlinkserver":
        asked |= {(f"mavlinkserver {sub}", "--help"): [*argv, sub, "--help"] for sub in ("certs", "registry")}
    with ThreadPoolExecutor(len(asked)) as pool:          # at once: each is a process of its own
        done = dict(zip(asked, pool.map(lambda argv: run_installed(installed, *argv, cwd=tmp_path), asked.values())))
    for (command, option), answer in done.items():
        if option == "--version":
            assert (answer.returncode, answer.stdout) == (0, f"{command} {__version__}\n"), answer.stderr
        else:
            assert answer.returncode == 0 and answer.stdout.startswith(f"usage: {command} "), answer.stderr


@pytest.mark.xdist_group("installed")
def test_the_installed_package_finds_its_files(installed, tmp_path):
    where = run_installed(installed, str(installed / "bin" / "python"), "-c",
                          "import driver.ice.lab, uavviewer; print(driver.ice.SLICE_DIR); print(uavviewer.RESOURCES); "
                          "print(driver.ice.lab.REGISTRY_CONFIG)", cwd=tmp_path)
    purelib = sysconfig.get_path("purelib", vars={"base": str(installed), "platbase": str(installed)})
    assert where.stdout.split() == [f"{purelib}/driver/slice", f"{purelib}/uavviewer/resources",
                                    f"{purelib}/driver/config/icegrid-registry.cfg"], where.stderr


@pytest.mark.xdist_group("installed")
def test_the_installed_window_flies_the_simulated_vehicle(installed, tmp_path):
    """Headless: take off, push both sticks, quit; the flight log it recorded shows the climb and the move."""
    shot = tmp_path / "shot.png"
    run = run_installed(installed, "uavviewer", "--sim", "--speedup", "8", "--ready-after", "1", "--log-dir",
                        str(tmp_path / "logs"), "--screenshot", str(shot), "--screenshot-fly",
                        "--screenshot-after", "1", cwd=tmp_path, timeout=120)
    assert run.returncode == 0 and "Traceback" not in run.stderr, run.stderr
    assert shot.stat().st_size > 0
    from pymavlink import mavutil
    log, = (tmp_path / "logs").glob("flight-*.tlog")
    mav = mavutil.mavlink_connection(str(log))
    heights, places = [], []
    while (m := mav.recv_match(type=["GLOBAL_POSITION_INT", "LOCAL_POSITION_NED"])) is not None:
        (heights.append(m.relative_alt / 1000) if m.get_type() == "GLOBAL_POSITION_INT" else places.append((m.x, m.y)))
    assert max(heights) > 2.5, max(heights)                       # the takeoff altitude, 3 m
    assert max(abs(x - places[0][0]) + abs(y - places[0][1]) for x, y in places) > 1.0   # the sticks moved it


POSE_CLIENT = """
import sys, time, Ice, driver.ice
jderobot, _ = driver.ice.load_slice()                  # the Slice files the wheel installed
with Ice.initialize() as ice:
    pose = jderobot.Pose3DPrx.uncheckedCast(ice.stringToProxy("Pose3D:tcp -h 127.0.0.1 -p " + sys.argv[1]))
    z = 0.0
    while z < 1.5:                                     # JdeRobot's z: metres up from home
        try:
            z = pose.getPose3DData().z
        except Ice.ConnectionRefusedException:         # the server is still starting
            pass
        time.sleep(0.1)
    print("climbed", round(z, 1))
"""


@pytest.mark.xdist_group("installed")
def test_the_installed_server_flies_the_simulated_vehicle(installed, tmp_path):
    """``mavlinkserver --sim`` takes off on --cmd; a JdeRobot client on the installed Slice files sees the climb."""
    from ice_fixtures import free_port
    port = str(free_port())
    server = subprocess.Popen([str(installed / "bin" / "mavlinkserver"), "--sim", "--sim-speedup", "4",
                               "--sim-ready-after", "1", "--no-log", "--one-port", port, "--daemon", "--cmd",
                               "takeoff 2"], cwd=tmp_path, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True, env={**os.environ, "PYTHONPATH": ""})
    try:
        seen = run_installed(installed, str(installed / "bin" / "python"), "-c", POSE_CLIENT, port, cwd=tmp_path,
                             timeout=90)
        assert seen.returncode == 0 and seen.stdout.startswith("climbed"), seen.stderr
    finally:
        server.terminate()
        out, _ = server.communicate(timeout=30)
    assert server.returncode == 0 and "serving Pose3D" in out and "Traceback" not in out, out


@pytest.mark.xdist_group("installed")
def test_the_menu_entry_starts_the_installed_window(installed, tmp_path):
    put = run_installed(installed, "uavviewer", "--install-desktop", cwd=tmp_path)
    assert put.returncode == 0, put.stderr
    entry = tmp_path / "data" / "applications" / "uavviewerpy.desktop"
    icon = tmp_path / "data" / "icons" / "hicolor" / "scalable" / "apps" / "uavviewerpy.svg"
    assert put.stdout.split() == ["menu", "entry:", str(entry), "icon:", str(icon)]
    valid = subprocess.run(["desktop-file-validate", str(entry)], capture_output=True, text=True)
    assert valid.returncode == 0 and not valid.stdout, valid.stdout
    fields = dict(line.split("=", 1) for line in entry.read_text().split("\n\n")[0].splitlines()[1:])
    assert fields["Exec"] == f'"{installed}/bin/uavviewer"' and fields["Icon"] == "uavviewerpy"
    assert icon.read_bytes() == (ROOT / "resources" / "icons" / "app.svg").read_bytes()
    gone = run_installed(installed, "uavviewer", "--remove-desktop", cwd=tmp_path)
    assert gone.returncode == 0 and not entry.exists() and not icon.exists()
