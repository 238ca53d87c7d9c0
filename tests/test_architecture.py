"""The package's shape: rooms by job, imports one way, the vocabulary defined once, small modules.

These read the source (``ast``), so they check what the code says, not what one run
happened to import. Every import counts, at any depth of a file (an import inside a
function runs as surely as one at the top), and importing ``a.b.c`` runs the faces
``a`` and ``a.b`` too: what a module *reaches* is all of that, transitively.
"""

from __future__ import annotations

import ast
import textwrap
from collections.abc import Iterable, Mapping
from pathlib import Path

import pytest

from casa_core import vocabulary

PACKAGE = Path(__file__).resolve().parents[1] / "casa_core"
MODULES = sorted(PACKAGE.rglob("*.py"))
#: "About 400 lines": a module past this has more than one job.
MAX_LINES = 420

#: The rooms, bottom up: each module belongs to the longest prefix that names it. The
#: package's own face (``casa_core``) holds its version only.
ROOMS = {
    "numerics": ("casa_core.numerics",),
    "words": ("casa_core", "casa_core.vocabulary", "casa_core.defaults"),
    "algebra": ("casa_core.fixed_order", "casa_core.portable_math"),
    "ground": ("casa_core.scene", "casa_core.config"),
    "model": ("casa_core.model",),
    "assist": ("casa_core.assist",),
    "robot": ("casa_core.robot",),
    "io": ("casa_core.io",),
    "planning": ("casa_core.planning",),
    "original": ("casa_core.io.original",),
    "learning": ("casa_core.learning",),
    "analysis": ("casa_core.analysis",),
    "stats": ("casa_core.stats",),
    "figures": ("casa_core.figures",),
    "report": ("casa_core.report",),
    "study": ("casa_core.study",),
    "calibration": ("casa_core.calibration",),
    "experiments": ("casa_core.experiments",),
    "bench": ("casa_core.bench",),
    "ros2": ("casa_core.ros2",),
    "cli": ("casa_core.cli",),
}
#: The rooms each room may import directly (its own always). This is the arrow diagram of
#: docs/index.md; it is a DAG, so what a room reaches is bounded by what it may import.
MAY_IMPORT = {
    "numerics": set(),
    "words": {"numerics"},
    "algebra": set(),
    "ground": {"words"},
    "model": set(),
    "assist": {"algebra", "words", "ground", "model"},
    "robot": {"algebra", "words", "ground", "assist"},
    "io": {"words", "ground"},
    "planning": {"algebra", "words", "ground", "model", "assist", "robot"},
    "original": {"algebra", "words", "ground", "io", "robot"},
    "learning": {"algebra", "words", "ground", "model", "assist", "planning", "io"},
    "analysis": {"algebra", "words", "ground", "model", "assist", "robot", "io", "original"}
    | {"learning"},
    "stats": {"words", "ground", "io"},
    "figures": {"words", "ground", "io", "stats"},
    "report": {"words", "io"},
    "study": {"algebra", "words", "ground", "model", "assist", "robot", "io", "planning"}
    | {"learning", "analysis"},
    "calibration": {"words", "ground", "assist", "robot", "io", "analysis", "study"},
    "experiments": {"words", "ground", "assist"},
    "bench": {"algebra", "words", "ground", "assist", "robot", "study", "planning", "learning"},
    "ros2": {"algebra", "words", "ground", "model", "assist", "robot", "io", "study"},
    "cli": set(ROOMS) - {"cli"},
}
#: What a room must never reach, however indirectly (third-party packages by top name).
NEVER_REACHES = {
    "model": {"pybullet", "torch", "pandas", "yaml", "json", "pathlib", "os", "io", "csv"},
    "assist": {"pybullet", "torch", "casa_core.robot", "casa_core.learning"},
    "io": {"pybullet", "torch", "casa_core.robot", "casa_core.study", "casa_core.learning"},
    "planning": {"pybullet", "casa_core.robot.sim", "casa_core.learning", "casa_core.study"},
    "learning": {"pybullet", "casa_core.robot.sim", "casa_core.study"},
    "stats": {"pybullet", "torch", "casa_core.robot", "casa_core.study", "casa_core.learning"},
    "figures": {"pybullet", "torch", "casa_core.robot", "casa_core.study", "casa_core.learning"},
    "report": {"pybullet", "torch", "matplotlib", "casa_core.study"},
    "words": {"numpy", "pandas"},
    "ground": {"pandas", "torch", "pybullet"},
    "experiments": {"pybullet", "torch", "casa_core.study"},
}


def module_name(path: Path, root: Path = PACKAGE) -> str:
    parts = path.relative_to(root.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def parents(name: str) -> list[str]:
    """The packages whose faces run when ``name`` is imported: ``a.b.c`` -> ``a``, ``a.b``."""
    parts = name.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts))]


