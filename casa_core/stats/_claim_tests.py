"""The checks behind hypotheses H1-H4 in :mod:`casa_core.stats.claims`, read from stats.csv.

Each check is one test in one form: the paper's form (each participant-condition an
independent observation: ANOVA or ANCOVA with Tukey HSD, independent non-inferiority,
mean Likert scores) or the within-subjects form (repeated-measures ANOVA, paired
non-inferiority, Friedman and Wilcoxon). A check passes, fails, or cannot be decided
(``passed`` None: the test was skipped or is absent, or no margin is known).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from casa_core.defaults import SIGNIFICANCE
from casa_core.io.tables import numeric_column, require_columns
from casa_core.stats.apa import p_value
from casa_core.stats.study import POOLED, _conditions, _prepare_trials
from casa_core.vocabulary import (
    CASA_AFTER_LEARNING,
    CASA_BEFORE_LEARNING,
    KNOWN_TASK,
    UNKNOWN_TASKS,
)

#: The hypotheses' words: "more accurate, efficient, and effortless" (lower is better).
METRICS = ("error", "efficiency", "relative_effort")
#: Non-inferiority bounds the paper reports for relative effort (Sec. V-B), used as the
#: margin when stats.csv gives none: relative effort has no unit, so the paper's bound
#: means the same here. Error and efficiency depend on units the paper does not give.
PAPER_BOUNDS = {
    (KNOWN_TASK, "relative_effort"): 0.065,
    ("unknown_goal", "relative_effort"): 0.035,
    ("unknown_skill", "relative_effort"): 0.03,
}


@dataclass(frozen=True)
class Check:
    """One test of a hypothesis: whether it passed (None: undecided) and its numbers.

    ``metric`` and ``form`` (``paper`` or ``within``) say which metric and analysis it
    belongs to (H1-H3; empty for H4's).
    """

    passed: bool | None
    text: str
    metric: str = ""
    form: str = ""


def _text(stats: pd.DataFrame) -> pd.DataFrame:
    require_columns(stats, ["hypothesis", "analysis", "task", "metric", "p"], "stats table")
    table = stats.copy()
    for column in ("term", "comparison", "note", "noninferior"):
        if column not in table.columns:
            table[column] = ""
    columns = ["term", "comparison", "note"]
    table[columns] = table[columns].astype(object).fillna("")
    for column in ("p", "estimate", "ci_high"):
        if column in table.columns:
            table[column] = numeric_column(table, column, "stats table")
    return table


def _rows(stats, hypothesis, task, metric, analysis, **where) -> pd.DataFrame:
    chosen = (stats["hypothesis"] == hypothesis) & (stats["task"] == task)
    chosen &= (stats["metric"] == metric) & (stats["analysis"] == analysis)
    for column, value in where.items():
        chosen &= stats[column] == value
    return stats[chosen]


def _significant(rows: pd.DataFrame, name: str) -> tuple[bool | None, str]:
    if rows.empty or not np.isfinite(rows["p"].iloc[0]):
        return None, f"{name} not computed"
    p = float(rows["p"].iloc[0])
    return p < SIGNIFICANCE, f"{name} {p_value(p)}"


def condition_means(trials: pd.DataFrame, tasks) -> dict[str, pd.Series]:
    """Per metric, the mean over participant-task cells of each condition in ``tasks``."""
    cells = _prepare_trials(trials, list(METRICS))
    return {
        metric: frame[frame["task"].isin(tasks)].groupby("method", observed=True)[metric].mean()
        for metric, frame in cells.items()
    }


def _direction(means: pd.Series, better: str, worse: str) -> tuple[bool | None, str]:
    if better not in means.index or worse not in means.index:
        return None, f"no trials of {better} or {worse}"
    difference = float(means[better] - means[worse])
    return difference < 0, f"mean {better} - {worse} = {difference:.3g}"


def _combine(form: str, metric: str, parts: list[tuple[bool | None, str]]) -> Check:
    outcomes = [passed for passed, _ in parts]
    # A failed part decides; an undecided one leaves the check undecided otherwise.
    passed = False if False in outcomes else None if None in outcomes else True
    verdict = {True: "pass", False: "fail", None: "undecided"}[passed]
    text = f"{metric} ({form}): {', '.join(t for _, t in parts)}: {verdict}"
    return Check(passed, text, metric, form)


def superiority(stats, means, *, hypothesis, task, metric, better, worse) -> list[Check]:
    """``better`` beats ``worse`` on ``metric``: the paper's test, then the within one."""
    omnibus = "ancova" if task == POOLED else "anova"
    direction = _direction(means[metric], better, worse)
    paper = [_significant(_rows(stats, hypothesis, task, metric, omnibus, term="method"), omnibus)]
    tukey = _rows(stats, hypothesis, task, metric, "tukey")
    pair = tukey[tukey["comparison"].isin([f"{better} vs {worse}", f"{worse} vs {better}"])]
    if not tukey.empty:
        paper.append(_significant(pair, f"Tukey {better} vs {worse}"))
    within = _rows(stats, hypothesis, task, metric, "rm_anova", term="method")
    return [
        _combine("paper", metric, [*paper, direction]),
        _combine("within", metric, [_significant(within, "rm_anova"), direction]),
    ]


def _noninferior_flag(value) -> bool | None:
    """The ``noninferior`` cell: a boolean (from analyze_study) or its text (stats.csv)."""
    if value is None or pd.isna(value):
        return None
    if value in (True, "True", "true"):
        return True
    if value in (False, "False", "false"):
        return False
    return None


def noninferiority(stats, *, hypothesis, task, metric, new, reference) -> list[Check]:
    """``new`` not inferior to ``reference``: independent (paper), then paired (within)."""
    rows = _rows(stats, hypothesis, task, metric, "noninferiority")
    rows = rows[rows["comparison"] == f"{new} vs {reference}"]
    checks = []
    for form, paired in (("paper", False), ("within", True)):
        name = f"{metric} {task} non-inferior to {reference} ({form})"
        row = rows[rows["note"].str.contains("paired") == paired]
        if row.empty or not np.isfinite(row["ci_high"].iloc[0]):
            checks.append(Check(None, f"{name}: bound not computed: undecided", metric, form))
            continue
        bound = float(row["ci_high"].iloc[0])
        flag = _noninferior_flag(row["noninferior"].iloc[0])
        if flag is not None:
            text = f"bound {bound:.3g} at margin {float(row['margin'].iloc[0]):.3g} (stats.csv)"
        elif (task, metric) in PAPER_BOUNDS:
            margin = PAPER_BOUNDS[(task, metric)]
            flag, text = bound < margin, f"bound {bound:.3g} vs the paper's {margin:g}"
        else:
            text = f"{name}: bound {bound:.3g}, no margin: undecided"
            checks.append(Check(None, text, metric, form))
            continue
        checks.append(Check(flag, f"{name}: {text}: {'pass' if flag else 'fail'}", metric, form))
    return checks


def h1_checks(stats: pd.DataFrame, trials: pd.DataFrame) -> list[Check]:
    """H1: CASA superior to NA and not inferior to PBA on Known Goal."""
    stats, means = _text(stats), condition_means(trials, [KNOWN_TASK])
    checks = []
    for metric in METRICS:
        key = {"hypothesis": "H1", "task": KNOWN_TASK, "metric": metric}
        checks += superiority(stats, means, **key, better="CASA", worse="NA")
        checks += noninferiority(stats, **key, new="CASA", reference="PBA")
    return checks


def h2_checks(stats: pd.DataFrame, trials: pd.DataFrame) -> list[Check]:
    """H2: CASA before learning superior to PBA (pooled), not inferior to NA (per task)."""
    stats, means = _text(stats), condition_means(trials, list(UNKNOWN_TASKS))
    checks = []
    for metric in METRICS:
        key = {"hypothesis": "H2", "metric": metric}
        checks += superiority(
            stats, means, **key, task=POOLED, better=CASA_BEFORE_LEARNING, worse="PBA"
        )
        for task in UNKNOWN_TASKS:
            checks += noninferiority(
                stats, **key, task=task, new=CASA_BEFORE_LEARNING, reference="NA"
            )
    return checks


def h3_checks(stats: pd.DataFrame, trials: pd.DataFrame) -> list[Check]:
    """H3: CASA after learning superior to NA (pooled over the misspecified tasks)."""
    stats, means = _text(stats), condition_means(trials, list(UNKNOWN_TASKS))
    checks = []
    for metric in METRICS:
        key = {"hypothesis": "H3", "task": POOLED, "metric": metric}
        checks += superiority(stats, means, **key, better=CASA_AFTER_LEARNING, worse="NA")
    return checks


def likert_checks(stats: pd.DataFrame, likert: pd.DataFrame) -> list[Check]:
    """H4: per misspecified task and question, CASA after learning rated above the rest."""
    stats = _text(stats)
    frame = _conditions(likert, "likert table")
    frame["score"] = numeric_column(frame, "score", "likert table")
    checks = []
    for task in UNKNOWN_TASKS:
        for question in sorted(frame.loc[frame["task"] == task, "question"].unique()):
            part = frame[(frame["task"] == task) & (frame["question"] == question)]
            means = part.groupby("method", observed=True)["score"].mean()
            name = f"{task} {question}"
            if CASA_AFTER_LEARNING not in means.index or len(means) < 2:
                checks.append(Check(None, f"{name}: too few conditions: undecided"))
            else:
                others = means.drop(CASA_AFTER_LEARNING)
                best = bool(means[CASA_AFTER_LEARNING] > others.max())
                text = f"mean {means[CASA_AFTER_LEARNING]:.2f} vs at most {others.max():.2f}"
                checks.append(Check(best, f"{name} (paper): {text}: {'pass' if best else 'fail'}"))
            checks.append(_likert_within(stats, task, question, name))
    return checks


def _likert_within(stats, task, question, name) -> Check:
    parts = [_significant(_rows(stats, "H4", task, question, "friedman"), "Friedman")]
    wilcoxon = _rows(stats, "H4", task, question, "wilcoxon")
    wilcoxon = wilcoxon[wilcoxon["comparison"].str.startswith(f"{CASA_AFTER_LEARNING} vs ")]
    if wilcoxon.empty:
        parts.append((None, "no Wilcoxon tests"))
    for index, row in wilcoxon.iterrows():
        other = row["comparison"].removeprefix(f"{CASA_AFTER_LEARNING} vs ")
        significant, text = _significant(wilcoxon.loc[[index]], f"vs {other}")
        higher = None if not np.isfinite(row["estimate"]) else bool(row["estimate"] > 0)
        passed = None if significant is None or higher is None else significant and higher
        parts.append((passed, f"{text} (difference {row['estimate']:.3g})"))
    return _combine("within", name, parts)
