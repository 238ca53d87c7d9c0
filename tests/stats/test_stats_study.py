"""The study analysis (H1-H4), its APA report and the ``casa stats`` command."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from casa_core import cli
from casa_core.stats import STATS_COLUMNS, analyze_study, anova, apa, report_markdown
from casa_core.stats.margins import Margins
from casa_core.stats.study import CONDITION_ORDER
from casa_core.vocabulary import condition_of

ANALYSES = {
    "anova",
    "ancova",
    "tukey",
    "noninferiority",
    "noninferiority_ratio",
    "rm_anova",
    "mixedlm",
    "mixedlm_lrt",
    "friedman",
    "wilcoxon",
}
METRICS = ["error", "efficiency", "relative_effort", "effort"]

# ------------------------------------------------------- synthetic study tables (seeded)

# (task, method, phase) of every analysed trial of one participant, as in the paper's protocol.
PROTOCOL = [
    ("known_goal", "NA", "no_misspecification"),
    ("known_goal", "PBA", "no_misspecification"),
    ("known_goal", "CASA", "no_misspecification"),
    *[
        (task, method, phase)
        for task in ("unknown_goal", "unknown_skill")
        for method, phase in (
            ("NA", "before_learning"),
            ("PBA", "before_learning"),
            ("CASA", "before_learning"),
            ("CASA", "after_learning"),
        )
    ],
]
QUESTIONS = ["understood", "effortless", "useful"]


def make_trials(n_participants: int = 11, seed: int = 0) -> pd.DataFrame:
    """A trials table with participant offsets and method effects (plus one familiarization)."""
    rng = np.random.default_rng(seed)
    rows = []
    for i in range(n_participants):
        offset = rng.normal(0.0, 0.5)  # participant skill: what the within design removes
        rows.append(_trial(f"P{i:02d}", "familiarization", "NA", "familiarization", 5.0, rng))
        for task, method, phase in PROTOCOL:
            effect = {"NA": 1.0, "PBA": 0.6, "CASA": 0.5}[method]
            if task != "known_goal" and method == "PBA":
                effect = 1.6  # confidently wrong assistance
            if phase == "after_learning":
                effect = 0.4
            rows.append(_trial(f"P{i:02d}", task, method, phase, 2.0 + effect + offset, rng))
    return pd.DataFrame(rows)


def _trial(participant, task, method, phase, level, rng) -> dict:
    error = level + rng.normal(0.0, 0.3)
    return {
        "dataset": "synthetic",
        "participant": participant,
        "task": task,
        "method": method,
        "phase": phase,
        "source": "simulated",
        "error": error,
        "efficiency": 0.5 * level + rng.normal(0.0, 0.2),
        "effort": float(round(100 * level + rng.normal(0.0, 10.0))),
        "effort_ticks": float(round(100 * level)),
        "relative_effort": level / 3.0 + rng.normal(0.0, 0.05),
        "duration": 15.0,
    }


def make_likert(n_participants: int = 11, seed: int = 1) -> pd.DataFrame:
    """A Likert table, scores 1-7, CASA after learning rated highest on misspecified tasks."""
    rng = np.random.default_rng(seed)
    rows = []
    for i in range(n_participants):
        for task, method, phase in PROTOCOL:
            base = {"NA": 2, "PBA": 4, "CASA": 5}[method]
            if task != "known_goal":
                base = 6 if phase == "after_learning" else (2 if method == "PBA" else 3)
            for question in QUESTIONS:
                score = int(np.clip(base + rng.integers(-1, 2), 1, 7))
                rows.append(
                    {
                        "dataset": "synthetic",
                        "participant": f"P{i:02d}",
                        "task": task,
                        "method": method,
                        "phase": phase,
                        "source": "simulated",
                        "question": question,
                        "score": score,
                    }
                )
    return pd.DataFrame(rows)


@pytest.fixture(scope="module")
def trials() -> pd.DataFrame:
    return make_trials(n_participants=11, seed=0)


@pytest.fixture(scope="module")
def likert() -> pd.DataFrame:
    return make_likert(n_participants=11, seed=1)


@pytest.fixture(scope="module")
def table(trials, likert) -> pd.DataFrame:
    # An absolute margin and a fraction of the reference mean: both non-inferiority forms.
    margins = Margins(absolute={"error": 1.0}, fractions={"relative_effort": 0.1})
    return analyze_study(trials, likert, margins=margins)


def _rows(table, **where) -> pd.DataFrame:
    mask = np.ones(len(table), dtype=bool)
    for column, value in where.items():
        mask &= (table[column] == value).to_numpy()
    return table[mask]


def test_table_has_the_contract_columns_and_analyses(table):
    assert list(table.columns) == STATS_COLUMNS
    assert set(table["analysis"]) == ANALYSES
    assert set(table["hypothesis"]) == {"H1", "H2", "H3", "H4"}
    assert table["note"].map(lambda note: isinstance(note, str)).all()


def test_paper_degrees_of_freedom_with_11_participants(table):
    # The paper's degrees of freedom (see docs/paper-to-code.md): 3 methods x 11 = 33
    # observations, df (2, 33 - 3); 66 observations with a one-df task covariate,
    # df (2, 66 - 3 - 1); 44 observations, df (1, 44 - 2 - 1).
    for metric in METRICS:
        h1 = _rows(table, hypothesis="H1", analysis="anova", metric=metric).iloc[0]
        h2 = _rows(table, hypothesis="H2", analysis="ancova", metric=metric, term="method")
        h3 = _rows(table, hypothesis="H3", analysis="ancova", metric=metric, term="method")
        assert (h1["df1"], h1["df2"]) == (2, 30)
        assert (h2.iloc[0]["df1"], h2.iloc[0]["df2"]) == (2, 62)
        assert (h3.iloc[0]["df1"], h3.iloc[0]["df2"]) == (1, 41)
        per_task = _rows(table, hypothesis="H2", analysis="anova", metric=metric)
        assert set(per_task["task"]) == {"unknown_goal", "unknown_skill"}
        assert (per_task["df2"] == 30).all()
        # Repeated-measures versions: (k - 1, (k - 1)(n - 1)) with n = 11 participants, times
        # the Greenhouse-Geisser epsilon (below 1 with three conditions: the rows report the
        # corrected test).
        rm1 = _rows(table, hypothesis="H1", analysis="rm_anova", metric=metric).iloc[0]
        rm2 = _rows(table, hypothesis="H2", analysis="rm_anova", metric=metric, term="method")
        for row in (rm1, rm2.iloc[0]):
            assert 0.5 <= row["epsilon"] < 1  # 1 / (k - 1) <= epsilon <= 1
            # Each number of stats.csv has 8 significant digits (stats._rows.DIGITS).
            assert row["df1"] == pytest.approx(2 * row["epsilon"], rel=1e-7)
            assert row["df2"] == pytest.approx(20 * row["epsilon"], rel=1e-7)


def test_rm_anova_rows_report_the_greenhouse_geisser_p(trials, table):
    # The row's p is rm_anova's p_gg where epsilon < 1; the uncorrected p and Mauchly's
    # test are kept in their own columns.
    from casa_core.stats import rm_anova

    known = trials[trials["task"] == "known_goal"]
    direct = rm_anova(known, "error", "method", "participant").iloc[0]
    row = _rows(table, hypothesis="H1", analysis="rm_anova", metric="error").iloc[0]
    assert direct["eps"] < 1
    # stats.csv holds 8 significant digits (stats._rows.DIGITS).
    assert row["p"] == pytest.approx(direct["p_gg"], rel=1e-8)
    assert row["p_uncorrected"] == pytest.approx(direct["p"], rel=1e-8)
    assert row["p"] >= row["p_uncorrected"]  # the correction only widens the F distribution
    assert row["sphericity_W"] == pytest.approx(direct["W_spher"], rel=1e-8)
    assert row["sphericity_p"] == pytest.approx(direct["p_spher"], rel=1e-8)
    assert "Greenhouse-Geisser corrected" in row["note"]


def test_every_hypothesis_has_both_forms(table):
    for metric in METRICS:
        for hypothesis, task in (
            ("H1", "known_goal"),
            ("H2", "unknown_goal+unknown_skill"),
            ("H2", "unknown_goal"),
            ("H2", "unknown_skill"),
            ("H3", "unknown_goal+unknown_skill"),
        ):
            found = set(_rows(table, hypothesis=hypothesis, task=task, metric=metric)["analysis"])
            assert {"rm_anova", "mixedlm"} <= found, (hypothesis, task, metric)
            assert found & {"anova", "ancova"}, (hypothesis, task, metric)
        h1 = _rows(table, hypothesis="H1", metric=metric)
        assert set(h1["comparison"]) >= {"CASA vs NA", "CASA vs PBA"}
        noninf = _rows(h1, analysis="noninferiority")
        # Independent (paper: pooled variance), independent with Welch's t, paired.
        assert len(noninf) == 3 and set(noninf["comparison"]) == {"CASA vs PBA"}
        for task in ("unknown_goal", "unknown_skill"):
            rows = _rows(
                table, hypothesis="H2", task=task, metric=metric, analysis="noninferiority"
            )
            assert set(rows["comparison"]) == {"CASA before learning vs NA"}
            assert len(rows) == 3  # independent (paper), Welch and paired
        tukey = _rows(table, hypothesis="H2", task="unknown_goal+unknown_skill", metric=metric)
        assert "CASA before learning vs PBA" in set(tukey["comparison"])


def test_paper_rows_equal_direct_calls(trials, table):
    # The H1 ANOVA row is anova() on the Known Goal trials with the paper's three methods.
    known = trials[trials["task"] == "known_goal"]
    direct = anova(known, "error", "method").iloc[0]
    row = _rows(table, hypothesis="H1", analysis="anova", metric="error").iloc[0]
    assert row["statistic"] == pytest.approx(direct["F"])
    assert row["p"] == pytest.approx(direct["p"])
    # The H3 per-task ANOVA compares NA with CASA after learning only (not before learning).
    skill = trials[(trials["task"] == "unknown_skill") & (trials["phase"] == "before_learning")]
    after = trials[(trials["task"] == "unknown_skill") & (trials["phase"] == "after_learning")]
    subset = pd.concat([skill[skill["method"] == "NA"], after])
    direct = anova(subset, "effort", "phase").iloc[0]
    row = _rows(
        table, hypothesis="H3", analysis="anova", task="unknown_skill", metric="effort"
    ).iloc[0]
    assert row["statistic"] == pytest.approx(direct["F"])


def test_noninferiority_rows(table):
    rows = _rows(table, hypothesis="H1", analysis="noninferiority", metric="error")
    paper = rows[rows["note"].str.contains("as the paper")].iloc[0]
    welch = rows[rows["note"].str.contains("Welch")].iloc[0]
    paired = rows[rows["note"].str.contains("paired")].iloc[0]
    # stats.claims takes the first row without "paired" as the paper's: the pooled one.
    assert rows[~rows["note"].str.contains("paired")].index[0] == paper.name
    assert welch["estimate"] == paper["estimate"] and 10 <= welch["df1"] <= 20
    # ci_high is the one-sided bound; the verdict at margin 1.0 agrees with it.
    assert paper["ci_high"] > paper["estimate"] and np.isnan(paper["ci_low"])
    assert bool(paper["noninferior"]) == (paper["ci_high"] < 1.0)
    assert (paper["df1"], paper["n"]) == (20, 22)
    assert (paired["df1"], paired["n"]) == (10, 11)
    # Without a margin (efficiency), only the bound.
    rows = _rows(table, hypothesis="H1", analysis="noninferiority", metric="efficiency")
    assert rows["p"].isna().all() and rows["noninferior"].isna().all()
    # A fractional margin (relative effort) adds the ratio test, Welch's and paired.
    ratio = _rows(table, hypothesis="H1", analysis="noninferiority_ratio", metric="relative_effort")
    assert len(ratio) == 2 and ratio["note"].str.contains("paired").sum() == 1
    assert (ratio["margin"] == 1.1).all() and ratio["note"].str.contains("level 0.05").all()
    assert not _rows(table, analysis="noninferiority_ratio", metric="error").shape[0]


def test_likert_rows(table):
    h4 = _rows(table, hypothesis="H4")
    assert set(h4["task"]) == {"known_goal", "unknown_goal", "unknown_skill"}
    assert set(h4["metric"]) == {"understood", "effortless", "useful"}
    friedman = _rows(h4, analysis="friedman", task="unknown_goal")
    assert (friedman["df1"] == 3).all()  # NA, PBA, CASA before and after learning
    wilcoxon = _rows(h4, analysis="wilcoxon", task="unknown_skill", metric="useful")
    assert set(wilcoxon["comparison"]) == {
        "CASA after learning vs CASA before learning",
        "CASA after learning vs NA",
        "CASA after learning vs PBA",
    }
    assert wilcoxon["note"].str.contains("Holm-adjusted over 3").all()
    known = _rows(h4, analysis="wilcoxon", task="known_goal", metric="useful")
    assert set(known["comparison"]) == {"CASA vs NA", "CASA vs PBA"}


def test_repeated_trials_are_averaged(trials):
    # Two identical copies of every trial: one observation per participant-condition still.
    # (Known Goal only, to keep the test fast.)
    trials = trials[trials["task"] == "known_goal"]
    doubled = pd.concat([trials, trials], ignore_index=True)
    a = analyze_study(trials, metrics=["error"])
    b = analyze_study(doubled, metrics=["error"])
    pd.testing.assert_frame_equal(a, b)


def test_condition_names():
    # The stats' levels: the vocabulary's conditions, the CASA family first.
    assert CONDITION_ORDER == [
        "CASA",
        "CASA before learning",
        "CASA after learning",
        "NA",
        "PBA",
        "NA after learning",
        "PBA after learning",
    ]
    assert condition_of("CASA", "before_learning") == "CASA before learning"
    assert condition_of("CASA", "after_learning") == "CASA after learning"
    assert condition_of("CASA", "no_misspecification") == "CASA"
    assert condition_of("PBA", "before_learning") == "PBA"
    assert condition_of("NA", "familiarization") is None


# ----------------------------------------------------------------------- degenerate data


def _notes(table, **where) -> str:
    return " | ".join(_rows(table, **where)["note"])


def test_one_participant(trials):
    one = trials[trials["participant"] == "P00"]
    table = analyze_study(one, metrics=["error"])
    assert "no residual degrees of freedom" in _notes(table, hypothesis="H1", analysis="anova")
    # H1's 3 conditions: the sphericity estimate needs 3 (casa_core.stats._tables).
    assert "at least 3 participants" in _notes(table, hypothesis="H1", analysis="rm_anova")
    within_rows = table[table["analysis"].isin(["rm_anova", "mixedlm"])]
    assert within_rows["statistic"].isna().all() and within_rows["note"].str.len().gt(0).all()


def test_missing_condition(trials):
    no_pba = trials[trials["method"] != "PBA"]
    table = analyze_study(no_pba, metrics=["error"])
    h1 = _rows(table, hypothesis="H1", analysis="anova").iloc[0]
    assert h1["df1"] == 1 and "missing condition(s): PBA" in h1["note"]
    noninf = _rows(table, hypothesis="H1", analysis="noninferiority")
    assert noninf["note"].str.contains("no observations of method = 'PBA'").all()


def test_zero_variance(trials):
    flat = trials.assign(error=1.0)
    table = analyze_study(flat, metrics=["error"])
    tested = table[table["analysis"].isin(["anova", "ancova", "rm_anova", "mixedlm"])]
    assert tested["statistic"].isna().all()
    assert tested["note"].str.contains("zero variance").all()


def test_task_with_no_trials(trials):
    no_skill = trials[trials["task"] != "unknown_skill"]
    table = analyze_study(no_skill, metrics=["error"])
    rows = _rows(table, hypothesis="H2", task="unknown_skill")
    assert len(rows) > 0 and rows["note"].str.startswith("no trials of unknown_skill").all()
    pooled = _rows(table, hypothesis="H2", task="unknown_goal+unknown_skill", analysis="ancova")
    assert pooled["note"].str.contains("single value").all()


def test_bad_input_is_an_error(trials):
    with pytest.raises(ValueError, match=r"missing column\(s\) 'error'"):
        analyze_study(trials.drop(columns=["error"]))
    wrong = trials.copy()
    wrong.loc[5, "method"] = "TELEPORT"
    with pytest.raises(ValueError, match="row 5: method 'TELEPORT'"):
        analyze_study(wrong, metrics=["error"])
    practice = trials.copy()
    practice.loc[0, "method"] = "TELEPORT"  # a familiarization trial: still not a method
    assert practice.loc[0, "phase"] == "familiarization"
    with pytest.raises(ValueError, match="row 0: method 'TELEPORT' in phase 'familiarization'"):
        analyze_study(practice, metrics=["error"])
    as_read = trials.copy()
    as_read.loc[4, "method"] = np.nan  # what pandas makes of the text "NA" by default
    with pytest.raises(ValueError, match="keep_default_na=False"):
        analyze_study(as_read, metrics=["error"])


# ------------------------------------------------------------------------- APA report


def test_apa_formatting():
    # APA: F(df1, df2) = two decimals; p < .001 below a thousandth, else three decimals
    # without the leading zero.
    assert apa.f_test(104.9312, 2, 30, 2e-14) == "F(2, 30) = 104.93, p < .001"
    assert apa.f_test(8.93, 2, 30, 0.00094) == "F(2, 30) = 8.93, p < .001"
    assert apa.f_test(6.119, 2, 62, 0.0038) == "F(2, 62) = 6.12, p = .004"
    assert apa.p_value(0.05) == "p = .050"
    assert apa.chi2_test(7.2986, 2, 0.026) == "χ²(2) = 7.30, p = .026"
    assert apa.proportion(0.371) == ".37"


def test_report_lists_every_hypothesis(table):
    text = report_markdown(table)
    for title in ("## H1", "## H2", "## H3", "## H4"):
        assert title in text
    row = _rows(table, hypothesis="H1", analysis="anova", metric="error").iloc[0]
    assert apa.f_test(row["statistic"], 30 // 15, 30, row["p"]) in text
    # One line per row, plus a header and a separator line per hypothesis.
    assert text.count("\n| ") == len(table) + 2 * 4


# -------------------------------------------------------------------------------- CLI


def test_cli_writes_both_outputs(tmp_path, trials, likert, capsys):
    # Known Goal only keeps it fast; the other hypotheses still get (skipped) rows.
    trials[trials["task"] == "known_goal"].to_csv(tmp_path / "trials.csv", index=False)
    likert[likert["task"] == "known_goal"].to_csv(tmp_path / "likert.csv", index=False)
    out_csv, out_md = tmp_path / "out" / "stats.csv", tmp_path / "out" / "stats.md"
    code = cli.main(
        [
            "stats",
            "--trials",
            str(tmp_path / "trials.csv"),
            "--likert",
            str(tmp_path / "likert.csv"),
            "--out-csv",
            str(out_csv),
            "--out-md",
            str(out_md),
        ]
    )
    assert code == 0
    written = pd.read_csv(out_csv, keep_default_na=False, na_values=[""])
    assert list(written.columns) == STATS_COLUMNS
    assert set(written["hypothesis"]) == {"H1", "H2", "H3", "H4"}
    assert "F(2, 30)" in out_md.read_text(encoding="utf-8")
    # CSV round trip: the report is the table's, opened by the trials' description.
    read_trials = pd.read_csv(tmp_path / "trials.csv", keep_default_na=False, na_values=[""])
    report = out_md.read_text(encoding="utf-8")
    assert report_markdown(written, trials=read_trials) == report
    assert "The data are simulated (source: simulated): 11 simulated participants." in report
    assert sorted(p.name for p in out_csv.parent.iterdir()) == ["stats.csv", "stats.md"]


def test_cli_bad_input_exit_code(tmp_path, capsys):
    (tmp_path / "trials.csv").write_text("participant,task\nP1,known_goal\n", encoding="utf-8")
    code = cli.main(
        [
            "stats",
            "--trials",
            str(tmp_path / "trials.csv"),
            "--out-csv",
            str(tmp_path / "s.csv"),
            "--out-md",
            str(tmp_path / "s.md"),
        ]
    )
    assert code == 1
    assert "missing column(s) 'method'" in capsys.readouterr().err
    assert not (tmp_path / "s.csv").exists()


def test_stats_import_no_robot_study_or_learning():
    import subprocess
    import sys

    code = (
        "import sys, casa_core.stats; "
        "print(sorted(m for m in sys.modules if m.split('.')[:2] in "
        "(['casa_core', 'robot'], ['casa_core', 'study'], ['casa_core', 'learning'])))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
