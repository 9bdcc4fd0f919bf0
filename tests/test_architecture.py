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


# -- the driver by layer: see docs/architecture.md -------------------------------------------------------
#: The driver's folders from the ground up: a module may import its own folder and any folder on a lower floor, never
#: one on its own floor or above. The loose modules at the top (options, __main__) stand above everything they start.
FLOORS = {
    "driver.core": 0, "driver.version": 0,
    "driver.link": 1, "driver.mission": 1, "driver.payload": 1, "driver.traffic": 1, "driver.review": 1,
    "driver.ftp": 1,
    "driver.setup": 2, "driver.params": 2, "driver.logs": 2, "driver.shots": 2,
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



# -- one round-trip policy ------------------------------------------------------------------------------------------
#: The one place a round trip is estimated and a timeout made from it (RFC 6298, Karn's rule and backoff).
ROUND_TRIP_POLICY = "driver/core/roundtrip.py"
#: Where a RoundTrip may be made: the vehicle's one, and a lone FTP read's own (a read outside a vehicle).
ROUND_TRIP_MADE_IN = {"driver/vehicle/vehicle.py", "driver/ftp/reader.py", ROUND_TRIP_POLICY}
#: Modules allowed to keep a round trip of their own, each with why (to be kept empty: a line here is a debt).
ROUND_TRIP_ALLOWED: dict[str, str] = {}


def _driver_sources(skip_sim: bool = True):
    """(relative path, parsed module) of every driver module (the simulator aside: it plays the vehicle)."""
    import ast
    for folder, _dirs, files in os.walk(os.path.join(ROOT, "driver")):
        for name in sorted(files):
            if not name.endswith(".py"):
                continue
            rel = os.path.relpath(os.path.join(folder, name), ROOT).replace(os.sep, "/")
            if skip_sim and rel.startswith("driver/sim/"):
                continue
            with open(os.path.join(ROOT, rel), encoding="utf-8") as f:
                yield rel, ast.parse(f.read())


def _named_like_a_round_trip(target) -> bool:
    import ast
    name = target.id if isinstance(target, ast.Name) else target.attr if isinstance(target, ast.Attribute) else ""
    return any(word in name.lower() for word in ("rtt", "round_trip", "roundtrip"))


def _handed_on(value) -> bool:
    """A value passed along, not worked out: a name, an attribute, None, a RoundTrip made (or a tuple of those)."""
    import ast
    if value is None or isinstance(value, (ast.Name, ast.Attribute)):
        return True
    if isinstance(value, ast.Tuple):
        return all(_handed_on(v) for v in value.elts)
    return (isinstance(value, ast.Constant) and value.value is None) or (
        isinstance(value, ast.Call) and getattr(value.func, "id", "") == "RoundTrip")


def round_trips_computed(rel: str, tree) -> list[str]:
    """Where ``tree`` works out a round trip itself: a value computed into a name like one (an average, a
    difference of times, a first guess), or a RoundTrip made outside :data:`ROUND_TRIP_MADE_IN`. Handing the
    vehicle's on (a name, an attribute, None) is no estimate, nor a module's constant bound (``FILL_RTT_MIN``)."""
    import ast
    found = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.Assign, ast.AugAssign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            handed = not isinstance(node, ast.AugAssign) and _handed_on(node.value)
            bound = isinstance(node.value, ast.Constant) and all(
                isinstance(t, ast.Name) and t.id.isupper() for t in targets)
            handed = handed or bound
            flat = [t for target in targets for t in (target.elts if isinstance(target, ast.Tuple) else [target])]
            if not handed and any(_named_like_a_round_trip(t) for t in flat):
                found.append(f"{rel}:{node.lineno}: {ast.unparse(node)[:80]}")
        if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "RoundTrip" and \
                rel not in ROUND_TRIP_MADE_IN:
            found.append(f"{rel}:{node.lineno}: a RoundTrip of its own")
    return found


def test_one_round_trip_policy():
    """Commands, the mission transfer, the parameter download and MAVLink FTP all wait the vehicle's one
    RoundTrip's timeout and feed it their clean answers: no module keeps an estimator and gains of its own."""
    found, allowed = [], []
    for rel, tree in _driver_sources():
        if rel == ROUND_TRIP_POLICY:
            continue
        (allowed if rel in ROUND_TRIP_ALLOWED else found).extend(round_trips_computed(rel, tree))
    assert found == [], "\n".join(found)
    stale = [rel for rel in ROUND_TRIP_ALLOWED if not any(a.startswith(rel + ":") for a in allowed)]
    assert stale == [], f"remove from ROUND_TRIP_ALLOWED: {stale}"


def test_the_round_trip_check_finds_an_estimator_of_its_own():
    import ast
    smoothed = ast.parse("class Download:\n    def arrived(self, sent, now):\n"
                         "        self.rtt = 0.8 * self.rtt + 0.2 * (now - sent)\n")
    handed = ast.parse("class Download:\n    def __init__(self, roundtrip):\n        self.roundtrip = roundtrip\n")
    assert round_trips_computed("driver/params/download.py", smoothed)
    assert not round_trips_computed("driver/params/download.py", handed)
    assert round_trips_computed("driver/mission/transfer.py", ast.parse("rt = RoundTrip(initial=0.1)"))


# -- the parts ask for what they use ---------------------------------------------------------------------------------
#: Expressions that may reach another object's underscore names, each with why (the driver's part of it is to stay
#: empty; a line here is a debt, never a way in).
UNDERSCORE_ALLOWED: dict[str, str] = {}
#: The viewer's, left for its own refactor (the window's and its features' seams): file -> expressions.
VIEWER_UNDERSCORE_ALLOWED = {
    "uavviewer/refresh.py": {"channel._schedule", "channel._stop"},
    "uavviewer/window/pilot_tools.py": {"w._qsettings", "self.window._qsettings", "w._connected", "c._opening"},
    "uavviewer/input/gamepad.py": {"GamepadReader._open"},
    "uavviewer/map/camera_overlay.py": {"view._label"},
    "uavviewer/map/traffic_overlay.py": {"view._arrow"},
}


def others_underscores(tree) -> list[tuple[int, str]]:
    """(line, expression) of every ``x._name`` in ``tree`` where ``x`` is not the object itself (``self``,
    ``cls``, ``super()``): another object's private name, which a port or a public name should carry instead."""
    import ast
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Attribute) or not node.attr.startswith("_") or node.attr.startswith("__"):
            continue
        base = node.value
        if isinstance(base, ast.Name) and base.id in ("self", "cls"):
            continue
        if isinstance(base, ast.Call) and getattr(base.func, "id", "") == "super":
            continue
        found.append((node.lineno, ast.unparse(node)))
    return found


