"""Rules of the codebase that a test can hold: the driver runs without Qt (on a companion computer); the viewer
is built by feature (docs/architecture.md): a thin main window, few loose modules, no import circles, no arrow
back up to the window, and widgets/ that know no feature."""
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


# -- the viewer by feature (docs/architecture.md): one folder per thing a pilot does ------------------------------
VIEWER = os.path.join(ROOT, "uavviewer")
LOOSE_AT_MOST = 8                  # __init__, __main__, app, main_window and a few shared ones
MAIN_WINDOW_AT_MOST = 300          # lines: it builds the window from the features' parts and wires them
NEUTRAL = ("widgets", "units")     # what a widget of widgets/ may use besides Qt and the driver


def viewer_imports() -> dict[str, set[str]]:
    """module -> the uavviewer modules it imports (lazy imports too; a type-only import is no import)."""
    import ast
    graph: dict[str, set[str]] = {}
    for folder, _dirs, files in os.walk(VIEWER):
        for name in files:
            if not name.endswith(".py"):
                continue
            path = os.path.join(folder, name)
            module = os.path.relpath(path, ROOT)[:-3].replace(os.sep, ".").removesuffix(".__init__")
            package = module if name == "__init__.py" else module.rpartition(".")[0]
            tree = ast.parse(open(path, encoding="utf-8").read())
            type_only = {id(n) for node in ast.walk(tree) if isinstance(node, ast.If)
                         and getattr(node.test, "id", "") == "TYPE_CHECKING" for n in ast.walk(node)}
            found = set()
            for node in ast.walk(tree):
                if id(node) in type_only:
                    continue
                if isinstance(node, ast.ImportFrom):
                    base = package.split(".")[:len(package.split(".")) - node.level + 1] if node.level else []
                    target = ".".join(base + ([node.module] if node.module else []))
                    found |= {f"{target}.{a.name}" if f"{target}.{a.name}" in modules_of_viewer() else target
                              for a in node.names}
                elif isinstance(node, ast.Import):
                    found |= {a.name for a in node.names}
            graph[module] = {m for m in found if m.startswith("uavviewer.") and m != module}
    return graph


def modules_of_viewer() -> set[str]:
    names = set()
    for folder, _dirs, files in os.walk(VIEWER):
        names |= {os.path.relpath(os.path.join(folder, f), ROOT)[:-3].replace(os.sep, ".").removesuffix(".__init__")
                  for f in files if f.endswith(".py")}
    return names


def feature(module: str) -> str:
    """The folder a module lives in (``flight``, ``input``, ...), or its own name for a loose one ("" for the
    package's face)."""
    return (module.split(".") + [""])[1]


def cycle(graph: dict[str, set[str]]) -> list[str]:
    """One circle of ``graph``, or []."""
    state: dict[str, int] = {}
    path: list[str] = []

    def visit(node: str) -> list[str]:
        state[node] = 1
        path.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                return path[path.index(nxt):] + [nxt]
            if nxt not in state and (found := visit(nxt)):
                return found
        state[node] = 2
        path.pop()
        return []
    for node in sorted(graph):
        if node not in state and (found := visit(node)):
            return found
    return []


def test_main_window_only_builds_and_wires():
    with open(os.path.join(VIEWER, "main_window.py"), encoding="utf-8") as f:
        lines = len(f.read().splitlines())
    assert lines <= MAIN_WINDOW_AT_MOST, f"main_window.py has {lines} lines: its logic belongs in a feature's folder"


def test_few_modules_loose_beside_the_feature_folders():
    loose = sorted(f for f in os.listdir(VIEWER) if f.endswith(".py"))
    assert len(loose) <= LOOSE_AT_MOST, f"{len(loose)} loose modules in uavviewer/: {loose}"


def test_the_viewer_has_no_import_circle():
    graph = viewer_imports()
    assert "uavviewer.flight.commands" in graph and "uavviewer.widgets.ask" in graph["uavviewer.flight.commands"]
    assert cycle(graph) == []


def test_features_import_each_other_without_circles():
    folders: dict[str, set[str]] = {}
    for module, targets in viewer_imports().items():
        if module.count(".") >= 2:                         # in a folder
            folders.setdefault(feature(module), set()).update(
                feature(t) for t in targets if t.count(".") >= 2 and feature(t) != feature(module))
    assert {"flight", "input", "camera", "map", "plan", "params", "connect", "fleet", "widgets"} <= set(folders)
    assert cycle(folders) == []


def test_no_arrow_runs_back_up_to_the_window():
    """Features may use widgets/, the shared modules and the drone adapter; never the window that builds them."""
    for module, targets in viewer_imports().items():
        if module.count(".") >= 2 and feature(module) != "window":
            up = {t for t in targets if t in ("uavviewer.main_window", "uavviewer.app") or feature(t) == "window"}
            assert not up, f"{module} imports {up}"


def test_widgets_know_no_feature():
    for module, targets in viewer_imports().items():
        if feature(module) == "widgets":
            other = {t for t in targets if feature(t) not in NEUTRAL}
            assert not other, f"{module} imports {other}: it belongs in that feature's folder"
