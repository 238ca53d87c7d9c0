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

REF = Path(__file__).parents[1] / "reference" / "stats"


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


def _long(wide: pd.DataFrame) -> pd.DataFrame:
    frame = wide.dropna().rename_axis("subject").reset_index()
    return frame.melt("subject", var_name="condition", value_name="y")


def test_rm_anova_sphericity_matches_pingouin_docs():
    # pingouin.rm_anova's documentation (pingouin-stats.org/build/html/generated/
    # pingouin.rm_anova.html, example 1) on its bundled "rm_anova_wide" dataset, listwise
    # complete: ddof1 3, ddof2 24, F 5.200652, p_unc 0.006557, ng2 0.346392, eps 0.694329
    # (printed to 6 decimals: tolerance half a unit of the last digit).
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        wide = pingouin.read_dataset("rm_anova_wide")
    row = rm_anova(_long(wide), "y", "condition", "subject").iloc[0]
    assert (row["df1"], row["df2"], row["n"]) == (3, 24, 9)
    assert row["F"] == pytest.approx(5.200652, abs=5e-7)
    assert row["p"] == pytest.approx(0.006557, abs=5e-7)
    assert row["ng2"] == pytest.approx(0.346392, abs=5e-7)
    assert row["eps"] == pytest.approx(0.694329, abs=5e-7)
    # Greenhouse-Geisser, closed form: the same F on (eps df1, eps df2) degrees of freedom.
    gg = stats.f.sf(5.200652, 3 * 0.694329, 24 * 0.694329)
    assert row["p_gg"] == pytest.approx(gg, rel=1e-5)
    # Mauchly, closed form as R's mauchly.test: S the covariance of the k - 1 orthonormal
    # contrasts, W = det S / (tr S / p)^p, chi2 = -(n - 1) f ln W with
    # f = 1 - (2p^2 + p + 2) / (6p (n - 1)) on q = p (p + 1) / 2 - 1 degrees of freedom, and
    # the second-order term w2 (Anderson 2003, Sec. 10.7.4; R uses k in it):
    # p = P(chi2_q > x) + w2 (P(chi2_{q+4} > x) - P(chi2_q > x)).
    y = wide.dropna().to_numpy()
    n, k = y.shape
    contrasts = np.linalg.qr(np.column_stack([np.ones(k), np.eye(k)[:, : k - 1]]))[0][:, 1:]
    cov = np.cov(y @ contrasts, rowvar=False)
    dim, nu = k - 1, n - 1
    w = np.linalg.det(cov) / (np.trace(cov) / dim) ** dim
    f = 1 - (2 * dim**2 + dim + 2) / (6 * dim * nu)
    chi2, q = -nu * f * np.log(w), dim * (dim + 1) / 2 - 1
    w2 = (dim + 2) * (dim - 1) * (dim - 2) * (2 * dim**3 + 6 * dim**2 + 3 * k + 2)
    w2 /= 288 * (nu * dim * f) ** 2
    p = stats.chi2.sf(chi2, q) + w2 * (stats.chi2.sf(chi2, q + 4) - stats.chi2.sf(chi2, q))
    assert row["W_spher"] == pytest.approx(w, rel=1e-9)
    assert row["p_spher"] == pytest.approx(p, rel=1e-9)
    # Greenhouse-Geisser epsilon from the same S: tr(S)^2 / (p tr(S^2)).
    assert row["eps"] == pytest.approx(np.trace(cov) ** 2 / (dim * np.trace(cov @ cov)), rel=1e-9)


def test_mauchly_matches_pingouin_sphericity_docs():
    # pingouin.sphericity's documentation (pingouin-stats.org/build/html/generated/
    # pingouin.sphericity.html, first example): W = 0.21, chi2 = 4.677, dof 2, p = 0.096
    # (printed to 3 decimals).
    wide = pd.DataFrame(
        {
            "A": [2.2, 3.1, 4.3, 4.1, 7.2],
            "B": [1.1, 2.5, 4.1, 5.2, 6.4],
            "C": [8.2, 4.5, 3.4, 6.2, 7.2],
        }
    )
    row = rm_anova(_long(wide), "y", "condition", "subject").iloc[0]
    assert row["W_spher"] == pytest.approx(0.21, abs=5e-3)
    assert row["p_spher"] == pytest.approx(0.096, abs=5e-4)


def test_rm_anova_two_way_sphericity_matches_pingouin_docs(two_way):
    # pingouin.sphericity's documentation on "rm_anova2": Metric p = 0.878; the Time x
    # Metric interaction chi2 = 3.763, dof 2, p = 0.152; Time (2 levels) holds trivially.
    ours = rm_anova(two_way, "Performance", ["Time", "Metric"], "Subject").set_index("term")
    assert ours.loc["Metric", "p_spher"] == pytest.approx(0.878, abs=5e-4)
    assert ours.loc["Time * Metric", "p_spher"] == pytest.approx(0.152, abs=5e-4)
    assert (ours.loc["Time", "W_spher"], ours.loc["Time", "p_spher"]) == (1.0, 1.0)
    assert ours.loc["Time", "eps"] == 1.0


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


