"""The pages of a dataset built with allow_invalid=true say what was left out and where the list is.

The dataset is the synthetic one of tests/analysis/test_datasets.py, broken there in two
trial logs and one line of surveys.csv, and processed with ``allow_invalid=True``: its
validation table lists them. ``casa stats``, ``casa report summary`` and ``casa report
results`` then write the three pages the workflow writes from those tables.
"""

from __future__ import annotations

import pytest

from casa_core.cli import main
from casa_core.io import read_table
from casa_core.io.atomic import write_csv
from casa_core.stats import analyze_study
from casa_core.stats.claims import evaluate_claims
from casa_core.stats.results import ROBUSTNESS_NOTE, results_markdown
from tests.analysis.test_datasets import _break, process
from tests.io.test_logs_synthetic import SCENE, write_dataset

LEFT_OUT = (
    "Left out: 2 trial logs and the lines of 1 problem in surveys.csv that break the data "
    "contract, excluded with allow_invalid=true; the list, with each problem, is in {path} "
    "(status excluded)."
)


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    root = tmp_path_factory.mktemp("left_out")
    write_dataset(root / "raw", participants=("p01", "p02"))
    _break(root / "raw")
    out = root / "processed"
    tables = process(root / "raw", out, SCENE, allow_invalid=True)
    write_csv(out / "validation.csv", tables.validation)
    return out


def test_stats_summary_and_results_say_how_many_trials_were_left_out(built, capsys):
    validation = str(built / "validation.csv")
    stats = ["stats", "--trials", str(built / "trials.csv"), "--likert", str(built / "likert.csv")]
    stats += ["--out-csv", str(built / "stats.csv"), "--out-md", str(built / "stats.md")]
    assert main([*stats, "--validation", validation]) == 0
    summary = ["report", "summary", "--stats", str(built / "stats.csv"), "--dataset", "lab"]
    summary += ["--out-md", str(built / "summary.md"), "--out-html", str(built / "s.html")]
    assert main([*summary, "--validation", validation]) == 0
    results = ["report", "results", "--dataset", "lab", "--out", str(built / "results.md")]
    results += [f"--{n}={built / n}.csv" for n in ("trials", "steps", "stats", "likert")]
    assert main([*results, "--validation", validation]) == 0
    said = LEFT_OUT.format(path=validation)
    for page in ("stats.md", "summary.md", "results.md"):
        text = (built / page).read_text()
        assert said in text, page
        # Near the top: before the first section.
        assert text.index(said) < text.index("\n## "), page
    # Without --validation (or with nothing excluded) no page says so.
    assert main(stats) == 0
    assert "Left out" not in (built / "stats.md").read_text()
    capsys.readouterr()


def test_a_dataset_of_simulated_logs_is_told_the_robustness_table_is_not_its_own(built):
    # The newcomer's lab dataset: logs copied from the simulated study (source simulated),
    # built as a dataset of its own: the workflow names no operator model for it.
    tables = {n: read_table(built / f"{n}.csv") for n in ("trials", "steps")}
    tables["stats"] = analyze_study(tables["trials"], metrics=["error"])
    assert set(tables["trials"]["source"]) == {"simulated"}
    judged = evaluate_claims(tables, epsilon=1.0)
    text = results_markdown(judged, tables, dataset="mylab")
    assert ROBUSTNESS_NOTE not in text
    assert "This dataset is not the simulated study the config builds" in text
    # The simulated study itself (an operator model named) points to the table.
    assert ROBUSTNESS_NOTE in results_markdown(
        judged, tables, dataset="simulated", operator="predictive"
    )