def import_graph(root: Path = PACKAGE) -> dict[str, set[str]]:
    """Module -> the modules it imports anywhere in its file (lazy imports included).

    ``from pkg import name`` is an import of ``pkg.name`` where that is a module, else of
    ``pkg``; a third-party import is its top-level name (``torch``).
    """
    paths = sorted(root.rglob("*.py"))
    known = {module_name(p, root) for p in paths}
    top = root.name
    graph = {}
    for path in paths:
        this = module_name(path, root)
        found = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = [
                    f"{node.module}.{alias.name}"
                    if f"{node.module}.{alias.name}" in known
                    else node.module
                    for alias in node.names
                ]
            else:
                continue
            for name in names:
                found.add(name if name.split(".")[0] == top else name.split(".")[0])
        graph[this] = found - {this}
    return graph


def reach(graph: Mapping[str, set[str]], start: str) -> set[str]:
    """Everything importing ``start`` runs: its imports, their faces, transitively."""
    seen: set[str] = set()
    todo = [start]
    while todo:
        for name in graph.get(todo.pop(), ()):
            for step in [*parents(name), name]:
                if step not in seen and step != start:
                    seen.add(step)
                    todo.append(step)
    return seen


def cycles(graph: Mapping[str, set[str]]) -> list[list[str]]:
    """Every group of modules that import each other, directly or through others (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if nxt not in graph:
                continue
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            group = []
            while True:
                member = stack.pop()
                group.append(member)
                if member == node:
                    break
            if len(group) > 1:
                found.append(sorted(group))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def room_of(name: str, rooms: Mapping[str, Iterable[str]] = ROOMS) -> str | None:
    best = None, -1
    for room, prefixes in rooms.items():
        for prefix in prefixes:
            if (name == prefix or name.startswith(prefix + ".")) and len(prefix) > best[1]:
                best = room, len(prefix)
    return best[0]


def upward_imports(graph, rooms=ROOMS, may_import=MAY_IMPORT) -> list[str]:
    """``module imports name (room -> room)`` for every import the arrows do not allow."""
    broken = []
    for module, names in sorted(graph.items()):
        here = room_of(module, rooms)
        for name in sorted(names):
            there = room_of(name, rooms)
            if there is not None and there != here and there not in may_import[here]:
                broken.append(f"{module} imports {name} ({here} -> {there})")
    return broken


def forbidden_reach(graph, never=NEVER_REACHES, rooms=ROOMS) -> list[str]:
    """``module reaches name`` for everything a room must never reach, however indirectly."""
    broken = []
    for module in sorted(graph):
        banned = never.get(room_of(module, rooms), set())
        for name in sorted(reach(graph, module)):
            if any(name == b or name.startswith(b + ".") for b in banned):
                broken.append(f"{module} reaches {name}")
    return broken


GRAPH = import_graph()
#: The package's face pins the libraries' CPU switches (casa_core.numerics) before
#: anything loads, so every room runs it; it reads the environment and nothing else,
#: which the reach checks take as given (the test below holds it to that).
ENVIRONMENT_ONLY = {"casa_core.numerics": {"os", "sys"}}


def test_the_cpu_switches_read_the_environment_only():
    for module, allowed in ENVIRONMENT_ONLY.items():
        assert GRAPH[module] <= allowed | {"__future__"}, GRAPH[module]


def test_every_module_is_in_a_room_and_every_room_has_modules():
    homeless = [m for m in GRAPH if room_of(m) is None]
    assert not homeless, f"modules in no room: {homeless}"
    empty = [room for room in ROOMS if not any(room_of(m) == room for m in GRAPH)]
    assert not empty, f"rooms with no module (renamed?): {empty}"
    assert set(MAY_IMPORT) == set(ROOMS) and set(NEVER_REACHES) <= set(ROOMS)


def test_the_arrows_form_no_cycle():
    # A room that may import another that may import it back would make the rules vacuous.
    assert not cycles({room: set(rooms) for room, rooms in MAY_IMPORT.items()})


def test_no_module_imports_a_room_above_its_own():
    broken = upward_imports(GRAPH)
    assert not broken, "\n".join(broken)


def test_no_modules_import_each_other():
    found = cycles(GRAPH)
    assert not found, "\n".join(" <-> ".join(group) for group in found)


def test_no_room_reaches_what_it_must_not():
    graph = {m: set() if m in ENVIRONMENT_ONLY else imports for m, imports in GRAPH.items()}
    broken = forbidden_reach(graph)
    assert not broken, "\n".join(broken)


def test_config_reaches_the_words_only():
    above = {m for m in reach(GRAPH, "casa_core.config") if m.startswith("casa_core")}
    assert above <= {"casa_core", "casa_core.vocabulary", "casa_core.defaults"}, above


PLANTED = {
    # low imports high inside a function: a hidden cycle, and an upward reach.
    "pkg/__init__.py": "",
    "pkg/low.py": "def f():\n    from pkg.high import g\n    return g\n",
    "pkg/high.py": "from pkg import low\n\ndef g():\n    return low\n",
    # mid is allowed to import low only, but reaches heavy through the face of pkg.sub.
    "pkg/mid.py": "import pkg.sub.light\n",
    "pkg/sub/__init__.py": "from pkg.sub import heavy\n",
    "pkg/sub/light.py": "",
    "pkg/sub/heavy.py": "import torch\n",
}


def test_the_checks_fail_on_a_planted_cycle_and_reach(tmp_path):
    for name, text in PLANTED.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(textwrap.dedent(text))
    graph = import_graph(tmp_path / "pkg")
    assert cycles(graph) == [["pkg.high", "pkg.low"]]
    rooms = {"low": ("pkg", "pkg.low"), "high": ("pkg.high",), "mid": ("pkg.mid",)}
    rooms |= {"sub": ("pkg.sub",)}
    may = {"low": set(), "high": {"low"}, "mid": {"low", "sub"}, "sub": {"low"}}
    assert upward_imports(graph, rooms, may) == ["pkg.low imports pkg.high (low -> high)"]
    reached = forbidden_reach(graph, {"mid": {"torch"}}, rooms)
    assert reached == ["pkg.mid reaches torch"]
    # Without the faces' imports the reach would go unseen.
    assert "pkg.sub.heavy" in reach(graph, "pkg.mid")


def test_modules_are_small():
    long = {
        module_name(p): n for p in MODULES if (n := len(p.read_text().splitlines())) > MAX_LINES
    }
    assert not long, f"modules over {MAX_LINES} lines: {long}"


def string_set(value: object) -> frozenset[str] | tuple[str, ...] | None:
    """A constant's strings: as a set from three on, in order for two (a pair's order is
    often its meaning, e.g. (new, reference))."""
    if not isinstance(value, tuple | list | frozenset | set) or len(value) < 2:
        return None
    if not all(isinstance(v, str) for v in value):
        return None
    return frozenset(value) if len(value) >= 3 else tuple(value)


VOCABULARY = {
    name: key
    for name, value in vars(vocabulary).items()
    if name.isupper() and (key := string_set(value)) is not None
}


def literal_strings(node: ast.AST) -> frozenset[str] | tuple[str, ...] | None:
    """The strings of a tuple/list/set literal of strings (:func:`string_set`), else None."""
    if not isinstance(node, ast.Tuple | ast.List | ast.Set):
        return None
    if not all(isinstance(e, ast.Constant) and isinstance(e.value, str) for e in node.elts):
        return None
    return string_set([e.value for e in node.elts])


def test_vocabulary_is_defined_once():
    # A literal listing the same names as a vocabulary tuple (in any order; a pair in its
    # order) is a second definition; a literal naming a subset (two of the methods) is a
    # choice, not a copy.
    copies = []
    for path in MODULES:
        if path.name == "vocabulary.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            strings = literal_strings(node)
            for name, value in VOCABULARY.items():
                if strings == value:
                    copies.append(f"{module_name(path)}:{node.lineno} repeats vocabulary.{name}")
    assert not copies, "\n".join(copies)


def top_level_constants(tree: ast.Module) -> dict[str, object]:
    """The module's ``UPPER_CASE = literal`` assignments (names and values)."""
    found = {}
    for node in tree.body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1:
            target = node.targets[0]
            if isinstance(target, ast.Name) and target.id.lstrip("_").isupper():
                try:
                    found[target.id] = ast.literal_eval(node.value)
                except ValueError:
                    continue
    return found