def test_mixedlm_closed_forms_on_sleep(sleep):
    # Balanced, two conditions, a random intercept away from the boundary: the
    # Kenward-Roger F is the paired t squared on n - 1 = 9 degrees of freedom, and the ML
    # likelihood factors into the participants' means (which the condition does not
    # change) and their 10 paired differences d ~ N(delta, 2 sigma^2), so the likelihood
    # ratio is n ln(sum d^2 / sum (d - mean d)^2) = n ln(1 + t^2 / (n - 1)), with R's
    # paired t = 4.0621 (R ?sleep; printed to 5 digits: rel 5e-5, 1e-4 for its square).
    row = mixedlm(sleep, "extra", "group", "ID").iloc[0]
    assert row["n"] == 20 and row["n_groups"] == 10
    assert (row["df1"], row["df2"]) == (1, pytest.approx(9, rel=1e-6))
    assert row["F"] == pytest.approx(4.0621**2, rel=1e-4)
    assert row["p"] == pytest.approx(0.002833, rel=1e-3)  # R's paired t-test
    assert row["lrt_df"] == 1
    assert row["chi2"] == pytest.approx(10 * np.log(1 + 4.0621**2 / 9), rel=5e-5)
    assert row["p_lrt"] == pytest.approx(stats.chi2.sf(row["chi2"], 1))
    assert "Kenward-Roger" in row["note"] and "boundary" not in row["note"]


def test_mixedlm_is_the_rm_anova_on_a_balanced_design(two_way):
    # Balanced 2 x 3 fully within design, every variance component positive: with random
    # intercepts per subject, subject x Time and subject x Metric the model has the
    # error strata of the repeated-measures ANOVA, and the Kenward-Roger F of each term
    # is the uncorrected repeated-measures F on its stratum's degrees of freedom
    # (pingouin, an independent implementation).
    ours = mixedlm(two_way, "Performance", ["Time", "Metric"], "Subject").set_index("term")
    assert list(ours.index) == ["Time", "Metric", "Time x Metric"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        anova = pingouin.rm_anova(
            two_way, dv="Performance", within=["Time", "Metric"], subject="Subject"
        )
    for term, line in zip(ours.index, anova.itertuples(), strict=True):
        assert ours.loc[term, "F"] == pytest.approx(line.F, rel=1e-5), term
        assert ours.loc[term, "df1"] == line.ddof1
        assert ours.loc[term, "df2"] == pytest.approx(line.ddof2, rel=1e-6), term
    assert "boundary" not in ours["note"].iloc[0]
    additive_only = mixedlm(
        two_way, "Performance", ["Time", "Metric"], "Subject", interaction=False
    )
    assert list(additive_only["term"]) == ["Time", "Metric"]


def test_mixedlm_flags_a_boundary_fit():
    # Every participant's mean is the same (their residuals are permutations of one set),
    # so the ML random-intercept variance is 0: the note says so, whatever the scale.
    residuals = [[-0.3, 0.0, 0.3], [0.3, -0.3, 0.0], [0.0, 0.3, -0.3]] * 2
    rows = [
        {"s": f"s{i}", "c": c, "y": scale * (j + r)}
        for scale in (1.0,)
        for i, rs in enumerate(residuals)
        for j, (c, r) in enumerate(zip("abc", rs, strict=True))
    ]
    data = pd.DataFrame(rows)
    for scale in (1.0, 1e4):
        row = mixedlm(data.assign(y=data["y"] * scale), "y", "c", "s").iloc[0]
        assert "boundary fit" in row["note"], scale


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
    # A skipped comparison (NaN) counts in the family, as R's p.adjust with its default
    # n = length(p) (R ?p.adjust): p.adjust(c(0.01, NA, 0.02), "holm") = 0.03, NA, 0.04.
    out = holm([0.01, np.nan, 0.02])
    assert np.isnan(out[1]) and out[[0, 2]] == pytest.approx([0.03, 0.04])
    # Ties keep R's order: both .02 get 2 x .02 after the smallest (.01 x 3 = .03).
    assert holm([0.02, 0.01, 0.02]) == pytest.approx([0.04, 0.03, 0.04])


def test_wilcoxon_holm_counts_skipped_comparisons():
    # Three comparisons, one impossible (no observations of "absent"): the two tested are
    # adjusted over m = 3, not 2.
    data = pd.read_csv(REF / "rounding_times.csv")
    others = ["Narrow Angle", "absent", "Wide Angle"]
    table = wilcoxon_holm(data, "time", "method", "player", target="Round Out", others=others)
    assert np.isnan(table.loc[1, "p"]) and "no observations" in table.loc[1, "note"]
    raw = table["p_unc"].to_numpy()
    assert table["p"].to_numpy() == pytest.approx(holm(raw), nan_ok=True)
    tested = raw[[0, 2]]
    smallest, largest = np.argmin(tested), np.argmax(tested)
    assert table["p"].to_numpy()[[0, 2]][smallest] == pytest.approx(min(1, 3 * tested.min()))
    assert table["p"].to_numpy()[[0, 2]][largest] == pytest.approx(
        min(1, max(3 * tested.min(), 2 * tested.max()))
    )


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
