"""Effort relative to NA (1 under NA by construction) and effort on a log scale."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from casa_core.stats import analyze_study, rm_anova
from casa_core.stats.study import LOG_EFFORT, ONE_SAMPLE_NOTE
from tests.stats.test_stats_study import make_trials


@pytest.fixture(scope="module")
def trials() -> pd.DataFrame:
    # relative_effort as the pipeline defines it: effort over the same participant's NA
    # effort on the same task, so exactly 1 under NA.
    frame = make_trials(n_participants=11, seed=0)
    frame = frame[frame["task"] == "known_goal"].copy()
    na = frame[frame["method"] == "NA"].set_index("participant")["effort"]
    frame["relative_effort"] = frame["effort"] / frame["participant"].map(na)
    return frame


@pytest.fixture(scope="module")
def table(trials) -> pd.DataFrame:
    return analyze_study(trials, metrics=["relative_effort", "effort"])


def _h1(table, **where):
    rows = table[table["hypothesis"] == "H1"]
    for column, value in where.items():
        rows = rows[rows[column] == value]
    return rows


def test_relative_effort_rows_say_they_are_one_sample_tests(trials, table):
    assert (trials.loc[trials["method"] == "NA", "relative_effort"] == 1.0).all()
    rows = _h1(table, metric="relative_effort")
    tested = rows[rows["analysis"] != "noninferiority"]
    assert tested["note"].str.contains(ONE_SAMPLE_NOTE, regex=False).all()
    # Other metrics are not flagged.
    assert not _h1(table, metric="effort")["note"].str.contains("one-sample").any()


def test_one_sample_against_na_welch_df(trials):
    # CASA against NA on relative effort: NA's 11 cells are all 1, so Welch's df is that of
    # a one-sample t on the 11 CASA cells, 10, where the pooled test claims 11 + 11 - 2.
    from casa_core.stats import non_inferiority

    welch = non_inferiority(trials, "relative_effort", "method", "CASA", "NA", welch=True)
    pooled = non_inferiority(trials, "relative_effort", "method", "CASA", "NA")
    assert welch.iloc[0]["df"] == pytest.approx(10, abs=1e-9)
    assert pooled.iloc[0]["df"] == 20
    assert "one-sample test" in welch.iloc[0]["note"]


def test_log_effort_rows_are_within_subjects_only(trials, table):
    rows = table[table["metric"] == LOG_EFFORT]
    assert set(rows["analysis"]) == {"rm_anova", "mixedlm", "mixedlm_lrt"}
    assert set(rows["hypothesis"]) == {"H1", "H2", "H3"}
    # By construction: the H1 row is rm_anova on log(effort + 1) of each trial.
    direct = rm_anova(
        trials.assign(y=np.log1p(trials["effort"])), "y", "method", "participant"
    ).iloc[0]
    row = _h1(table, metric=LOG_EFFORT, analysis="rm_anova").iloc[0]
    # stats.csv holds 8 significant digits (stats._rows.DIGITS): half a unit in the 8th.
    assert row["statistic"] == pytest.approx(direct["F"], rel=1e-8)
    assert row["p_uncorrected"] == pytest.approx(direct["p"], rel=1e-8)