def repeated_definitions(paths: Iterable[Path], root: Path = PACKAGE) -> list[str]:
    """Every second definition of one thing: a constant of the same name and value in two
    modules, two constants (or a constant and a literal) listing the same strings, a
    function with the same name and body in two modules."""
    constants: dict[tuple[str, str], list[str]] = {}
    strings: dict[object, list[str]] = {}
    functions: dict[tuple[str, str], list[str]] = {}
    literals = []
    for path in paths:
        module = module_name(path, root)
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for name, value in top_level_constants(tree).items():
            if not isinstance(value, dict | list | set):
                constants.setdefault((name, repr(value)), []).append(module)
            if (key := string_set(value)) is not None:
                strings.setdefault(key, []).append(f"{module}.{name}")
        for node in tree.body:
            if isinstance(node, ast.FunctionDef):
                body = ast.dump(ast.Module(body=node.body, type_ignores=[]))
                functions.setdefault((node.name, body), []).append(module)
        for node in ast.walk(tree):
            if isinstance(node, ast.Tuple | ast.List | ast.Set):
                try:
                    key = string_set(ast.literal_eval(node))
                except ValueError:
                    continue
                if key is not None:
                    literals.append((key, module, node.lineno))
    found = [
        f"{name} = {value} in {', '.join(where)}"
        for (name, value), where in constants.items()
        if len(where) > 1
    ]
    found += [
        f"the same strings: {', '.join(where)}" for where in strings.values() if len(where) > 1
    ]
    found += [
        f"def {name} in {', '.join(where)}"
        for (name, _), where in functions.items()
        if len(where) > 1
    ]
    for key, module, line in literals:
        owners = [o for o in strings.get(key, []) if not o.startswith(module + ".")]
        if owners:
            found.append(f"{module}:{line} repeats {', '.join(owners)}")
    return found


