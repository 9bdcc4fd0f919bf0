"""Issue 23's Shape item: driver.camera never imports driver.ice; the Ice camera source lives with the Ice code
and registers its ``ice:`` scheme, so the dependency runs one way (ice -> camera)."""
from __future__ import annotations

import ast
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_driver_camera_imports_nothing_of_driver_ice():
    folder = os.path.join(ROOT, "driver", "camera")
    for name in sorted(os.listdir(folder)):
        if name.endswith(".py"):
            tree = ast.parse(open(os.path.join(folder, name), encoding="utf-8").read())
            for node in ast.walk(tree):
                if isinstance(node, ast.ImportFrom):
                    assert not (node.module or "").startswith(("ice", "driver.ice")), (name, node.module)
                    assert not (node.level >= 2 and (node.module or "").startswith("ice")), (name, node.module)
    code = ("import sys, driver.camera, driver.camera.uri, driver.camera.sim\n"
            "sys.exit(1 if any(m.startswith('driver.ice') for m in sys.modules) else 0)\n")
    assert subprocess.run([sys.executable, "-c", code], cwd=ROOT).returncode == 0


def test_the_ice_scheme_is_registered_by_the_ice_side():
    from driver.camera import open_source
    import driver.ice.camera_source as camera_source
    src = open_source("ice:Camera:tcp -h 127.0.0.1 -p 9", start=False)
    assert isinstance(src, camera_source.IceSource) and src.proxy == "Camera:tcp -h 127.0.0.1 -p 9"
