"""The desktop's application menu: a freedesktop.org desktop entry and icon for this installation.

Per user, in ``$XDG_DATA_HOME`` (``~/.local/share``): ``applications/uavviewerpy.desktop`` and the scalable icon
in the ``hicolor`` theme, so no root is needed and removing them leaves nothing behind. The entry starts the
installation it was made from: the ``uavviewer`` command installed by pip, or ``main.py`` of a checkout with the
checkout's Python.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from driver.version import __version__

from .. import RESOURCES

#: the desktop file's name without ``.desktop``, also told to the window manager by the running window
APP_ID = "uavviewerpy"


def data_home() -> Path:
    """``$XDG_DATA_HOME``, or ``~/.local/share`` when it is unset or not absolute (the Base Directory rule)."""
    value = os.environ.get("XDG_DATA_HOME", "")
    return Path(value) if os.path.isabs(value) else Path.home() / ".local" / "share"


def entry_path() -> Path:
    return data_home() / "applications" / f"{APP_ID}.desktop"


def icon_path() -> Path:
    return data_home() / "icons" / "hicolor" / "scalable" / "apps" / f"{APP_ID}.svg"


def command() -> list[str]:
    """What starts this installation: the ``uavviewer`` script beside this Python, else this checkout's main.py."""
    script = Path(sys.executable).parent / "uavviewer"
    if script.is_file() and os.access(script, os.X_OK):
        return [str(script)]
    return [sys.executable, str(Path(__file__).resolve().parents[2] / "main.py")]


def _exec_line(argv: list[str]) -> str:
    """An Exec value: every argument quoted, with the characters the specification reserves escaped."""
    def quoted(arg: str) -> str:
        for ch in ("\\", '"', "`", "$"):
            arg = arg.replace(ch, "\\" + ch)
        return '"' + arg.replace("%", "%%") + '"'
    # the file format escapes backslashes once more on top of the Exec quoting
    return " ".join(quoted(a) for a in argv).replace("\\", "\\\\")


def entry_text(argv: list[str] | None = None) -> str:
    argv = command() if argv is None else argv
    return "\n".join([
        "[Desktop Entry]",
        "Type=Application",
        "Version=1.4",
        "Name=UavViewerPy",
        "GenericName=Drone Ground Station",
        "Comment=Fly a 3DR Solo or an ArduPilot copter from this computer",
        f"Icon={APP_ID}",
        f"TryExec={argv[0]}",
        f"Exec={_exec_line(argv)}",
        "Terminal=false",
        "Categories=Science;Robotics;",
        "Keywords=drone;MAVLink;ArduPilot;ArduCopter;Solo;ground station;JdeRobot;",
        "StartupNotify=true",
        f"X-UavViewerPy-Version={__version__}",
        "Actions=simulator;",
        "",
        "[Desktop Action simulator]",
        "Name=Fly the simulated vehicle",
        f"Exec={_exec_line(argv + ['--sim'])}",
        "",
    ])


def install() -> list[str]:
    """Write the entry and the icon; returns what was done, for the pilot to read."""
    entry, icon = entry_path(), icon_path()
    icon.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(RESOURCES / "icons" / "app.svg", icon)
    entry.parent.mkdir(parents=True, exist_ok=True)
    tmp = entry.with_suffix(".tmp")
    tmp.write_text(entry_text(), encoding="utf-8")
    tmp.replace(entry)                                  # a menu never reads half an entry
    _refresh(entry.parent, icon.parents[2])
    return [f"menu entry: {entry}", f"icon: {icon}"]


def remove() -> list[str]:
    gone = []
    for path in (entry_path(), icon_path()):
        if path.exists():
            path.unlink()
            gone.append(f"removed {path}")
    _refresh(entry_path().parent, icon_path().parents[2])
    return gone or ["no menu entry was installed"]


def _refresh(applications: Path, theme: Path) -> None:
    """Tell the desktop's caches, where their tools exist (menus also notice changes by themselves)."""
    for tool, folder in (("update-desktop-database", applications), ("gtk-update-icon-cache", theme)):
        if shutil.which(tool) and folder.is_dir():
            subprocess.run([tool, "-q", str(folder)] if tool == "update-desktop-database"
                           else [tool, "-q", "-t", str(folder)], check=False, capture_output=True)
