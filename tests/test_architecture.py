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


# -- the driver by layer (issue 30): see docs/architecture.md -------------------------------------------------------
#: The driver's folders from the ground up: a module may import its own folder and any folder on a lower floor, never
#: one on its own floor or above. The loose modules at the top (options, __main__) stand above everything they start.
FLOORS = {
    "driver.core": 0, "driver.version": 0, "driver.ftp": 0,
    "driver.link": 1, "driver.mission": 1, "driver.params": 1, "driver.payload": 1, "driver.traffic": 1,
    "driver.logs": 1, "driver.review": 1,
    "driver.setup": 2, "driver.shots": 2,
    "driver.vehicle": 3,
    "driver.camera": 4,
    "driver.console": 5, "driver.ice": 5,
    "driver.options": 6,
    "driver.sim": 7,
    "driver.__main__": 8, "driver": 8,
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


# -- the viewer by feature (docs/architecture.md): one folder per thing a pilot does ------------------------------
VIEWER = os.path.join(ROOT, "uavviewer")
LOOSE_AT_MOST = 8                  # __init__, __main__, app, main_window and a few shared ones
MAIN_WINDOW_AT_MOST = 300          # lines: it builds the window from the features' parts and wires them
NEUTRAL = ("widgets", "units")     # what a widget of widgets/ may use besides Qt and the driver


def viewer_imports() -> dict[str, set[str]]:
    """module -> the uavviewer modules it imports (lazy imports too; a type-only import is no import)."""
    import ast
    graph: dict[str, set[str]] = {}
    known = modules_of_viewer()
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
                    found |= {f"{target}.{a.name}" if f"{target}.{a.name}" in known else target
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


# -- the viewer and the drone: typed calls, answers bound to who asked ---------------------------------------------
def _viewer_trees():
    import ast
    for folder, _dirs, files in os.walk(VIEWER):
        for name in sorted(files):
            if name.endswith(".py"):
                path = os.path.join(folder, name)
                yield os.path.relpath(path, ROOT), ast.parse(open(path, encoding="utf-8").read())


def _is_drone(node) -> bool:
    """``drone``, ``self.drone``, ``self.adapter.drone``, ``w.flight.drone``: the drone flown."""
    import ast
    return (isinstance(node, ast.Name) and node.id == "drone") or (isinstance(node, ast.Attribute)
                                                                    and node.attr == "drone")


def test_the_viewer_calls_only_what_the_drone_offers():
    """A command is the drone's own method, written in the code: a method the driver renames or drops fails here,
    not when a pilot presses the button. Never a method looked up by its name in a string."""
    import ast
    from driver.shots.api import Shots
    from driver.vehicle.api import Drone
    unknown, by_name, untyped = [], [], []
    for path, tree in _viewer_trees():
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and _is_drone(node.value) and not hasattr(Drone, node.attr):
                unknown.append(f"{path}:{node.lineno} {ast.unparse(node)}")
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "getattr" \
                    and node.args and _is_drone(node.args[0]):
                by_name.append(f"{path}:{node.lineno} {ast.unparse(node)}")
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "send" \
                    and ast.unparse(node.func.value).endswith("adapter"):
                call = node.args[0] if node.args else None
                shots = (isinstance(call, ast.Attribute) and isinstance(call.value, ast.Attribute)
                         and call.value.attr == "shots" and _is_drone(call.value.value))   # drone.shots.orbit
                if shots and not hasattr(Shots, call.attr):
                    unknown.append(f"{path}:{node.lineno} {ast.unparse(call)}")
                elif not shots and not (isinstance(call, ast.Attribute) and _is_drone(call.value)):
                    untyped.append(f"{path}:{node.lineno} {ast.unparse(node)}")
    assert not unknown, f"not in driver.vehicle.api.Drone (or its Shots): {unknown}"
    assert not by_name, f"the drone's parts looked up by a name in a string: {by_name}"
    assert not untyped, f"adapter.send takes one of the drone's methods (adapter.send(adapter.drone.land)): {untyped}"


_TEXT_TESTS = {"startswith", "endswith", "replace", "partition", "rpartition", "find", "index", "count", "lower"}


def test_no_part_of_the_viewer_routes_results_by_their_wording():
    """A command's answer goes back to the caller that asked (``adapter.send(..., then=...)``); a result's
    ``command`` is words for the pilot, and rewording it must not change what the window does."""
    import ast

    def command_text(node) -> bool:
        return isinstance(node, ast.Attribute) and node.attr == "command"

    found = []
    for path, tree in _viewer_trees():
        for node in ast.walk(tree):
            hit = False
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in _TEXT_TESTS:
                inner = node.func.value
                while isinstance(inner, ast.Call) and isinstance(inner.func, ast.Attribute):
                    inner = inner.func.value             # result.command.replace(...).startswith(...)
                hit = command_text(inner)
            elif isinstance(node, ast.Subscript):
                hit = command_text(node.value)           # result.command[len("param "):]
            elif isinstance(node, ast.Compare):
                sides = [node.left, *node.comparators]
                words = any(isinstance(s, ast.Constant) and isinstance(s.value, str) for s in sides)
                inside = any(isinstance(op, (ast.In, ast.NotIn)) and command_text(right)
                             for op, right in zip(node.ops, node.comparators))
                hit = inside or (words and any(command_text(s) for s in sides))
            if hit:
                found.append(f"{path}:{node.lineno} {ast.unparse(node)}")
    assert not found, f"results routed by their wording: {found}"


def test_the_viewer_speaks_of_the_product_not_of_issue_numbers():
    """A docstring or comment says what the window does and why; which issue asked for it is the history's."""
    import re
    found = []
    for folder, _dirs, files in os.walk(VIEWER):
        for name in sorted(files):
            if name.endswith(".py"):
                path = os.path.join(folder, name)
                for number, line in enumerate(open(path, encoding="utf-8"), 1):
                    if re.search(r"\bissues? ?#?\d+", line, re.IGNORECASE):
                        found.append(f"{os.path.relpath(path, ROOT)}:{number}: {line.strip()}")
    assert not found, found
