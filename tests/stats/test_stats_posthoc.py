"""casa_core.stats.posthoc: the ANCOVA form's interaction and model-based comparisons.

References: pingouin.anova's documentation (pingouin-stats.org/build/html/generated/
pingouin.anova.html) on its bundled "anova2" and "anova2_unbalanced" datasets, and closed
forms on the balanced design.
"""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pingouin
import pytest
from scipy import stats

from casa_core.stats import analyze_study, tukey_hsd
from casa_core.stats.posthoc import interaction, model_contrasts


def _dataset(name: str) -> pd.DataFrame:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return pingouin.read_dataset(name)


@pytest.fixture(scope="module")
def crops() -> pd.DataFrame:
    # 3 crops x 2 blends x 4 plots, balanced.
    return _dataset("anova2")


def test_interaction_matches_pingouin_docs_balanced(crops):
    # pingouin docs, two-way ANOVA with balanced design: Blend * Crop SS 2360.083, DF 2,
    # F 2.178, p_unc 0.142; Residual SS 9753.250, DF 18 (printed to 3 decimals).
    row = interaction(crops, "Yield", "Crop", "Blend").iloc[0]
    assert (row["term"], row["df1"], row["df2"], row["n"]) == ("Crop x Blend", 2, 18, 24)
    assert row["F"] == pytest.approx(2.178, abs=5e-4)
    assert row["p"] == pytest.approx(0.142, abs=5e-4)
    assert row["np2"] == pytest.approx(2360.083 / (2360.083 + 9753.250), abs=1e-6)


def test_interaction_matches_pingouin_docs_unbalanced():
    # pingouin docs, unbalanced design (statsmodels): Diet * Exercise SS 15.625, DF 1,
    # F 0.297, p_unc 0.605; Residual DF 6.
    data = _dataset("anova2_unbalanced")
    row = interaction(data, "Scores", "Diet", "Exercise").iloc[0]
    assert (row["df1"], row["df2"]) == (1, 6)
    assert row["F"] == pytest.approx(0.297, abs=5e-4)
    assert row["p"] == pytest.approx(0.605, abs=5e-4)


def test_model_contrasts_closed_form_on_the_balanced_design(crops):
    # Balanced: the contrast of two crops in Yield ~ Crop + Blend is the difference of
    # their marginal means; its SE is sqrt(MSE (1/8 + 1/8)) with the additive model's
    # MSE = (SS_residual + SS_interaction) / (18 + 2) from pingouin's published table;
    # Tukey's p is the studentized range of 3 means on 20 df at |t| sqrt(2).
    table = model_contrasts(crops, "Yield", "Crop", "Blend").set_index(["A", "B"])
    means = crops.groupby("Crop")["Yield"].mean()
    mse = (9753.250 + 2360.083) / 20
    se = np.sqrt(mse * (1 / 8 + 1 / 8))
    half = stats.studentized_range.ppf(0.95, 3, 20) / np.sqrt(2)
    for a, b in (("Corn", "Soy"), ("Corn", "Wheat"), ("Soy", "Wheat")):
        row = table.loc[(a, b)]
        diff = means[a] - means[b]
        assert row["diff"] == pytest.approx(diff, abs=1e-9)
        assert row["se"] == pytest.approx(se, rel=1e-6)  # published SS to 3 decimals
        assert row["df"] == 20
        t = diff / se
        assert row["p"] == pytest.approx(stats.studentized_range.sf(abs(t) * np.sqrt(2), 3, 20))
        assert row["ci_low"] == pytest.approx(diff - half * se, rel=1e-5)
        assert (row["n_A"], row["n_B"]) == (8, 8)


def test_model_contrasts_holm(crops):
    # Holm over the three unadjusted t-test p-values of the same contrasts (2 t(20) tails).
    tukey = model_contrasts(crops, "Yield", "Crop", "Blend")
    holm = model_contrasts(crops, "Yield", "Crop", "Blend", adjust="holm")
    raw = 2 * stats.t.sf(np.abs(tukey["t"].to_numpy()), 20)
    order = np.argsort(raw)
    expected = np.maximum.accumulate(np.minimum(1, raw[order] * np.array([3, 2, 1])))
    assert holm["p"].to_numpy()[order] == pytest.approx(expected)
    with pytest.raises(ValueError, match="adjust must be"):
        model_contrasts(crops, "Yield", "Crop", "Blend", adjust="bonferroni")


def test_model_contrasts_remove_the_covariate_from_the_residual(crops):
    # The one-way Tukey test leaves the blend effect in its residual: same differences
    # on the balanced design, a different (here larger) standard error.
    shifted = crops.assign(Yield=crops["Yield"] + np.where(crops["Blend"] == "Blend X", 60, 0))
    model = model_contrasts(shifted, "Yield", "Crop", "Blend")
    oneway = tukey_hsd(shifted, "Yield", "Crop")
    assert model["diff"].to_numpy() == pytest.approx(oneway["diff"].to_numpy())
    assert (model["ci_high"] - model["ci_low"] < oneway["ci_high"] - oneway["ci_low"]).all()


def test_degenerate_contrasts_and_interaction(crops):
    one_blend = crops[crops["Blend"] == "Blend X"]
    note = model_contrasts(one_blend, "Yield", "Crop", "Blend").iloc[0]["note"]
    assert "the covariate 'Blend' takes a single value" in note
    one_crop = crops[crops["Crop"] == "Corn"]
    assert "at least 2 levels" in interaction(one_crop, "Yield", "Crop", "Blend").iloc[0]["note"]
    # One empty cell of six: five cell means against the additive model's four parameters
    # leave one interaction degree of freedom; residual 20 - 5.
    empty_cell = crops[~((crops["Crop"] == "Soy") & (crops["Blend"] == "Blend Y"))]
    row = interaction(empty_cell, "Yield", "Crop", "Blend").iloc[0]
    assert (row["df1"], row["df2"]) == (1, 15) and np.isfinite(row["F"])
    # Each crop in one blend only: nothing left for the interaction.
    split = crops[(crops["Crop"] == "Corn") == (crops["Blend"] == "Blend X")]
    assert "not estimable" in interaction(split, "Yield", "Crop", "Blend").iloc[0]["note"]


def test_study_pooled_rows_use_the_model_with_task():
    # H2 pooled: the Tukey rows are model_contrasts over method + task, and an interaction
    # row method x task with df (2, 66 - 6) follows the ANCOVA rows.
    from tests.stats.test_stats_study import make_trials

    trials = make_trials(n_participants=11, seed=0)
    table = analyze_study(trials, metrics=["error"])
    pooled = table[(table["hypothesis"] == "H2") & (table["task"] == "unknown_goal+unknown_skill")]
    inter = pooled[(pooled["analysis"] == "ancova") & (pooled["term"] == "method x task")]
    assert len(inter) == 1 and (inter["df1"].iloc[0], inter["df2"].iloc[0]) == (2, 60)
    tukey = pooled[pooled["analysis"] == "tukey"]
    assert tukey["note"].str.contains("method \\+ task", regex=True).all()
    assert (tukey["df1"] == 62).all()  # the ANCOVA's residual df
