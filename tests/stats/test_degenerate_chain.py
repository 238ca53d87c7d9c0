"""Degenerate and extreme data never crash the statistics, their reports or the figures.

A dataset that validates goes through the whole per-dataset chain, as the workflow runs
it: tables built and written, read back, statistics, ``stats.csv`` read back, the APA
report and the summary, the objective and Likert figures. Degenerate data (a pilot of two,
a condition with one participant, equal values) give rows whose ``note`` says why a test
was skipped, never an exception. The expected outcomes follow from the counts of each
design (stated at each test); the generated datasets are seeded, so a failure reproduces.
"""

from __future__ import annotations

import io
import warnings

import matplotlib
import numpy as np
import pandas as pd
import pytest

from casa_core.analysis.datasets import build_tables, write_tables
from casa_core.figures import likert_figure, objective_figure
from casa_core.figures._bars import wilson_interval
from casa_core.figures.build import build_figure
from casa_core.io import SURVEY_COLUMNS, check_paths, read_table, write_surveys, write_trial
from casa_core.io.atomic import frame_to_csv_text
from casa_core.report import pages as report_pages
from casa_core.stats import (
    analyze_study,
    ancova,
    anova,
    friedman,
    mixedlm,
    non_inferiority,
    report_markdown,
    rm_anova,
    tukey_hsd,
    wilcoxon_holm,
)
from casa_core.stats.summary import summary_markdown
from casa_core.vocabulary import QUESTIONS
from tests.io.test_logs_synthetic import CONDITIONS, SCENE, trial_frame, write_dataset

matplotlib.use("Agg")

KNOWN = [c for c in CONDITIONS if c[0] == "known_goal"]


@pytest.fixture(autouse=True)
def _quiet():
    # Degenerate data make numpy, scipy and statsmodels warn; only exceptions matter here.
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def _chain(folder, out) -> dict:
    """The per-dataset chain of the workflow on one raw dataset folder; its products."""
    tables = build_tables(folder, SCENE)
    write_tables(tables, out)
    trials, likert = read_table(out / "trials.csv"), read_table(out / "likert.csv")
    stats = analyze_study(trials, likert)
    (out / "stats.csv").write_text(frame_to_csv_text(stats), encoding="utf-8")
    report = report_markdown(stats)
    summary = summary_markdown(read_table(out / "stats.csv"), dataset=folder.name)
    report_pages.markdown_html(summary)
    # As build_figure draws them, rendered in memory at a low resolution (faster).
    stats_back = read_table(out / "stats.csv")
    _draw(objective_figure(read_table(out / "trials.csv"), stats_back))
    _draw(likert_figure(read_table(out / "likert.csv"), stats_back))
    return {"stats": stats, "report": report, "summary": summary}


def _skipped(stats: pd.DataFrame) -> pd.DataFrame:
    """The rows of tests that did not run: neither a statistic nor an estimate."""
    return stats[stats["statistic"].isna() & stats["estimate"].isna()]


def _draw(fig) -> None:
    """Render a figure (tick labels and limits are computed only when drawn)."""
    fig.savefig(io.BytesIO(), format="png", dpi=30)


def _skipped_notes(stats: pd.DataFrame, analysis: str, hypothesis: str = "H1") -> list[str]:
    """The notes of ``analysis`` on the error in ``hypothesis``."""
    rows = stats[(stats["analysis"] == analysis) & (stats["hypothesis"] == hypothesis)]
    return rows.loc[rows["metric"] == "error", "note"].tolist()


# --- the pilot datasets of the issue ---------------------------------------------------


def test_pilot_with_two_participants_runs_the_chain(tmp_path):
    write_dataset(tmp_path / "pilot", ("p01", "p02"), conditions=KNOWN)
    result = _chain(tmp_path / "pilot", tmp_path / "out")
    stats = result["stats"]
    # Two participants, three conditions: the contrasts' covariance has rank 1 < 2 df.
    (note,) = _skipped_notes(stats, "rm_anova")
    assert "needs more participants" in note and "got 2" in note
    assert stats.loc[stats["analysis"] == "rm_anova", "statistic"].isna().all()
    # The paper's ANOVA treats the 6 participant-conditions as independent: F(2, 3).
    h1 = stats[(stats["analysis"] == "anova") & (stats["metric"] == "error")].iloc[0]
    assert np.isfinite(h1["statistic"]) and (h1["df1"], h1["df2"]) == (2.0, 3.0)
    assert "skipped: needs more participants" in result["report"]
    assert "skipped: needs more participants" in result["summary"]
    written = build_figure("objective", tmp_path / "objective", trials=tmp_path / "out/trials.csv")
    assert [p.suffix for p in written] == [".pdf", ".png"]


