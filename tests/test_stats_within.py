"""casa_core.stats.within against published R output (sources: tests/reference/stats)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pingouin
import pytest
from scipy import stats
from statsmodels.stats.anova import AnovaRM

from casa_core.stats import friedman, holm, mixedlm, rm_anova, wilcoxon_holm

REF = Path(__file__).parent / "reference" / "stats"


@pytest.fixture(scope="module")
def sleep() -> pd.DataFrame:
    return pd.read_csv(REF / "sleep.csv", dtype={"group": str})


@pytest.fixture(scope="module")
def two_way() -> pd.DataFrame:
    # pingouin's "rm_anova2" dataset: 2 x 3 fully within design (Time x Metric).
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return pingouin.read_dataset("rm_anova2")


# ---------------------------------------------------------- repeated-measures ANOVA


def test_rm_anova_two_levels_is_the_paired_t_squared(sleep):
    # R ?sleep: paired t.test gives t = -4.0621, df = 9, p-value = 0.002833.  With two
    # within levels the repeated-measures F is t squared with df (1, 9) and the same p.
    row = rm_anova(sleep, "extra", "group", "ID").iloc[0]
    assert (row["df1"], row["df2"], row["n"]) == (1, 9, 10)
    assert row["F"] == pytest.approx(4.0621**2, rel=5e-5)
    assert row["p"] == pytest.approx(0.002833, abs=5e-7)


def test_rm_anova_two_factors_agrees_with_statsmodels(two_way):
    # Independent implementation: statsmodels AnovaRM (univariate, uncorrected) on the same
    # balanced data gives the same F, df and p for both main effects and the interaction.
    ours = rm_anova(two_way, "Performance", ["Time", "Metric"], "Subject").set_index("term")
    theirs = AnovaRM(two_way, "Performance", "Subject", within=["Time", "Metric"]).fit()
    table = theirs.anova_table
    for term, key in (("Time", "Time"), ("Metric", "Metric"), ("Time * Metric", "Time:Metric")):
        assert ours.loc[term, "F"] == pytest.approx(table.loc[key, "F Value"], rel=1e-8)
        assert ours.loc[term, "df1"] == table.loc[key, "Num DF"]
        assert ours.loc[term, "df2"] == table.loc[key, "Den DF"]
        assert ours.loc[term, "p"] == pytest.approx(table.loc[key, "Pr > F"], rel=1e-6)


def test_rm_anova_averages_repeats_and_drops_incomplete_participants(sleep):
    # Duplicating every observation changes nothing (cells are averaged); removing one
    # participant's second condition drops that participant, and the note says so.
    doubled = pd.concat([sleep, sleep], ignore_index=True)
    once = rm_anova(sleep, "extra", "group", "ID").iloc[0]
    twice = rm_anova(doubled, "extra", "group", "ID").iloc[0]
    assert twice["F"] == pytest.approx(once["F"])
    incomplete = sleep[~((sleep["ID"] == 1) & (sleep["group"] == "2"))]
    row = rm_anova(incomplete, "extra", "group", "ID").iloc[0]
    assert row["n"] == 9 and row["df2"] == 8
    assert "1 participant(s) with missing conditions dropped" in row["note"]


def test_rm_anova_degenerate(sleep):
    one = sleep[sleep["ID"] == 1]
    assert "at least 2 participants" in rm_anova(one, "extra", "group", "ID").iloc[0]["note"]
    flat = sleep.assign(extra=2.0)
    assert "zero variance" in rm_anova(flat, "extra", "group", "ID").iloc[0]["note"]
    # Equal to rounding: pingouin's F from such values is a ratio of rounding errors.
    rounding = sleep.assign(extra=0.267529 + 1e-15 * np.arange(len(sleep)))
    assert "zero variance" in rm_anova(rounding, "extra", "group", "ID").iloc[0]["note"]
    single = sleep[sleep["group"] == "1"]
    assert "at least 2 levels" in rm_anova(single, "extra", "group", "ID").iloc[0]["note"]


def test_rm_anova_without_error_variance_reports_no_f(sleep):
    # Each participant's second value is the first plus the same 1.5: the error term
    # (participant x condition) is 0 and F = 1.5^2 n / 0 is undefined, not a number from
    # rounding (pingouin gives about -7e17 here).
    first = sleep[sleep["group"] == "1"]
    additive = pd.concat([first, first.assign(group="2", extra=first["extra"] + 1.5)])
    row = rm_anova(additive, "extra", "group", "ID").iloc[0]
    assert np.isnan(row["F"]) and np.isnan(row["p"])
    assert "no error variance" in row["note"]


def test_rm_anova_accepts_a_dv_named_like_a_condition():
    data = pd.DataFrame(
        {
            "s": ["a", "b", "c"] * 3,
            "c": ["x"] * 3 + ["y"] * 3 + ["z"] * 3,
            "y": [1.0, 2.0, 1.5, 2.0, 2.5, 3.5, 4.0, 3.0, 5.0],
        }
    )
    assert rm_anova(data, "y", "c", "s").iloc[0]["F"] > 0


# ------------------------------------------------------------------------ mixed model


def test_mixedlm_matches_lme4_on_sleep(sleep):
    # lme4: lmer(extra ~ group + (1 | ID), sleep): group2 t value 4.062, the paired t; the
    # Wald chi-square with 1 df is its square.
    row = mixedlm(sleep, "extra", "group", "ID").iloc[0]
    assert row["df1"] == 1 and row["n"] == 20 and row["n_groups"] == 10
    assert row["chi2"] == pytest.approx(4.0621**2, rel=5e-4)
    assert row["p"] == pytest.approx(stats.chi2.sf(row["chi2"], 1))


def test_mixedlm_equals_rm_anova_on_balanced_data(two_way):
    # With a random intercept, REML and complete balanced data, the Wald chi-square of an
    # additive model divided by its df equals the repeated-measures F of that additive model
    # (compound symmetry); the additive model is the additive two-way ANOVA with subject
    # blocks, which statsmodels OLS gives directly.
    import statsmodels.formula.api as smf
    from statsmodels.stats.anova import anova_lm

    data = two_way.rename(columns={"Performance": "y"})
    ols = smf.ols("y ~ C(Subject) + C(Time) + C(Metric)", data).fit()
    f_metric = anova_lm(ols, typ=2).loc["C(Metric)", "F"]
    row = mixedlm(two_way, "Performance", ["Time", "Metric"], "Subject").set_index("term")
    assert row.loc["Metric", "df1"] == 2
    assert row.loc["Metric", "chi2"] / 2 == pytest.approx(f_metric, rel=1e-4)


def test_mixedlm_degenerate(sleep):
    one = sleep[sleep["ID"] == 1]
    assert "at least 2 participants" in mixedlm(one, "extra", "group", "ID").iloc[0]["note"]
    flat = sleep.assign(extra=0.0)
    assert "zero variance" in mixedlm(flat, "extra", "group", "ID").iloc[0]["note"]


# ------------------------------------------------------------------ Friedman, Wilcoxon


def test_friedman_matches_r_rounding_times():
    # R ?friedman.test: Friedman chi-squared = 11.143, df = 2, p-value = 0.003805.
    data = pd.read_csv(REF / "rounding_times.csv")
    row = friedman(data, "time", "method", "player").iloc[0]
    assert row["Q"] == pytest.approx(11.143, abs=5e-4)
    assert (row["df1"], row["n"]) == (2, 22)
    assert row["p"] == pytest.approx(0.003805, abs=5e-7)
    assert row["W"] == pytest.approx(row["Q"] / (22 * 2))  # Kendall's W, by definition


def test_wilcoxon_matches_r_depression_example():
    # R ?wilcox.test: paired, alternative "greater": V = 40, p-value = 0.01953 (exact).  Our
    # test is two-sided: the exact null distribution is symmetric, so p doubles.
    data = pd.read_csv(REF / "depression.csv")
    row = wilcoxon_holm(data, "hamilton", "visit", "patient", target="first").iloc[0]
    assert (row["A"], row["B"], row["V"], row["n"]) == ("first", "second", 40, 9)
    assert row["p_unc"] == pytest.approx(2 * 0.01953, abs=1e-5)
    assert row["p"] == row["p_unc"]  # a family of one
    # Rank-biserial correlation: (V - (T - V)) / T with T = n (n + 1) / 2 = 45.
    assert row["rbc"] == pytest.approx((40 - 5) / 45)


def test_wilcoxon_with_ties_uses_r_normal_approximation(sleep):
    # sleep has one zero difference and tied ranks, so R drops the zero and uses the normal
    # approximation with continuity and tie corrections.  Closed form on the 9 non-zero
    # differences: z = (|V - n(n+1)/4| - 0.5) / sqrt(n(n+1)(2n+1)/24 - sum(t^3 - t)/48).
    d = (
        sleep[sleep["group"] == "1"].set_index("ID")["extra"]
        - sleep[sleep["group"] == "2"].set_index("ID")["extra"]
    ).to_numpy()
    d = d[d != 0]
    n = len(d)
    ranks = stats.rankdata(np.abs(d))
    v = ranks[d > 0].sum()
    _, ties = np.unique(ranks, return_counts=True)
    sigma = np.sqrt(n * (n + 1) * (2 * n + 1) / 24 - np.sum(ties**3 - ties) / 48)
    z = (abs(v - n * (n + 1) / 4) - 0.5) / sigma
    row = wilcoxon_holm(sleep, "extra", "group", "ID", target="1").iloc[0]
    assert row["V"] == v == 0
    assert row["p_unc"] == pytest.approx(2 * stats.norm.sf(z), rel=1e-10)
    assert row["p_unc"] == pytest.approx(0.009091, abs=5e-7)  # R's printed value


def test_holm_closed_form():
    # Holm: sort, multiply the i-th smallest by (m - i + 1), running maximum, cap at 1.
    # p = (.01, .04, .03, .005): .005*4 = .02, .01*3 = .03, .03*2 = .06, max(.04*1, .06) = .06.
    assert holm([0.01, 0.04, 0.03, 0.005]) == pytest.approx([0.03, 0.06, 0.06, 0.02])
    assert holm([0.5, 0.9]) == pytest.approx([1.0, 1.0])
    out = holm([0.01, np.nan, 0.02])
    assert np.isnan(out[1]) and out[[0, 2]] == pytest.approx([0.02, 0.02])


def test_wilcoxon_holm_adjusts_over_the_family():
    data = pd.read_csv(REF / "rounding_times.csv")
    table = wilcoxon_holm(data, "time", "method", "player", target="Round Out")
    assert list(table["B"]) == ["Narrow Angle", "Wide Angle"]
    assert table["p"].to_numpy() == pytest.approx(holm(table["p_unc"].to_numpy()))


def test_rank_tests_degenerate():
    same = pd.DataFrame(
        {"s": ["a", "a", "a", "b", "b", "b"], "c": ["x", "y", "z"] * 2, "v": [4] * 6}
    )
    assert "same score" in friedman(same, "v", "c", "s").iloc[0]["note"]
    row = wilcoxon_holm(same, "v", "c", "s", target="x").iloc[0]
    assert "all paired differences are zero" in row["note"] and np.isnan(row["p"])
    two = same[same["c"] != "z"]
    assert "at least 3 conditions" in friedman(two, "v", "c", "s").iloc[0]["note"]
    missing = wilcoxon_holm(same, "v", "c", "s", target="x", others=["w"]).iloc[0]
    assert "no observations of c = 'w'" in missing["note"]