def _sources(tree: str):
    import ast
    for folder, _dirs, files in os.walk(os.path.join(ROOT, tree)):
        for name in sorted(files):
            if name.endswith(".py"):
                rel = os.path.relpath(os.path.join(folder, name), ROOT).replace(os.sep, "/")
                with open(os.path.join(ROOT, rel), encoding="utf-8") as f:
                    yield rel, ast.parse(f.read())


def test_no_driver_module_touches_another_objects_underscore_names():
    """A part is handed narrow ports (driver.core.ports) and public names, never another object's private fields:
    what it depends on at run time is what its constructor says (MAVSDK's plugins and their Sender&)."""
    found, allowed = [], set()
    for rel, tree in _sources("driver"):
        hits = others_underscores(tree)
        if rel in UNDERSCORE_ALLOWED:
            allowed.add(rel) if hits else None
            continue
        found += [f"{rel}:{line}: {expr}" for line, expr in hits]
    assert found == [], "\n".join(found)
    assert allowed == set(UNDERSCORE_ALLOWED), f"remove from UNDERSCORE_ALLOWED: {set(UNDERSCORE_ALLOWED) - allowed}"


def test_no_viewer_module_touches_another_objects_underscore_names_beyond_the_known_ones():
    found, seen = [], set()
    for rel, tree in _sources("uavviewer"):
        known = VIEWER_UNDERSCORE_ALLOWED.get(rel, set())
        hits = others_underscores(tree)
        seen |= {(rel, expr) for _, expr in hits}
        found += [f"{rel}:{line}: {expr}" for line, expr in hits if expr not in known]
    assert found == [], "\n".join(found)
    gone = {(rel, e) for rel, known in VIEWER_UNDERSCORE_ALLOWED.items() for e in known} - seen
    assert not gone, f"remove from VIEWER_UNDERSCORE_ALLOWED: {sorted(gone)}"


def test_the_underscore_check_finds_a_part_reaching_into_the_vehicle():
    import ast
    reach = ast.parse("class Payload:\n    def point(self):\n        return self._v._command_long(178)\n")
    own = ast.parse("class Payload(Base):\n    def point(self):\n        return self._commands.long(178), "
                    "super()._open(), cls._made\n")
    assert others_underscores(reach) == [(3, "self._v._command_long")]
    assert others_underscores(own) == []


# -- one place for what each firmware does differently ---------------------------------------------------------------
FIRMWARE_PROFILE = "driver/core/firmware.py"


def firmware_branches(tree) -> list[tuple[int, str]]:
    """Where ``tree`` tells firmwares apart by itself: a version compared (``(3, 4)``, ``"3.3"``), the flight
    software's number or the protocol bits AUTOPILOT_VERSION advertises read."""
    import ast
    import re
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare) and not any(isinstance(op, (ast.In, ast.NotIn)) for op in node.ops):
            for side in [node.left, *node.comparators]:
                if isinstance(side, ast.Tuple) and len(side.elts) >= 2 and all(
                        isinstance(e, ast.Constant) and type(e.value) is int for e in side.elts):
                    found.append((node.lineno, ast.unparse(node)))
                elif isinstance(side, ast.Constant) and isinstance(side.value, str) and \
                        re.fullmatch(r"\d+\.\d+(\.\d+)?", side.value):
                    found.append((node.lineno, ast.unparse(node)))
        elif isinstance(node, ast.Attribute) and (node.attr == "flight_sw_version"
                                                  or node.attr.startswith("MAV_PROTOCOL_CAPABILITY_")):
            found.append((node.lineno, ast.unparse(node)))
    return found


