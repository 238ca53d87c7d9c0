"""The wide per-participant table (``casa stats --out-wide``, wide.csv)."""

from __future__ import annotations

import csv
import math
import re
from collections import defaultdict

import pandas as pd
import pytest

from casa_core import cli
from casa_core.stats.wide import wide_column
from casa_core.vocabulary import TASK_CONDITIONS, condition_of
from tests.stats.test_stats_study import make_trials

METRICS = ("error", "efficiency", "relative_effort", "effort")


def _means_from_csv(path) -> dict[tuple[str, str, str, str], float]:
    """Each participant's mean per task, condition and metric, read row by row from a
    trials.csv with the csv module: independent of the pandas grouping under test."""
    values = defaultdict(list)
    with open(path, newline="") as handle:
        for row in csv.DictReader(handle):
            condition = condition_of(row["method"], row["phase"])
            if condition is None:
                continue  # familiarization is not a condition
            for metric in METRICS:
                if row[metric] != "":
                    key = (row["participant"], row["task"], condition, metric)
                    values[key].append(float(row[metric]))
    return {key: math.fsum(v) / len(v) for key, v in values.items()}


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    folder = tmp_path_factory.mktemp("wide")
    trials = make_trials(n_participants=4, seed=3)
    # A repeated trial (its cell is the mean of two) and a missing cell (an empty one).
    repeat = trials[(trials["participant"] == "P01") & (trials["method"] == "PBA")].copy()
    repeat["error"] += 1.5
    missing = (trials["participant"] == "P02") & (trials["task"] == "known_goal")
    missing &= trials["method"] == "CASA"
    # Row order must not matter: reversed, the repeat last.
    trials = pd.concat([trials[~missing].iloc[::-1], repeat], ignore_index=True)
    trials.to_csv(folder / "trials.csv", index=False)
    out = [str(folder / name) for name in ("stats.csv", "stats.md", "wide.csv")]
    code = cli.main(
        ["stats", "--trials", str(folder / "trials.csv"), "--out-csv", out[0], "--out-md", out[1]]
        + ["--out-wide", out[2]]
    )
    assert code == 0
    with open(out[2], newline="") as handle:
        rows = list(csv.DictReader(handle))
    first = float(repeat.loc[repeat["task"] == "known_goal", "error"].iloc[0]) - 1.5
    return _means_from_csv(folder / "trials.csv"), rows, first


def test_one_row_per_participant_and_names_jasp_spss_and_r_accept(written):
    _, rows, _ = written
    assert [row["participant"] for row in rows] == ["P00", "P01", "P02", "P03"]
    header = list(rows[0])
    assert header[0] == "participant"
    # A variable name of SPSS (the strictest of the three): a letter, then letters,
    # digits and underscores, at most 64 characters.
    assert all(re.fullmatch(r"[A-Za-z][A-Za-z0-9_]{0,63}", name) for name in header)
    # Every condition the study runs on each task, times the four metrics.
    assert len(header) == 1 + 4 * sum(len(c) for c in TASK_CONDITIONS.values())


def test_values_are_the_participants_means_of_trials_csv(written):
    means, rows, first = written
    checked = 0
    for row in rows:
        for task, conditions in TASK_CONDITIONS.items():
            for condition in conditions:
                for metric in METRICS:
                    cell = row[wide_column(task, condition, metric)]
                    expected = means.get((row["participant"], task, condition, metric))
                    if expected is None:
                        assert cell == "", (row["participant"], task, condition, metric)
                    else:
                        assert float(cell) == pytest.approx(expected, rel=1e-12, abs=1e-15)
                        checked += 1
    # Everything but the missing cell's four metrics was compared.
    assert checked == 4 * 4 * sum(len(c) for c in TASK_CONDITIONS.values()) - 4
    # The repeated PBA trial (error 1.5 above the first) is averaged in.
    assert float(rows[1]["known_goal_PBA_error"]) == pytest.approx(first + 0.75, rel=1e-12)
    assert rows[2]["known_goal_CASA_error"] == ""


def test_a_name_outside_the_rule_is_an_error():
    with pytest.raises(ValueError, match="not a name JASP, SPSS and R accept"):
        wide_column("9task", "NA", "error")
