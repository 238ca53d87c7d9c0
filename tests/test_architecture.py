"""The package's shape: imports run one way, the vocabulary is defined once, modules stay small.

These read the source (``ast``), so they check what the code says, not what one run
happened to import.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from casa_core import vocabulary

PACKAGE = Path(__file__).resolve().parents[1] / "casa_core"
MODULES = sorted(PACKAGE.rglob("*.py"))
#: "About 400 lines": a module past this has more than one job.
MAX_LINES = 420


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported(path: Path) -> set[str]:
    """Every module ``path`` imports, at any depth of the file (lazy imports included)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            names |= {f"{node.module}.{alias.name}" for alias in node.names}
    return names


def in_layer(name: str, layer: str) -> bool:
    return name == layer or name.startswith(layer + ".")


def modules_of(*layers: str) -> list[Path]:
    return [p for p in MODULES if any(in_layer(module_name(p), layer) for layer in layers)]


EQUATIONS = ("casa_core.confidence", "casa_core.inference", "casa_core.arbitration")
# (layer, what it must not import): the arrows of docs/index.md.
FORBIDDEN = [
    (EQUATIONS + ("casa_core._checks",), ("casa_core.intents", "casa_core.assistant")),
    (EQUATIONS + ("casa_core._checks",), ("pybullet", "torch", "pandas", "yaml", "json")),
    (EQUATIONS + ("casa_core._checks",), ("pathlib", "os", "io", "csv")),
    (("casa_core.intents", "casa_core.assistant"), ("casa_core.planning", "casa_core.learning")),
    (("casa_core.intents", "casa_core.assistant"), ("casa_core.study", "casa_core.robot")),
    (("casa_core.planning",), ("casa_core.learning", "casa_core.study", "casa_core.library")),
    (("casa_core.learning",), ("casa_core.study", "casa_core.skills", "casa_core.library")),
    (("casa_core.learning",), ("casa_core.io", "casa_core.robot", "pybullet")),
    (("casa_core.library",), ("casa_core.study", "casa_core.robot", "casa_core.io.trial_log")),
    (("casa_core.io",), ("casa_core.study", "casa_core.robot", "casa_core.learning")),
    (("casa_core.robot",), ("casa_core.learning", "casa_core.library", "casa_core.study")),
    (("casa_core.stats", "casa_core.figures"), ("casa_core.robot", "casa_core.study")),
    (("casa_core.stats", "casa_core.figures"), ("casa_core.learning", "casa_core.library")),
    (("casa_core.stats", "casa_core.figures"), ("pybullet", "torch", "casa_core.skills")),
    (("casa_core.vocabulary", "casa_core.defaults"), ("casa_core", "numpy", "pandas")),
    # Replay redoes inference over logs: no simulator, no study, no drawing.
    (("casa_core.replay",), ("casa_core.study", "casa_core.robot.sim", "pybullet")),
    (("casa_core.replay",), ("casa_core.figures", "casa_core.cli", "casa_core.planning")),
]


@pytest.mark.parametrize(("layers", "forbidden"), FORBIDDEN, ids=lambda v: ",".join(v))
def test_imports_run_one_way(layers, forbidden):
    broken = [
        f"{module_name(path)} imports {name}"
        for path in modules_of(*layers)
        for name in sorted(imported(path))
        if any(in_layer(name, f) for f in forbidden)
    ]
    assert not broken, "\n".join(broken)


def test_every_layer_named_above_exists():
    # A renamed package would make the rules above pass vacuously.
    for layers, _ in FORBIDDEN:
        assert modules_of(*layers), f"no module in {layers}"


def test_modules_are_small():
    long = {
        module_name(p): n for p in MODULES if (n := len(p.read_text().splitlines())) > MAX_LINES
    }
    assert not long, f"modules over {MAX_LINES} lines: {long}"


VOCABULARY = {
    name: frozenset(value)
    for name, value in vars(vocabulary).items()
    if name.isupper() and isinstance(value, tuple) and len(value) >= 2
}


def literal_strings(node: ast.AST) -> frozenset[str] | None:
    """The strings of a tuple/list/set literal of strings, else None."""
    if not isinstance(node, ast.Tuple | ast.List | ast.Set) or len(node.elts) < 2:
        return None
    if not all(isinstance(e, ast.Constant) and isinstance(e.value, str) for e in node.elts):
        return None
    return frozenset(e.value for e in node.elts)


def test_vocabulary_is_defined_once():
    # A literal listing the same names as a vocabulary tuple (in any order) is a second
    # definition; a literal naming a subset (e.g. two of the methods) is a choice, not a copy.
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


#: Modules whose every public function shows its use in a docstring example that runs.
EXAMPLED = [*EQUATIONS, "casa_core._checks", "casa_core.tables", "casa_core.vocabulary"]
EXAMPLED += ["casa_core.io", "casa_core.stats"]


def test_public_functions_have_examples():
    lacking = []
    for path in modules_of(*EXAMPLED):
        if path.name.startswith("_") and path.name != "__init__.py":
            continue  # private modules: their callers' examples exercise them
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            public = isinstance(node, ast.FunctionDef) and not node.name.startswith("_")
            if public and ">>>" not in (ast.get_docstring(node) or ""):
                lacking.append(f"{module_name(path)}.{node.name}")
    assert not lacking, f"public functions without a docstring example: {lacking}"