def test_condition_with_a_single_participant(tmp_path):
    folder = tmp_path / "ds"
    write_dataset(folder, ("p01", "p02", "p03"), conditions=KNOWN[:2])
    write_dataset(folder, ("p04",), conditions=KNOWN[2:], surveys=False, seed=1)
    stats = _chain(folder, tmp_path / "out")["stats"]
    tukey = stats[(stats["analysis"] == "tukey") & (stats["metric"] == "error")]
    tukey = tukey[tukey["hypothesis"] == "H1"]
    # CASA has one observation: scipy's Tukey HSD refuses it, the row says so.
    assert tukey["note"].str.contains("needs at least 2 observations per group").all()
    # No participant has all three conditions.
    assert "got 0" in _skipped_notes(stats, "rm_anova")[0]


def test_one_participant_runs_the_chain(tmp_path):
    write_dataset(tmp_path / "solo", ("p01",), conditions=CONDITIONS[::2])
    stats = _chain(tmp_path / "solo", tmp_path / "out")["stats"]
    assert _skipped(stats)["note"].str.len().gt(0).all()
    within = stats[stats["analysis"].isin(["rm_anova", "mixedlm", "friedman"])]
    # One participant: no within-subjects test can run, each says why.
    assert within["statistic"].isna().all() and within["note"].str.len().gt(0).all()
    assert within["note"].str.contains("at least 2 participants").any()


# --- every analysis on degenerate inputs -----------------------------------------------


def _long(values, participants: int, conditions=("a", "b", "c")) -> pd.DataFrame:
    """``participants`` x ``conditions`` observations taking ``values`` in turn."""
    cells = [(f"s{i}", c) for c in conditions for i in range(participants)]
    y = np.resize(np.asarray(values, dtype=float), len(cells))
    frame = pd.DataFrame(cells, columns=["s", "c"])
    frame["y"], frame["task"] = y, np.resize(["t1", "t2"], len(cells))
    return frame


ANALYSES = {
    "anova": lambda d: anova(d, "y", "c"),
    "ancova": lambda d: ancova(d, "y", "c", "task"),
    "tukey": lambda d: tukey_hsd(d, "y", "c"),
    "noninferiority": lambda d: non_inferiority(d, "y", "c", "a", "b", margin=1.0),
    "noninferiority_paired": lambda d: non_inferiority(d, "y", "c", "a", "b", subject="s"),
    "rm_anova": lambda d: rm_anova(d, "y", "c", "s"),
    "rm_anova_two_way": lambda d: rm_anova(d, "y", ["c", "task"], "s"),
    "mixedlm": lambda d: mixedlm(d, "y", "c", "s"),
    "friedman": lambda d: friedman(d, "y", "c", "s"),
    "wilcoxon": lambda d: wilcoxon_holm(d, "y", "c", "s", target="a"),
}
STATISTIC = {"anova": "F", "ancova": "F", "tukey": "diff", "rm_anova": "F", "mixedlm": "chi2"}
STATISTIC |= {"friedman": "Q", "wilcoxon": "V", "noninferiority": "bound"}
DEGENERATE = {
    "one participant": _long([1.0, 2.0, 4.0], 1),
    "two participants": _long([1.0, 2.5, 2.0, 4.0, 3.0, 7.5], 2),
    "one observation in a group": _long([1.0, 2.0, 4.0, 3.0, 6.0, 9.0], 3).iloc[:-2],
    "all equal": _long([3.0], 4),
    "all zero": _long([0.0], 3),
    "huge": _long([1e300, 3e300, 2e300, 5e299], 4),
    "near the float maximum": _long([1.7e308, -1.7e308, 1e308], 4),
    "tiny": _long([1e-300, 3e-300, 0.0, 2e-300], 4),
    "one condition": _long([1.0, 2.0], 3, conditions=("a",)),
    "empty": _long([1.0], 2).iloc[:0],
    # s0 has a and c, s1 and s2 b and c: no participant has every condition, none a and b.
    "no complete participant": _long([1.0, 2.0, 4.0, 3.0, 6.0, 9.0, 2.0, 5.0, 7.0], 3).iloc[
        [0, 6, 4, 7, 5, 8]
    ],
}

