"""Rules of the codebase that a test can hold: the driver runs without Qt (on a companion computer)."""
from __future__ import annotations

import os
import pkgutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def driver_modules() -> list[str]:
    import driver
    return ["driver"] + [m.name for m in pkgutil.walk_packages(driver.__path__, "driver.")
                         if not m.name.endswith("__main__")]


def test_driver_never_imports_qt():
    modules = driver_modules()
    assert "driver.vehicle" in modules and "driver.sim" in modules
    code = ("import importlib, sys\n"
            f"for name in {modules!r}:\n"
            "    importlib.import_module(name)\n"
            "qt = sorted(m for m in sys.modules if m.split('.')[0] in ('PyQt5', 'pyqtgraph', 'sip'))\n"
            "print(qt)\n"
            "sys.exit(1 if qt else 0)\n")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