def test_nothing_is_defined_twice():
    found = repeated_definitions(MODULES)
    assert not found, "\n".join(found)


REPEATED = {
    "pkg/__init__.py": "",
    "pkg/a.py": 'TICK = 0.05\nGOALS = ("green", "purple")\n\ndef _as_list(x):\n    return [x]\n',
    "pkg/b.py": 'TICK = 0.05\n\ndef _as_list(x):\n    return [x]\n\nNAMES = ["green", "purple"]\n',
    "pkg/c.py": 'def f():\n    return ("green", "purple")\n\nPAIR = ("purple", "green")\n',
}


def test_the_check_finds_each_kind_of_repetition(tmp_path):
    for name, text in REPEATED.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    found = repeated_definitions(sorted((tmp_path / "pkg").rglob("*.py")), tmp_path / "pkg")
    assert "TICK = 0.05 in pkg.a, pkg.b" in found
    assert "the same strings: pkg.a.GOALS, pkg.b.NAMES" in found
    assert "def _as_list in pkg.a, pkg.b" in found
    assert "pkg.c:2 repeats pkg.a.GOALS, pkg.b.NAMES" in found
    assert not any("PAIR" in line for line in found)  # another order: another pair


def test_one_condition_of():
    defined = [
        module_name(path)
        for path in MODULES
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
        if isinstance(node, ast.FunctionDef) and node.name == "condition_of"
    ]
    assert defined == ["casa_core.vocabulary"]


def test_the_scene_has_one_name():
    # The scene is a casa_core.scene.Scene called `scene`; `layout` was a second name for it.
    named_layout = [
        f"{module_name(path)}:{node.lineno} {node.name}"
        for path in MODULES
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
        and any(a.arg == "layout" for a in node.args.args + node.args.kwonlyargs)
    ]
    assert not named_layout, "\n".join(named_layout)


def test_code_cites_the_repository_docs_only():
    root = PACKAGE.parent
    files = [*MODULES, root / "README.md", *sorted((root / "workflow").rglob("*.smk"))]
    files += sorted((root / "config").glob("*.yaml"))
    citing = [str(p.relative_to(root)) for p in files if "NOTES" in p.read_text(encoding="utf-8")]
    assert not citing, f"cite docs/ instead of NOTES: {citing}"
    cited = {"docs/paper-to-code.md", "docs/departures.md", "docs/data-contracts.md"}
    for page in cited:
        assert (root / page).is_file(), f"{page} is cited but missing"


#: Rooms whose every public function shows its use in a docstring example that runs.
EXAMPLED = ["casa_core.model", "casa_core.vocabulary", "casa_core.io", "casa_core.stats"]


def test_public_functions_have_examples():
    lacking = []
    for path in MODULES:
        if room_of(module_name(path), {"exampled": EXAMPLED}) is None:
            continue
        if path.name.startswith("_") and path.name != "__init__.py":
            continue  # private modules: their callers' examples exercise them
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            public = isinstance(node, ast.FunctionDef) and not node.name.startswith("_")
            if public and ">>>" not in (ast.get_docstring(node) or ""):
                lacking.append(f"{module_name(path)}.{node.name}")
    assert not lacking, f"public functions without a docstring example: {lacking}"


#: Rooms of single modules at the package's top level, with no face of their own.
TOP_LEVEL = {"words", "ground", "numerics", "algebra"}


@pytest.mark.parametrize("face", sorted({room_of(m) for m in GRAPH} - TOP_LEVEL))
def test_each_room_has_a_face_that_says_its_modules(face):
    # The face's docstring names each public module of its package.
    for prefix in ROOMS[face]:
        init = PACKAGE.parent / prefix.replace(".", "/") / "__init__.py"
        doc = ast.get_docstring(ast.parse(init.read_text(encoding="utf-8"))) or ""
        modules = sorted(p.stem for p in init.parent.glob("*.py") if not p.name.startswith("_"))
        missing = [m for m in modules if f"{prefix}.{m}" not in doc and f".{m}`" not in doc]
        assert not missing, f"{prefix}'s docstring does not name {missing}"
