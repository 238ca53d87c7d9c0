"""The pooled mixed model (Kenward-Roger F, likelihood ratio), the ratio margins and the
non-inferiority level against R (tests/reference/stats/mixed_within.R and README.md)."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pingouin
import pytest

from casa_core.stats import analyze_study, mixedlm, non_inferiority
from casa_core.stats.margins import Margins
from casa_core.stats.noninferiority import ratio_non_inferiority
from casa_core.stats.power import replicate_detections
from tests.stats.conftest import REF

TERMS = {"method": "method", "task": "task", "method x task": "method:task"}


@pytest.fixture(scope="module")
def data() -> pd.DataFrame:
    return pd.read_csv(REF / "mixed_within.csv")


@pytest.fixture(scope="module")
def r() -> pd.DataFrame:
    return pd.read_csv(REF / "mixed_within_r.csv").set_index(["case", "test", "term"])


@pytest.mark.parametrize("case", ["balanced", "unbalanced"])
def test_kenward_roger_and_likelihood_ratio_match_lme4(data, r, case):
    # R: lmerTest anova(type = 3, ddf = "Kenward-Roger") (pbkrtest's KR, contr.sum) and
    # anova() of ML fits; our REML and ML optima agree with lme4's to its tolerance.
    frame = data if case == "balanced" else data[data["dropped"] == 0]
    ours = mixedlm(frame, "y", ["method", "task"], "participant").set_index("term")
    for term, name in TERMS.items():
        kr, lrt = r.loc[(case, "Kenward-Roger", name)], r.loc[(case, "LRT", name)]
        assert ours.loc[term, "F"] == pytest.approx(kr["statistic"], rel=2e-5), term
        assert ours.loc[term, "df1"] == kr["df1"]
        assert ours.loc[term, "df2"] == pytest.approx(kr["df2"], rel=1e-5), term
        assert ours.loc[term, "p"] == pytest.approx(kr["p"], rel=1e-4), term
        assert ours.loc[term, "chi2"] == pytest.approx(lrt["statistic"], rel=1e-5), term
        assert ours.loc[term, "lrt_df"] == lrt["df1"]
        assert ours.loc[term, "p_lrt"] == pytest.approx(lrt["p"], rel=1e-4), term
    # pbkrtest's KRmodcomp of the nested models gives the interaction's test too.
    modcomp = r.loc[(case, "KRmodcomp", "method:task")]
    assert ours.loc["method x task", "df2"] == pytest.approx(modcomp["df2"], rel=1e-5)


def test_kenward_roger_is_the_rm_anova_f_on_the_balanced_design(data):
    # The closed form: balanced, every component positive, so each term's KR F is the
    # uncorrected repeated-measures F on its stratum (pingouin, independent of R).
    ours = mixedlm(data, "y", ["method", "task"], "participant")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        anova = pingouin.rm_anova(data, dv="y", within=["method", "task"], subject="participant")
    assert ours["F"].to_numpy() == pytest.approx(anova["F"].to_numpy(), rel=1e-5)
    assert ours["df2"].to_numpy() == pytest.approx(anova["ddof2"].to_numpy(), rel=1e-6)


def test_kenward_roger_one_factor_unbalanced(data, r):
    frame = data[(data["task"] == "t1") & (data["dropped"] == 0)]
    row = mixedlm(frame, "y", "method", "participant").iloc[0]
    kr = r.loc[("one factor", "Kenward-Roger", "method")]
    assert row["F"] == pytest.approx(kr["statistic"], rel=2e-5)
    assert row["df2"] == pytest.approx(kr["df2"], rel=1e-5)
    assert row["p"] == pytest.approx(kr["p"], rel=1e-4)


@pytest.mark.parametrize("form", ["paired", "welch"])
def test_ratio_margin_matches_r(data, r, form):
    # R: t.test(new - 1.05 ref) (paired) and t.test(new, 1.05 ref) (Welch), the Fieller
    # bound by uniroot on their p; new = method c, reference = method a, task t1.
    frame = data[data["task"] == "t1"]
    subject = "participant" if form == "paired" else None
    row = ratio_non_inferiority(frame, "y", "method", "c", "a", fraction=0.05, subject=subject)
    row = row.iloc[0]
    case = f"ratio {form}"
    assert row["t"] == pytest.approx(r.loc[(case, "t", "ratio"), "statistic"], rel=1e-9)
    assert row["df"] == pytest.approx(r.loc[(case, "t", "ratio"), "df1"], rel=1e-9)
    assert row["p"] == pytest.approx(r.loc[(case, "t", "ratio"), "p"], rel=1e-8)
    bound = r.loc[(case, "Fieller bound", "ratio"), "statistic"]
    assert row["bound"] == pytest.approx(bound, rel=1e-9)
    assert row["estimate"] == pytest.approx(r.loc[(case, "estimate", "ratio"), "statistic"])
    assert row["margin"] == 1.05 and bool(row["noninferior"])


def test_ratio_bound_is_unbounded_when_the_reference_mean_is_not_above_zero():
    frame = pd.DataFrame(
        {
            "m": ["new"] * 4 + ["ref"] * 4,
            "s": list("abcd") * 2,
            "y": [1.0, 1.2, 0.9, 1.1, 0.1, -0.3, 0.5, 0.05],
        }
    )
    row = ratio_non_inferiority(frame, "y", "m", "new", "ref", fraction=0.1).iloc[0]
    assert row["bound"] == np.inf and "unbounded" in row["note"]


def test_level_0025_is_the_two_sided_95_interval_of_r(sleep):
    # R ?sleep: paired t.test 95 % CI [-2.4598858, -0.7001142]: its upper end is the
    # one-sided 97.5 % bound of mean(1) - mean(2), the bound at level 0.025; 0.05 is
    # the paper's (its one-sided 95 % bound).
    row = non_inferiority(sleep, "extra", "group", "1", "2", alpha=0.025, subject="ID")
    assert row.iloc[0]["bound"] == pytest.approx(-0.7001142, rel=1e-6)
    trials = sleep.assign(
        participant=sleep["ID"].astype(str),
        method=sleep["group"].map({"1": "CASA", "2": "PBA"}),
        task="known_goal",
        phase="no_misspecification",
        error=sleep["extra"],
    )
    na = trials[trials["method"] == "CASA"].assign(method="NA", error=lambda t: t["error"] + 3)
    trials = pd.concat([trials, na], ignore_index=True)
    table = analyze_study(trials, margins=Margins(alpha=0.025), metrics=["error"])
    rows = table[(table["analysis"] == "noninferiority") & (table["hypothesis"] == "H1")]
    paired = rows[rows["note"].str.contains("paired")].iloc[0]
    assert paired["ci_high"] == pytest.approx(-0.7001142, rel=1e-6)
    assert all("one-sided level 0.025" in note for note in rows["note"])


def test_the_level_comes_from_the_config_and_reaches_power():
    margins = Margins.from_config({"noninferiority_alpha": 0.025})
    assert margins.alpha == 0.025
    assert "--noninferiority-alpha 0.025" in margins.options()
    assert Margins.from_config({}).alpha == 0.05  # the paper's
    with pytest.raises(ValueError, match="noninferiority_alpha"):
        Margins(alpha=0.7)
    rows = [
        dict(
            participant=f"p{i}",
            task="known_goal",
            method=m,
            phase="no_misspecification",
            error=v + 0.1 * i + 0.05 * ((i * k) % 3),
            efficiency=v,
            relative_effort=v,
        )
        for i in range(1, 5)
        for k, (m, v) in enumerate({"NA": 3.0, "PBA": 2.0, "CASA": 1.0}.items())
    ]
    detections = replicate_detections(
        pd.DataFrame(rows), sizes=[4], variant="default", replicate=1, margins=margins
    )
    assert set(detections["noninferiority_alpha"]) == {0.025}


def test_an_unbounded_ratio_bound_is_nan_in_stats_csv_and_its_note_says_why():
    # Two participants: on Unknown Goal the Welch ratio test's reference mean is not
    # significantly above 0, so Fieller's bound is unbounded; stats.csv holds finite
    # numbers or NaN only (its readers refuse infinities).
    from tests.stats.test_stats_study import make_trials

    table = analyze_study(make_trials(n_participants=2, seed=0), None,
                          margins=Margins(fractions={"error": 0.05}))  # fmt: skip
    ratio = table[table["analysis"] == "noninferiority_ratio"]
    unbounded = ratio[ratio["note"].str.contains("unbounded")]
    assert len(unbounded) >= 1 and unbounded["ci_high"].isna().all()
    assert (~unbounded["noninferior"].astype(bool)).all()
    assert not np.isinf(table.select_dtypes("number").to_numpy(dtype=float)).any()
