"""The driver's ZeroC Ice face: JdeRobot 5.5 interfaces plus our ``mavlinkserver`` extension.

The Slice files in ``slice/`` are the single statement of the wire contract;
they are compiled at run time with ``Ice.loadSlice`` the first time anything
here needs them, so no generated code is committed and nothing can drift.
"""
from __future__ import annotations

import os
import threading

_PACKAGE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def data_dir(name: str) -> str:
    """``slice`` or ``config``: package data when installed (driver/NAME, see pyproject.toml), in a checkout the
    folder of that name beside driver/."""
    inside = os.path.join(_PACKAGE, name)
    return inside if os.path.isdir(inside) else os.path.join(os.path.dirname(_PACKAGE), name)


SLICE_DIR = data_dir("slice")
JDEROBOT_FILES = ("datetime.ice", "exceptions.ice", "containers.ice", "common.ice", "pose3d.ice", "cmdvel.ice",
                  "ardroneextra.ice", "navdata.ice", "image.ice", "camera.ice")
EXTENSION_FILE = "mavlinkserver.ice"

_lock = threading.Lock()
_modules = None


def slice_files(extension: bool = True) -> list[str]:
    files = [os.path.join(SLICE_DIR, "jderobot", name) for name in JDEROBOT_FILES]
    if extension:
        files.append(os.path.join(SLICE_DIR, EXTENSION_FILE))
    return files


def load_slice():
    """``(jderobot, mavlinkserver)``: the generated modules, compiled once per process."""
    global _modules
    with _lock:
        if _modules is None:
            import Ice
            Ice.loadSlice("", ["-I" + SLICE_DIR, "--all"] + slice_files())
            import jderobot
            import mavlinkserver
            _modules = (jderobot, mavlinkserver)
        return _modules
