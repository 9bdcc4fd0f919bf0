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


# -- the driver by layer (issue 30): see docs/architecture.md -------------------------------------------------------
#: The driver's folders from the ground up: a module may import its own folder and any folder on a lower floor, never
#: one on its own floor or above. The loose modules at the top (options, __main__) stand above everything they start.
FLOORS = {
    "driver.core": 0, "driver.version": 0,
    "driver.link": 1, "driver.mission": 1, "driver.params": 1, "driver.payload": 1,
    "driver.vehicle": 2,
    "driver.camera": 3,
    "driver.console": 4, "driver.ice": 4,
    "driver.options": 5,
    "driver.sim": 6,
    "driver.__main__": 7, "driver": 7,
}
MAX_LOOSE_MODULES = 8
MAX_FACADE_LINES = 600


def _module_name(path: str, base: str) -> str:
    rel = os.path.relpath(path, base)[:-3].replace(os.sep, ".")
    return rel[:-len(".__init__")] if rel.endswith(".__init__") else rel


def _imports(tree: str) -> dict[str, set[str]]:
    """module -> the modules of ``tree`` it imports, anywhere in the file (at the top or inside a function). A
    folder without __init__.py (bench/) is a set of scripts that import each other by their bare names."""
    import ast
    folder = os.path.join(ROOT, tree)
    base = ROOT if os.path.exists(os.path.join(folder, "__init__.py")) else folder
    files = [os.path.join(d, f) for d, _dirs, fs in os.walk(folder) for f in fs if f.endswith(".py")]
    modules = {_module_name(f, base): f for f in files}
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        package = name if path.endswith("__init__.py") else name.rpartition(".")[0]
        parsed = ast.parse(open(path, encoding="utf-8").read())
        found = set()
        for node in ast.walk(parsed):
            targets = []
            if isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    parts = package.split(".")
                    base = ".".join(parts[:len(parts) - node.level + 1] + ([base] if base else []))
                # "from . import guided" names a module; "from .state import X" names its module
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base for a in node.names]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            for t in targets:
                while t and t not in modules:
                    t = t.rpartition(".")[0]
                if t and t != name and t in modules:
                    found.add(t)
        graph[name] = found
    return graph


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected groups of more than one module (Tarjan), each an import circle."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                out.append(sorted(group))
    for v in list(graph):
        if v not in index:
            visit(v)
    return out


def _floor(module: str) -> tuple[str, int]:
    for prefix in sorted(FLOORS, key=len, reverse=True):
        if module == prefix or module.startswith(prefix + "."):
            return prefix, FLOORS[prefix]
    raise AssertionError(f"{module}: no floor in FLOORS (add its folder to the table and docs/architecture.md)")


def test_no_import_circles_in_the_driver_or_the_benches():
    for tree in ("driver", "bench"):
        assert _circles(_imports(tree)) == [], tree


def test_no_driver_module_imports_a_folder_on_its_own_floor_or_above():
    wrong = []
    for module, imported in _imports("driver").items():
        folder, floor = _floor(module)
        for other in imported:
            other_folder, other_floor = _floor(other)
            if other_folder != folder and other_floor >= floor:
                wrong.append(f"{module} -> {other}")
    assert wrong == []


def test_few_modules_loose_at_the_top_of_the_driver():
    loose = sorted(f for f in os.listdir(os.path.join(ROOT, "driver")) if f.endswith(".py"))
    assert len(loose) <= MAX_LOOSE_MODULES, loose


def test_the_vehicle_facade_stays_small():
    with open(os.path.join(ROOT, "driver", "vehicle", "vehicle.py"), encoding="utf-8") as f:
        lines = sum(1 for _ in f)
    assert lines <= MAX_FACADE_LINES, f"driver/vehicle/vehicle.py has {lines} lines: move a job into its part"