NO_OTHER = ("one condition", "empty")


@pytest.mark.parametrize("case", list(DEGENERATE))
@pytest.mark.parametrize("analysis", list(ANALYSES))
def test_every_analysis_gives_a_row_with_a_reason(analysis, case):
    table = ANALYSES[analysis](DEGENERATE[case])
    # Wilcoxon has a row per other condition: none when "a" is the only one.
    assert len(table) >= (0 if analysis == "wilcoxon" and case in NO_OTHER else 1)
    statistic = table[STATISTIC[analysis.removesuffix("_paired").removesuffix("_two_way")]]
    # A test either ran (finite statistic) or says why not.
    for value, note in zip(statistic, table["note"], strict=True):
        assert np.isfinite(value) or note, (analysis, case, table.to_dict("records"))


def test_rm_anova_needs_more_participants_than_degrees_of_freedom():
    # 3 participants and 3 conditions (2 df) run; the same with 2 is skipped, as is the
    # two-way design's interaction (2 x 1 df) and its main effects with 2 participants.
    ran = rm_anova(DEGENERATE["huge"].assign(y=np.arange(12.0) % 5), "y", "c", "s")
    assert np.isfinite(ran["F"].iloc[0])
    cells = [(f"s{i}", c, t) for i in range(2) for c in "abc" for t in ("t1", "t2")]
    two_way = pd.DataFrame(cells, columns=["s", "c", "task"]).assign(y=np.arange(12.0) ** 1.5)
    two = rm_anova(two_way, "y", ["c", "task"], "s")
    assert two["note"].str.contains("needs more participants").all(), two["note"].tolist()


def test_huge_values_say_their_sums_of_squares_overflow():
    note = anova(DEGENERATE["near the float maximum"], "y", "c")["note"].iloc[0]
    assert "too large (up to 1.7e+308)" in note


def test_cell_means_of_values_near_the_float_maximum_do_not_overflow():
    # Two trials of 1.5e308 average to 1.5e308; summed first they would be infinite.
    trials = pd.DataFrame(
        [
            {"participant": f"p{i}", "task": "known_goal", "method": m, "error": 1.5e308}
            | {"phase": "no_misspecification"}
            for i in range(3)
            for m in ("NA", "PBA", "CASA")
            for _ in range(2)
        ]
    )
    stats = analyze_study(trials, metrics=["error"])
    h1 = stats[stats["hypothesis"] == "H1"]
    assert h1["note"].str.contains("too large").all()


# --- rendering and figures on degenerate and extreme tables ----------------------------


def _trials(values, participants: int, conditions=CONDITIONS, success=True) -> pd.DataFrame:
    rows = []
    for i in range(participants):
        for j, (task, method, phase) in enumerate(conditions):
            value = values[(i * len(conditions) + j) % len(values)]
            rows.append(
                {"participant": f"p{i}", "task": task, "method": method, "phase": phase}
                | {"source": "human", "error": value, "efficiency": value, "effort": 3}
                | {"relative_effort": value, "duration": 10.0, "timed_out": False}
                | {"success": success, "trial": f"p{i}/{task}_{method}_{phase}"}
            )
    return pd.DataFrame(rows)


EXTREME = {
    "error 1e300": _trials([1e300, 2e300, 5e299], 3),
    "near the float maximum": _trials([1.7e308, 1e308, 1.2e308], 3),
    "all equal": _trials([1.0], 4),
    "all zero": _trials([0.0], 3),
    "one trial per condition": _trials([0.5, 0.7, 0.2], 1),
    "all of four succeed": _trials([0.5, 0.7, 0.2, 0.9], 4, success=True),
    "none of three succeed": _trials([0.5, 0.7, 0.2], 3, success=False),
}


@pytest.mark.parametrize("case", list(EXTREME))
def test_extreme_tables_give_stats_reports_and_an_objective_figure(case):
    trials = EXTREME[case]
    stats = analyze_study(trials, metrics=["error"])
    assert _skipped(stats)["note"].str.len().gt(0).all()
    stats_back = read_table(io.StringIO(frame_to_csv_text(stats)))
    assert "H1" in report_markdown(stats_back)
    summary_markdown(stats_back, dataset=case)
    _draw(objective_figure(trials, stats_back))