def test_firmware_differences_live_in_the_firmware_profile():
    """The parts ask driver.core.firmware (learnt from AUTOPILOT_VERSION, the link's framing and the UNSUPPORTED
    answers) what this vehicle's firmware does; none tests a version or a capability bit itself (QGroundControl's
    FirmwarePlugin). The simulator, which plays each firmware, aside."""
    found = []
    for rel, tree in _driver_sources():
        if rel != FIRMWARE_PROFILE:
            found += [f"{rel}:{line}: {expr}" for line, expr in firmware_branches(tree)]
    assert found == [], "\n".join(found)


def test_the_firmware_check_finds_a_version_test():
    import ast
    assert firmware_branches(ast.parse("if version is not None and version < (3, 4):\n    pass\n"))
    assert firmware_branches(ast.parse("legacy = state.firmware.startswith('3') or firmware == '3.3'"))
    assert firmware_branches(ast.parse("ftp = bool(m.capabilities & mavlink.MAV_PROTOCOL_CAPABILITY_FTP)"))
    assert not firmware_branches(ast.parse("fw.payload_commands and fw.knows(511) is not False"))



# -- names ----------------------------------------------------------------------------------------------------------
ISSUE_NUMBERS_ALLOWED: set[str] = set()


def test_the_driver_speaks_of_the_product_not_of_issue_numbers():
    """A docstring or comment says why, in the product's words: "issue 31" tells a reader nothing."""
    import re
    found = []
    for folder, _dirs, files in os.walk(os.path.join(ROOT, "driver")):
        for name in files:
            rel = os.path.relpath(os.path.join(folder, name), ROOT).replace(os.sep, "/")
            if name.endswith(".py") and rel not in ISSUE_NUMBERS_ALLOWED:
                with open(os.path.join(ROOT, rel), encoding="utf-8") as f:
                    found += [f"{rel}:{n}" for n, line in enumerate(f, 1)
                              if re.search(r"\bissues? #?\d", line, re.IGNORECASE)]
    assert found == [], found


#: Names a reader had to look up to follow the log download and the Ice client's journal: each was renamed for
#: what it holds in flight terms (the bytes the .part keeps, the tail asked twice, the results before a restart).
UNCLEAR_NAMES = {"tokens", "kept", "verify", "tail_full", "short_asks", "TAIL_TWICE", "ANSWERED_MIN",
                 "_result_offset", "_result_high", "_resync"}


def names_defined(tree) -> list[tuple[int, str]]:
    """(line, name) of every name ``tree`` binds: variables, attributes assigned, arguments, functions, classes."""
    import ast
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
            found.append((node.lineno, node.id))
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
            found.append((node.lineno, node.attr))
        elif isinstance(node, ast.arg):
            found.append((node.lineno, node.arg))
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            found.append((node.lineno, node.name))
    return found


def test_the_driver_names_what_it_holds():
    """A name says what it holds (a log's ``saved`` bytes, the journal's ``_results_before_restart``), never a
    plumbing word a reader must trace back to its assignments."""
    found = [f"{rel}:{line}: {name}" for rel, tree in _sources("driver")
             for line, name in names_defined(tree) if name in UNCLEAR_NAMES]
    assert found == [], "\n".join(found)


def test_the_names_check_finds_a_plumbing_word():
    import ast
    found = names_defined(ast.parse("self.tail_full = set()\ndef f(tokens): pass\n"))
    assert sorted(found) == [(1, "tail_full"), (2, "f"), (2, "tokens")]

# -- sizes ----------------------------------------------------------------------------------------------------------
MAX_MODULE_LINES = 600
MAX_CLASS_LINES = 400
#: Over the limits, each with why (to be kept empty).
SIZE_ALLOWED: dict[str, str] = {}


def oversized(rel: str, source: str) -> list[str]:
    import ast
    found = []
    lines = len(source.splitlines())
    if lines > MAX_MODULE_LINES:
        found.append(f"{rel}: {lines} lines")
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ClassDef) and node.end_lineno - node.lineno + 1 > MAX_CLASS_LINES:
            found.append(f"{rel}: class {node.name} {node.end_lineno - node.lineno + 1} lines")
    return found


def test_no_module_over_600_lines_nor_class_over_400_outside_the_simulator():
    found, allowed = [], set()
    for tree in ("driver", "uavviewer"):
        for folder, _dirs, files in os.walk(os.path.join(ROOT, tree)):
            for name in files:
                rel = os.path.relpath(os.path.join(folder, name), ROOT).replace(os.sep, "/")
                if not name.endswith(".py") or rel.startswith("driver/sim/"):
                    continue
                with open(os.path.join(ROOT, rel), encoding="utf-8") as f:
                    hits = oversized(rel, f.read())
                if rel in SIZE_ALLOWED:
                    allowed.add(rel) if hits else None
                else:
                    found += hits
    assert found == [], "\n".join(found)
    assert allowed == set(SIZE_ALLOWED), f"remove from SIZE_ALLOWED: {set(SIZE_ALLOWED) - allowed}"

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
