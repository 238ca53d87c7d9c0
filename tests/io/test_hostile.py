"""The hostile-input corpus (``tests/io/hostile/make_corpus.py``) via ``casa validate`` and the DAG.

Each case is one dataset folder breaking one thing; its expected outcome (an error
with its rule, a warning with its rule, or valid) is stated by the generator, from
the contract ``docs/data-contracts.md``. Every case must give exactly that outcome,
name the file, and never a traceback; the DAG over all cases at once must leave every
raw file byte-identical.

Corpus: 71 cases: 63 errors, 5 warnings, 3 valid (``test_corpus_counts`` checks these
numbers against the generator).
"""

from __future__ import annotations

import csv
import hashlib
import os
import re
import shutil
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

from casa_core.cli import main
from casa_core.vocabulary import QUESTIONS
from tests.io.hostile.make_corpus import make_corpus, planned

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
ENV = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}
PLANNED = planned()
#: Error cases whose dataset keeps good rows or files once the bad ones are excluded.
PARTIAL = ("surveys_score_8", "duplicate_condition", "upper_case_extension")
RULE_TOKEN = re.compile(r"\[([a-z0-9-]+)\]")


def _known_rules() -> str:
    """The validator's source, where every rule it reports is spelled as a string."""
    return "".join(p.read_text(encoding="utf-8") for p in (ROOT / "casa_core" / "io").glob("*.py"))


SOURCE = _known_rules()


def _params():
    params = []
    for name, outcome in PLANNED:
        marks = []
        if len(outcome) > 1 and f'"{outcome[1]}"' not in SOURCE:
            marks.append(pytest.mark.xfail(reason="rule not yet in the validator", strict=False))
        params.append(pytest.param(name, marks=marks, id=name))
    return params


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("corpus")
    return folder, {case.name: case for case in make_corpus(folder)}


def test_corpus_counts():
    counts = Counter(outcome[0] for _, outcome in PLANNED)
    line = (
        f"Corpus: {len(PLANNED)} cases: {counts['error']} errors, {counts['warning']} warnings, "
        f"{counts['valid']} valid"
    )
    print(line)
    assert line in " ".join(__doc__.split()), line
    assert len({name for name, _ in PLANNED}) == len(PLANNED)


@pytest.mark.parametrize("name", _params())
def test_validate_gives_the_expected_outcome(corpus, name, capsys):
    root, cases = corpus
    case = cases[name]
    folder = root / name
    code = main(["validate", str(folder)])
    output = capsys.readouterr()
    text = output.out + output.err
    assert "Traceback" not in text
    kind = case.outcome[0]
    if kind == "valid":
        assert code == 0, text
        assert RULE_TOKEN.findall(text) == [], text
        return
    assert code == (1 if kind == "error" else 0), text
    named = str(folder / case.file) if case.file else str(folder)
    mark = "warning " if kind == "warning" else ""
    lines = [line for line in text.splitlines() if f"{mark}[{case.rule}]" in line]
    assert any(named in line for line in lines), f"expected {named}: {mark}[{case.rule}] in\n{text}"
    if kind == "error":
        # The expected rule is broken as an error, not only a warning.
        assert any("warning [" not in line for line in lines), text


def _copy_workflow(folder: Path) -> Path:
    for name in ("Snakefile", "workflow", "config", "profiles"):
        source = ROOT / name
        if source.is_dir():
            shutil.copytree(source, folder / name)
        elif source.is_file():
            shutil.copy(source, folder / name)
    return folder


def _fingerprint(folder: Path) -> dict[str, str]:
    """Every file and link below ``folder`` (links not followed): its bytes' sha256, or target."""
    found = {}
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            path = Path(root) / name
            key = path.relative_to(folder).as_posix()
            if path.is_symlink():
                found[key] = f"link -> {os.readlink(path)}"
            elif path.is_file():
                found[key] = hashlib.sha256(path.read_bytes()).hexdigest()
    return found


@pytest.mark.pipeline
def test_dag_over_the_whole_corpus_keeps_raw_data_and_reports_every_case(tmp_path):
    repo = _copy_workflow(tmp_path)
    raw = repo / "data" / "raw"
    cases = make_corpus(raw)
    before = _fingerprint(raw)
    # Every case is validated; processing (a job per dataset, the slow part) runs where
    # something is left to process once bad files are excluded.
    processed = [case for case in cases if case.outcome[0] != "error" or case.name in PARTIAL]
    targets = [f"data/processed/{case.name}/validation.csv" for case in cases] + [
        f"data/processed/{case.name}/trials.csv" for case in processed
    ]
    result = subprocess.run(
        [str(BIN / "snakemake"), "--cores", "2", "--keep-going", "--scheduler", "greedy"]
        + targets
        + ["--config", "simulate=false", "allow_invalid=true"],
        cwd=repo,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=600,
    )
    text = result.stdout + result.stderr
    assert "Traceback" not in text, text[-3000:]
    for log in (repo / "logs").rglob("*"):
        if log.is_file():
            assert "Traceback" not in log.read_text(errors="replace"), log
    assert _fingerprint(raw) == before
    assert result.returncode == 0, text[-3000:]
    missing = []
    for case in cases:
        tables = repo / "data" / "processed" / case.name
        if case in processed:
            assert (tables / "trials.csv").is_file(), case.name
        with open(tables / "validation.csv", newline="", encoding="utf-8") as handle:
            rows = list(csv.DictReader(handle))
        if case.rule is None:
            assert {row["status"] for row in rows} <= {"ok", "ignored"}, (case.name, rows)
        elif f'"{case.rule}"' not in SOURCE:
            continue  # rule not yet in the validator (xfail in the casa validate test)
        elif not any(row["rule"] == case.rule and row["file"] == case.report for row in rows):
            missing.append((case.name, case.rule, case.report, rows))
    assert missing == []
    # With allow_invalid, one bad Likert row leaves out that row only: the generator writes
    # one answer per question (3) and breaks one.
    with open(repo / "data" / "processed" / "surveys_score_8" / "likert.csv", newline="") as f:
        assert len(list(csv.DictReader(f))) == len(QUESTIONS) - 1
