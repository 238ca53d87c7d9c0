"""casa_core.stats.between against published R output (sources: tests/reference/stats)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pingouin
import pytest
from scipy import stats

from casa_core.stats import ancova, anova, non_inferiority, tukey_hsd

REF = Path(__file__).parents[1] / "reference" / "stats"


@pytest.fixture(scope="module")
def plants() -> pd.DataFrame:
    return pd.read_csv(REF / "plantgrowth.csv")


@pytest.fixture(scope="module")
def female_penguins() -> pd.DataFrame:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = pingouin.read_dataset("penguins")
    return data[data["sex"] == "female"].dropna(subset=["body_mass_g"])


# ----------------------------------------------------------------------------- ANOVA


def test_anova_matches_r_on_plantgrowth(plants):
    # R: summary(aov(weight ~ group, PlantGrowth)) -> F(2, 27) = 4.846, p = 0.01591
    # (wekaleamstudios.co.uk, "One-way ANOVA (cont.)", 2010).
    row = anova(plants, "weight", "group").iloc[0]
    assert (row["term"], row["df1"], row["df2"], row["n"]) == ("group", 2, 27, 30)
    assert row["F"] == pytest.approx(4.8461, abs=5e-5)
    assert row["p"] == pytest.approx(0.01591, abs=5e-6)
    # Partial eta squared = SS_group / (SS_group + SS_res) = 3.7663 / (3.7663 + 10.4921),
    # sums of squares from the same R table.
    assert row["np2"] == pytest.approx(3.7663 / (3.7663 + 10.4921), abs=1e-4)
    assert row["note"] == ""


def test_anova_unequal_groups_matches_r_on_female_penguins(female_penguins):
    # R: lm(body_mass_g ~ species, females): F-statistic 393.2 on 2 and 162 DF.
    row = anova(female_penguins, "body_mass_g", "species").iloc[0]
    assert (row["df1"], row["df2"]) == (2, 162)
    assert row["F"] == pytest.approx(393.2, abs=0.05)


# ---------------------------------------------------------------------------- ANCOVA


def test_ancova_matches_r_on_mtcars():
    # R: summary(aov(mpg ~ hp + am, mtcars)): am Df 1, Sum Sq 202.2, Pr(>F) 3.46e-05, residual
    # Df 29 ("R - Analysis of Covariance", tutorialspoint).  am enters last, so R's sequential
    # test of am is the type II test reported here.
    cars = pd.read_csv(REF / "mtcars_ancova.csv")
    cars["am"] = cars["am"].map({0: "automatic", 1: "manual"})
    table = ancova(cars, "mpg", between="am", covariate="hp").set_index("term")
    assert list(table.index) == ["am", "hp"]
    assert (table.loc["am", "df1"], table.loc["am", "df2"]) == (1, 29)
    assert table.loc["am", "p"] == pytest.approx(3.46e-05, rel=2e-3)
    # F = MS_am / MS_res; the R table gives Sum Sq 202.2 and residual Sum Sq over 29 Df.
    ms_res = 202.2 / table.loc["am", "F"]
    assert ms_res * 29 == pytest.approx(245.4, abs=0.1)


def test_ancova_categorical_covariate_is_a_factor():
    # A two-level text covariate has one degree of freedom, as a 0/1 numeric one would:
    # both codings span the same model, so F and p are identical.
    cars = pd.read_csv(REF / "mtcars_ancova.csv")
    cars["power"] = np.where(cars["hp"] > 120, "high", "low")
    cars["power01"] = (cars["power"] == "high").astype(float)
    cars["am"] = cars["am"].astype(str)
    text = ancova(cars, "mpg", "am", "power").set_index("term")
    numeric = ancova(cars, "mpg", "am", "power01").set_index("term")
    assert text.loc["power", "df1"] == 1
    assert text.loc["am", "F"] == pytest.approx(numeric.loc["am", "F"], rel=1e-10)
    assert text.loc["power", "p"] == pytest.approx(numeric.loc["power01", "p"], rel=1e-10)


def test_ancova_agrees_with_pingouin():
    # Independent implementation: pingouin.ancova (type II, validated against JASP by its
    # authors) on pingouin's own "ancova" dataset.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = pingouin.read_dataset("ancova")
        expected = pingouin.ancova(data=data, dv="Scores", covar="Income", between="Method")
    ours = ancova(data, "Scores", "Method", "Income").set_index("term")
    expected = expected.set_index("Source")
    for term in ("Method", "Income"):
        assert ours.loc[term, "F"] == pytest.approx(expected.loc[term, "F"], rel=1e-8)
        assert ours.loc[term, "p"] == pytest.approx(expected.loc[term, "p_unc"], rel=1e-6)


# ------------------------------------------------------------------------- Tukey HSD


def test_tukey_matches_r_on_plantgrowth(plants):
    # R: TukeyHSD(aov(weight ~ group, PlantGrowth)); R prints B - A ("trt1-ctrl"), we give
    # A - B, so differences and intervals change sign.
    table = tukey_hsd(plants, "weight", "group").set_index(["A", "B"])
    published = {  # (diff B - A, lwr, upr, p adj)
        ("ctrl", "trt1"): (-0.371, -1.0622161, 0.3202161, 0.3908711),
        ("ctrl", "trt2"): (0.494, -0.1972161, 1.1852161, 0.1979960),
        ("trt1", "trt2"): (0.865, 0.1737839, 1.5562161, 0.0120064),
    }
    for pair, (diff, lwr, upr, p) in published.items():
        row = table.loc[pair]
        assert row["diff"] == pytest.approx(-diff, abs=1e-9)
        assert row["ci_low"] == pytest.approx(-upr, abs=1e-6)
        assert row["ci_high"] == pytest.approx(-lwr, abs=1e-6)
        assert row["p"] == pytest.approx(p, abs=1e-6)


def test_tukey_kramer_matches_r_on_unequal_groups(female_penguins):
    # R: TukeyHSD(aov(body_mass_g ~ species, data = females)), 73 / 34 / 58 birds.
    table = tukey_hsd(female_penguins, "body_mass_g", "species").set_index(["A", "B"])
    published = {  # R's "B-A": diff, lwr, upr
        ("Adelie", "Chinstrap"): (158.3703, 22.32078, 294.4197),
        ("Adelie", "Gentoo"): (1310.9058, 1195.64908, 1426.1624),
        ("Chinstrap", "Gentoo"): (1152.5355, 1011.00620, 1294.0648),
    }
    for pair, (diff, lwr, upr) in published.items():
        row = table.loc[pair]
        assert row["diff"] == pytest.approx(-diff, abs=1e-4)
        assert row["ci_low"] == pytest.approx(-upr, abs=1e-3)
        assert row["ci_high"] == pytest.approx(-lwr, abs=1e-3)
    assert table.loc[("Adelie", "Chinstrap"), "p"] == pytest.approx(0.0179471, abs=1e-6)
    assert (
        table.loc[("Adelie", "Chinstrap"), "n_A"],
        table.loc[("Adelie", "Chinstrap"), "n_B"],
    ) == (
        73,
        34,
    )
    assert (table["p"] < 1e-7).sum() == 2  # R prints 0.0000000 for the Gentoo pairs


# ------------------------------------------------------------------ non-inferiority


def test_noninferiority_bound_is_its_formula(sleep):
    # The paper's bound (see docs/paper-to-code.md): d + t(0.95, df) SE, with the pooled
    # two-sample SE and df = n1 + n2 - 2.
    a = sleep.loc[sleep["group"] == "1", "extra"].to_numpy()
    b = sleep.loc[sleep["group"] == "2", "extra"].to_numpy()
    pooled = ((len(a) - 1) * a.var(ddof=1) + (len(b) - 1) * b.var(ddof=1)) / (len(a) + len(b) - 2)
    se = np.sqrt(pooled * (1 / len(a) + 1 / len(b)))
    d = a.mean() - b.mean()
    row = non_inferiority(sleep, "extra", "group", new="1", reference="2").iloc[0]
    assert row["estimate"] == pytest.approx(d)
    assert row["df"] == 18
    assert row["se"] == pytest.approx(se)
    assert row["bound"] == pytest.approx(d + stats.t.ppf(0.95, 18) * se)
    assert np.isnan(row["p"]) and pd.isna(row["noninferior"])


def test_noninferiority_bound_from_r_two_sided_interval(sleep):
    # R: t.test(extra ~ group, sleep, var.equal = TRUE): 95 % CI [-3.363874, 0.203874] around
    # d = -1.58.  SE = half-width / t(0.975, 18); the one-sided 95 % bound is d + t(0.95, 18) SE.
    se = (0.203874 + 3.363874) / 2 / stats.t.ppf(0.975, 18)
    row = non_inferiority(sleep, "extra", "group", new="1", reference="2").iloc[0]
    assert row["estimate"] == pytest.approx(-1.58, abs=1e-12)
    assert row["bound"] == pytest.approx(-1.58 + stats.t.ppf(0.95, 18) * se, abs=1e-5)


def test_noninferiority_welch_matches_r(sleep):
    # R: t.test(extra ~ group, data = sleep) (Welch, R's default): t = -1.8608,
    # df = 17.776, 95 % CI [-3.3654832, 0.2054832] (R ?t.test on sleep). SE from the
    # interval's half-width; the one-sided 95 % bound is d + t(0.95, df) SE.
    row = non_inferiority(sleep, "extra", "group", "1", "2", welch=True).iloc[0]
    assert row["df"] == pytest.approx(17.776, abs=5e-4)
    se = (0.2054832 + 3.3654832) / 2 / stats.t.ppf(0.975, row["df"])
    assert row["se"] == pytest.approx(se, abs=1e-6)
    assert row["estimate"] / row["se"] == pytest.approx(-1.8608, abs=5e-5)
    assert row["bound"] == pytest.approx(-1.58 + stats.t.ppf(0.95, row["df"]) * se, abs=1e-6)
    with pytest.raises(ValueError, match="welch applies to independent samples"):
        non_inferiority(sleep, "extra", "group", "1", "2", subject="ID", welch=True)


def test_noninferiority_welch_against_a_constant_is_a_one_sample_test(sleep):
    # A reference identically 1 (relative effort under NA): Welch's t reduces to the
    # one-sample t of the new group against 1, df = n_new - 1; the pooled test claims
    # n_new + n_reference - 2.
    new = sleep[sleep["group"] == "1"]
    data = pd.concat([new, new.assign(group="2", extra=1.0)])
    welch = non_inferiority(data, "extra", "group", "1", "2", welch=True, margin=2.0).iloc[0]
    pooled = non_inferiority(data, "extra", "group", "1", "2", margin=2.0).iloc[0]
    one = stats.ttest_1samp(new["extra"] - 1.0 - 2.0, 0.0, alternative="less")
    assert (welch["df"], pooled["df"]) == (9, 18)
    assert welch["p"] == pytest.approx(one.pvalue, rel=1e-10)
    assert "one-sample" in welch["note"]


def test_noninferiority_paired_matches_r(sleep):
    # R: t.test(extra[group == 1], extra[group == 2], paired = TRUE): t = -4.0621, df = 9,
    # 95 % CI [-2.4598858, -0.7001142] (R ?sleep); one-sided bound from the same SE.
    se = (2.4598858 - 0.7001142) / 2 / stats.t.ppf(0.975, 9)
    row = non_inferiority(sleep, "extra", "group", "1", "2", subject="ID").iloc[0]
    assert row["df"] == 9 and row["n_new"] == 10
    assert row["se"] == pytest.approx(se, abs=1e-6)
    assert row["bound"] == pytest.approx(-1.58 + stats.t.ppf(0.95, 9) * se, abs=1e-6)


def test_noninferiority_test_at_the_bound_has_p_alpha(sleep):
    # Group 2 against group 1 (d = +1.58, a positive bound).  The bound is the smallest
    # margin at which the one-sided test rejects: at margin = bound the test statistic is
    # exactly -t(0.95, df), so p = alpha.
    bound = non_inferiority(sleep, "extra", "group", "2", "1").iloc[0]["bound"]
    at = non_inferiority(sleep, "extra", "group", "2", "1", margin=bound).iloc[0]
    assert at["p"] == pytest.approx(0.05, abs=1e-9)
    wider = non_inferiority(sleep, "extra", "group", "2", "1", margin=bound + 0.01).iloc[0]
    narrower = non_inferiority(sleep, "extra", "group", "2", "1", margin=bound - 0.01).iloc[0]
    assert bool(wider["noninferior"]) and not bool(narrower["noninferior"])
    assert wider["p"] < 0.05 < narrower["p"]
    # p is the Student t cdf of (d - margin) / SE.
    t = (wider["estimate"] - wider["margin"]) / wider["se"]
    assert wider["t"] == pytest.approx(t) and wider["p"] == pytest.approx(stats.t.cdf(t, 18))


def test_noninferiority_higher_is_better_mirrors_lower(sleep):
    # Negating the data and the direction gives the mirrored bound and the same verdict.
    flipped = sleep.assign(extra=-sleep["extra"])
    low = non_inferiority(sleep, "extra", "group", "1", "2", margin=0.9).iloc[0]
    high = non_inferiority(
        flipped, "extra", "group", "1", "2", lower_is_better=False, margin=0.9
    ).iloc[0]
    assert high["bound"] == pytest.approx(-low["bound"])
    assert high["p"] == pytest.approx(low["p"])
    assert bool(high["noninferior"]) == bool(low["noninferior"])


def test_noninferiority_rejects_bad_arguments(sleep):
    with pytest.raises(ValueError, match="margin must be a positive number"):
        non_inferiority(sleep, "extra", "group", "1", "2", margin=-1.0)
    with pytest.raises(ValueError, match="alpha must be in"):
        non_inferiority(sleep, "extra", "group", "1", "2", alpha=1.5)


# ------------------------------------------------------------- degenerate and bad input


def test_degenerate_inputs_give_notes_not_crashes(plants):
    one_group = plants[plants["group"] == "ctrl"]
    assert "at least 2 levels" in anova(one_group, "weight", "group").iloc[0]["note"]
    assert "at least 2 levels" in tukey_hsd(one_group, "weight", "group").iloc[0]["note"]
    constant = plants.assign(weight=1.0)
    assert "zero variance" in anova(constant, "weight", "group").iloc[0]["note"]
    # Equal to rounding (15 digits): statsmodels would report an F from rounding errors.
    rounding = plants.assign(weight=0.267529 + 1e-15 * np.arange(len(plants)))
    assert "zero variance" in anova(rounding, "weight", "group").iloc[0]["note"]
    assert np.isnan(anova(constant, "weight", "group").iloc[0]["F"])
    flat_groups = plants.assign(weight=plants["group"].map({"ctrl": 1.0, "trt1": 2.0, "trt2": 3.0}))
    assert "zero residual variance" in anova(flat_groups, "weight", "group").iloc[0]["note"]
    assert "zero within-group" in tukey_hsd(flat_groups, "weight", "group").iloc[0]["note"]
    missing = non_inferiority(plants, "weight", "group", "trt1", "absent").iloc[0]
    assert "no observations of group = 'absent'" in missing["note"]
    tiny = plants.groupby("group").head(1)
    assert "no residual degrees of freedom" in anova(tiny, "weight", "group").iloc[0]["note"]
    empty = plants.iloc[:0]
    assert anova(empty, "weight", "group").iloc[0]["note"]


def test_bad_input_names_column_and_row(plants):
    with pytest.raises(ValueError, match=r"missing column\(s\) 'mass'"):
        anova(plants, "mass", "group")
    broken = plants.astype({"weight": object})
    broken.loc[3, "weight"] = "heavy"
    with pytest.raises(ValueError, match=r"column 'weight', row 3: 'heavy' is not a number"):
        tukey_hsd(broken, "weight", "group")