def test_likert_figure_on_one_participant_and_equal_answers():
    rows = [
        (f"p{i}", task, method, phase, question, 4)
        for i in range(2)
        for task, method, phase in CONDITIONS
        for question in QUESTIONS
    ]
    likert = pd.DataFrame(rows, columns=list(SURVEY_COLUMNS))
    for part in (likert, likert[likert["participant"] == "p0"]):
        stats = analyze_study(_trials([1.0], 1).iloc[:0], part)
        notes = stats.loc[stats["analysis"] == "friedman", "note"]
        assert notes.str.len().gt(0).all()  # equal answers or a single participant
        _draw(likert_figure(part, stats))


def test_wilson_interval_holds_the_proportion():
    # The Wilson interval contains k / n by construction; rounding once left n of n at
    # 1 - 1e-16 (4 of 4, 10 of 10) and 0 of n at +3e-17, a negative error bar.
    for n in range(1, 80):
        for k in range(n + 1):
            low, high = wilson_interval(k, n)
            assert 0.0 <= low <= k / n <= high <= 1.0, (k, n)


# --- the property: every generated dataset that validates goes through the chain -------


def _generated_dataset(folder, rng: np.random.Generator) -> None:
    """A random valid-looking dataset: 1-4 participants, some conditions, short trials."""
    participants = [f"p{i + 1:02d}" for i in range(int(rng.integers(1, 5)))]
    chosen = rng.choice(len(CONDITIONS), int(rng.integers(1, len(CONDITIONS) + 1)), False)
    conditions = [CONDITIONS[j] for j in sorted(chosen)]
    answered = []
    for participant in participants:
        mine = [c for c in conditions if rng.uniform() < 0.85] or conditions[:1]
        for task, method, phase in mine:
            intents = ("green", "purple") if method != "NA" else ()
            offset = [*rng.normal(0.0, 0.02, 3), 0.0]
            frame = trial_frame(
                task,
                offset=offset,
                slowdown=int(rng.integers(1, 3)),
                intents=intents,
                lapses=float(rng.choice([0.0, 0.1])),
                rng=rng,
            )
            style = rng.choice(["whole", "cut", "still"])
            if style == "cut":
                frame = frame.iloc[: int(rng.integers(2, len(frame) + 1))]
            elif style == "still":
                # Standing at the start: all-equal positions and no keys.
                frame = frame.iloc[: int(rng.integers(2, 40))].copy()
                frame[["x", "y", "z", "rot"]] = frame[["x", "y", "z", "rot"]].iloc[0].to_numpy()
                frame["keys"] = ""
            meta = {"participant": participant, "task": task, "method": method}
            meta |= {"phase": phase, "source": "human", "intents": list(intents), "seed": 0}
            if rng.uniform() < 0.5:
                meta["max_duration"] = float(rng.choice([2.0, 60.0]))
            write_trial(folder / participant / f"{task}_{method}_{phase}", meta, frame)
            answered.append((participant, task, method, phase))
    if rng.uniform() < 0.6:
        equal = rng.uniform() < 0.3
        rows = [
            (*condition, question, 4 if equal else int(rng.integers(1, 8)))
            for condition in answered
            for question in QUESTIONS
        ]
        write_surveys(folder / "surveys.csv", pd.DataFrame(rows, columns=list(SURVEY_COLUMNS)))


#: Seeds of the generated datasets; few, so that the test stays within seconds. Seed 24
#: (found by a longer sweep) has Likert answers where no participant has every condition.
SEEDS = (0, 1, 2, 24)


def test_every_generated_dataset_that_validates_goes_through_the_chain(tmp_path):
    validated = []
    for seed in SEEDS:
        folder = tmp_path / f"ds{seed}"
        _generated_dataset(folder, np.random.default_rng(seed))
        if any(check.problems for check in check_paths([folder])):
            continue
        try:
            _chain(folder, tmp_path / f"out{seed}")
        except Exception as error:  # noqa: BLE001 - report the seed with any failure
            raise AssertionError(f"seed {seed}: the chain failed on a valid dataset") from error
        validated.append(seed)
    # Most generated datasets are valid: otherwise the property would test nothing.
    assert len(validated) >= len(SEEDS) // 2, validated
