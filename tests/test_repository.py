"""The repository agrees with itself: the map of the package, the environments' pins."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "casa_core"


def package_files() -> set[str]:
    """Every file of the package but the faces (``__init__.py``) and caches."""
    return {
        p.relative_to(PACKAGE).as_posix()
        for p in PACKAGE.rglob("*")
        if p.is_file() and p.name != "__init__.py" and "__pycache__" not in p.parts
    }


def index_files(text: str) -> set[str]:
    """The files docs/index.md names in the first column of its package tables."""
    section = text.split("## The package, `casa_core/`")[1].split("## Around the package")[0]
    named = set()
    for line in section.splitlines():
        if line.startswith("| `"):
            first = line.split("|")[1]
            named |= set(re.findall(r"`([^`]+)`", first))
    return named


def test_docs_index_names_every_file_of_the_package_and_no_other():
    named = index_files((ROOT / "docs" / "index.md").read_text(encoding="utf-8"))
    files = package_files()
    assert not files - named, f"docs/index.md does not name {sorted(files - named)}"
    assert not named - files, (
        f"docs/index.md names files that do not exist: {sorted(named - files)}"
    )


def test_the_index_check_sees_a_missing_and_a_stale_row():
    text = "## The package, `casa_core/`\n| `a.py`, `b/c.py` | job |\n| `d.py` | x |\n"
    assert index_files(text + "## Around the package\n| `e.py` | not a module |\n") == {
        "a.py",
        "b/c.py",
        "d.py",
    }


def test_the_conda_environment_has_the_pins_of_pyproject():
    # The jobs' environment (`--sdm conda`) runs casa, not Snakemake.
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    pins = {d for d in project["project"]["dependencies"] if not d.startswith("snakemake")}
    env = yaml.safe_load((ROOT / "workflow" / "envs" / "casa.yaml").read_text(encoding="utf-8"))
    pip = next(d["pip"] for d in env["dependencies"] if isinstance(d, dict))
    assert {d for d in pip if not d.startswith("--")} == pins


#: Calls that can run code held in a file: unpickling (numpy with pickles allowed,
#: pickle, torch.load, which unpickles) and YAML's full loaders.
CODE_RUNNING_LOADS = re.compile(
    r"allow_pickle\s*=\s*True|\bpickle\.loads?\(|\btorch\.load\(|yaml\.(unsafe_)?load\(|"
    r"yaml\.full_load\(|\beval\(|\bexec\("
)


def code_running_loads(text: str) -> list[str]:
    return [line.strip() for line in text.splitlines() if CODE_RUNNING_LOADS.search(line)]


def test_no_loader_of_the_package_or_workflow_can_run_code_from_a_file():
    files = [*(ROOT / "casa_core").rglob("*.py"), *(ROOT / "workflow").rglob("*.smk")]
    found = {
        str(path.relative_to(ROOT)): hits
        for path in files
        if (hits := code_running_loads(path.read_text(encoding="utf-8")))
    }
    assert found == {}


def test_the_loader_check_sees_each_kind_of_code_running_load():
    planted = [
        "np.load(path, allow_pickle=True)",
        "pickle.load(handle)",
        "torch.load(path)",
        "yaml.load(text, Loader=yaml.Loader)",
        "yaml.unsafe_load(text)",
    ]
    assert code_running_loads("\n".join(planted)) == planted
    assert code_running_loads("np.load(path, allow_pickle=False)\nyaml.safe_load(text)") == []
