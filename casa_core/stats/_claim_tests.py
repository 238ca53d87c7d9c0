"""The checks behind hypotheses H1-H4 in :mod:`casa_core.stats.claims`, read from stats.csv.

Each check is one test in one form: the paper's form (each participant-condition an
independent observation: ANOVA or ANCOVA with Tukey HSD, independent non-inferiority,
mean Likert scores) or the within-subjects form (repeated-measures ANOVA, paired
non-inferiority, Friedman and Wilcoxon). A check passes, fails, or cannot be decided
(``passed`` None: the test was skipped or is absent, or no margin is known). A check
that does not pass says why (:attr:`Check.reason`, and at the end of its text): not
significant, or significant but in the opposite direction to the paper's, say.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import pandas as pd

from casa_core.defaults import SIGNIFICANCE
from casa_core.io.tables import numeric_column, require_columns
from casa_core.stats._rows import noninferiority_level
from casa_core.stats._tables import participants_shortfall
from casa_core.stats.apa import p_value
from casa_core.stats.margins import PAPER_ALPHA
from casa_core.stats.study import POOLED, _prepare_trials
from casa_core.vocabulary import (
    CASA_AFTER_LEARNING,
    CASA_BEFORE_LEARNING,
    KNOWN_TASK,
    TASK_LABELS,
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


#: Between a check's outcome and why it did not pass; results.md splits a check's text at
#: its last ": ", so the reason never holds one.
BECAUSE = " — "


@dataclass(frozen=True)
class Check:
    """One test of a hypothesis: whether it passed (None: undecided) and its numbers.

    ``metric`` and ``form`` (``paper`` or ``within``) say which metric and analysis it
    belongs to (H1-H3; empty for H4's). ``requirement`` is what the check asks in the
    paper's direction (``"CASA after learning below NA (...)"``), for the hypothesis'
    criterion; ``reason`` is why it did not pass, in short and without numbers
    (``"significant, but in the opposite direction"``; empty when it passed), and the
    text ends with the outcome and the same reason with its numbers. ``shortfall`` is
    ``(got, needed)`` participants when it is undecided because a test it needs was not
    computed for too few participants (the skip note of stats.csv), else None.
    """

    passed: bool | None
    text: str
    metric: str = ""
    form: str = ""
    requirement: str = ""
    reason: str = ""
    shortfall: tuple[int, int] | None = None


class Part(NamedTuple):
    """One condition of a check: met (None: undecided), its numbers, why it is not met.

    ``reason`` is the short reason (no numbers), ``why`` the same with its numbers;
    ``shortfall`` as :attr:`Check.shortfall`.
    """

    passed: bool | None
    text: str
    reason: str = ""
    why: str = ""
    shortfall: tuple[int, int] | None = None


def _outcome(passed: bool | None, why: str = "") -> str:
    """``pass``, ``fail`` or ``undecided``, and why a check failed (an undecided one's
    numbers already say what is missing)."""
    verdict = {True: "pass", False: "fail", None: "undecided"}[passed]
    return f"{verdict}{BECAUSE}{why}" if why and passed is False else verdict


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


#: The reason of a check undecided because a test needs more participants.
TOO_FEW = "too few participants"


def _shortfall(rows: pd.DataFrame) -> tuple[int, int] | None:
    """``(got, needed)`` participants of a skipped test, from its note in stats.csv."""
    if rows.empty or "note" not in rows.columns:
        return None
    return participants_shortfall(rows["note"].iloc[0])


def _significant(rows: pd.DataFrame, name: str) -> Part:
    if rows.empty or not np.isfinite(rows["p"].iloc[0]):
        shortfall = _shortfall(rows)
        if shortfall is not None:
            got, needed = shortfall
            text = f"{name} not computed ({got} participants, needs {needed})"
            return Part(None, text, TOO_FEW, text, shortfall)
        return Part(None, f"{name} not computed", "test not computed", f"{name} not computed")
    p = float(rows["p"].iloc[0])
    why = f"not significant ({name} {p_value(p)})"
    return Part(p < SIGNIFICANCE, f"{name} {p_value(p)}", "not significant", why)


def condition_means(trials: pd.DataFrame, tasks) -> dict[str, pd.Series]:
    """Per metric, the mean over participant-task cells of each condition in ``tasks``."""
    cells = _prepare_trials(trials, list(METRICS))
    return {
        metric: frame[frame["task"].isin(tasks)].groupby("method", observed=True)[metric].mean()
        for metric, frame in cells.items()
    }


#: A reason's words for condition means on the other side of the paper's direction.
OPPOSITE = "in the opposite direction"


def _direction(means: pd.Series, better: str, worse: str) -> Part:
    """The paper's direction: ``better``'s mean below ``worse``'s (lower is better)."""
    if better not in means.index or worse not in means.index:
        text = f"no trials of {better} or {worse}"
        return Part(None, text, "no trials of a condition", text)
    difference = float(means[better] - means[worse])
    text = f"mean {better} - {worse} = {difference:.3g}"
    if difference > 0:
        return Part(False, text, OPPOSITE, f"{OPPOSITE} ({better} above {worse})")
    return Part(difference < 0, text, "no difference", f"no difference ({better} equal to {worse})")


def _in_direction(tests: list[Part], direction: Part) -> list[Part]:
    """The parts of a superiority check; a significant test the wrong way round says so."""
    if direction.reason == OPPOSITE and all(part.passed for part in tests):
        reason = f"significant, but {direction.reason}"
        direction = direction._replace(reason=reason, why=f"significant, but {direction.why}")
    return [*tests, direction]


def _sentence(reasons) -> str:
    """Reasons as one clause, each said once: ``not significant, and no difference``.

    >>> _sentence(["not significant", "not significant, and no difference"])
    'not significant, and no difference'
    >>> _sentence(["not significant", "no difference", "in the opposite direction"])
    'not significant, no difference, and in the opposite direction'
    """
    said = list(dict.fromkeys(a for reason in reasons for a in reason.split(", and ") if a))
    return ", and ".join(said) if len(said) < 3 else f"{', '.join(said[:-1])}, and {said[-1]}"


def _combine(form: str, metric: str, parts: list[Part], requirement: str = "") -> Check:
    outcomes = [part.passed for part in parts]
    # A failed part decides; an undecided one leaves the check undecided otherwise.
    passed = False if False in outcomes else None if None in outcomes else True
    deciding = [part for part in parts if part.passed is passed] if passed is not True else []
    reason = _sentence(part.reason for part in deciding)
    why = ", and ".join(part.why for part in deciding)
    text = f"{metric} ({form}): {', '.join(part.text for part in parts)}: {_outcome(passed, why)}"
    shortfalls = [part.shortfall for part in deciding if part.shortfall]
    return Check(passed, text, metric, form, requirement, reason, min(shortfalls, default=None))


def _where(task: str) -> str:
    """The task(s) a test is run on, in the paper's words."""
    if task == POOLED:
        return " and ".join(TASK_LABELS[t] for t in UNKNOWN_TASKS) + " pooled"
    return TASK_LABELS.get(task, task)


#: The two forms of every check of H1-H3: the paper's (each participant-condition an
#: independent observation) and the within-subjects one.
FORMS = ("paper", "within")
#: The interaction term of the pooled tasks' test, per form.
INTERACTION = {"paper": ("ancova", "method x task"), "within": ("rm_anova", "method * task")}


def _interaction(stats, hypothesis, metric, form) -> float | None:
    """p of the pooled tasks' method x task term in ``form`` when significant, else None."""
    analysis, term = INTERACTION[form]
    rows = _rows(stats, hypothesis, POOLED, metric, analysis, term=term)
    if rows.empty or not np.isfinite(rows["p"].iloc[0]):
        return None
    p = float(rows["p"].iloc[0])
    return p if p < SIGNIFICANCE else None


def _superiority_parts(stats, means, form, *, hypothesis, task, metric, better, worse):
    """The parts of one form's superiority check on ``task`` (pooled or one task)."""
    direction = _direction(means[metric], better, worse)
    if form == "within":
        rows = _rows(stats, hypothesis, task, metric, "rm_anova", term="method")
        return _in_direction([_significant(rows, "rm_anova")], direction)
    omnibus = "ancova" if task == POOLED else "anova"
    paper = [_significant(_rows(stats, hypothesis, task, metric, omnibus, term="method"), omnibus)]
    tukey = _rows(stats, hypothesis, task, metric, "tukey")
    pair = tukey[tukey["comparison"].isin([f"{better} vs {worse}", f"{worse} vs {better}"])]
    if not tukey.empty:
        paper.append(_significant(pair, f"Tukey {better} vs {worse}"))
    return _in_direction(paper, direction)


def superiority(
    stats, means, *, hypothesis, task, metric, better, worse, task_means=None
) -> list[Check]:
    """``better`` beats ``worse`` on ``metric``: the paper's test, then the within one.

    On the pooled tasks, a form whose method x task interaction is significant
    (:data:`INTERACTION`) is judged by the simple effects of method per task instead
    (``task_means``: the condition means per task): the pooled test averages effects
    that differ by task, and the hypothesis asks about each task.
    """
    keys = {"hypothesis": hypothesis, "metric": metric, "better": better, "worse": worse}
    checks = []
    for form in FORMS:
        p = _interaction(stats, hypothesis, metric, form) if task == POOLED else None
        if p is None or task_means is None:
            parts = _superiority_parts(stats, means, form, task=task, **keys)
            checks.append(_combine(form, metric, parts, _superior_requirement(task, keys)))
            continue
        analysis = INTERACTION[form][0]
        for one in UNKNOWN_TASKS:
            qualified = Part(True, f"{analysis} method x task {p_value(p)}, so {_where(one)}")
            parts = _superiority_parts(stats, task_means[one], form, task=one, **keys)
            requirement = _superior_requirement(one, keys) + (
                " (where method x task is significant, per task)"
            )
            checks.append(_combine(form, metric, [qualified, *parts], requirement))
    return checks


def _superior_requirement(task, keys) -> str:
    better, worse = keys["better"], keys["worse"]
    return (
        f"{better} below {worse} ({_where(task)}): the test at p < {SIGNIFICANCE} and the "
        f"mean of {better} lower"
    )


def _noninferior_flag(value) -> bool | None:
    """The ``noninferior`` cell: a boolean (from analyze_study) or its text (stats.csv)."""
    if value is None or pd.isna(value):
        return None
    if value in (True, "True", "true"):
        return True
    if value in (False, "False", "false"):
        return False
    return None


def level_words(stats: pd.DataFrame) -> str:
    """The non-inferiority level of ``stats`` in words: ``one-sided 95%`` (level .05)."""
    rows = stats[stats["analysis"].astype(str).str.startswith("noninferiority")]
    level = noninferiority_level(rows["note"]) if "note" in rows else None
    return f"one-sided {100 * (1 - (level or PAPER_ALPHA)):g}%"


def noninferiority(stats, *, hypothesis, task, metric, new, reference) -> list[Check]:
    """``new`` not inferior to ``reference``: independent (paper), then paired (within).

    Within subjects, a margin set as a fraction of the reference mean is judged by the
    paired ratio row (``noninferiority_ratio``) when stats.csv has it: the margin is an
    estimate, and the ratio test counts its error.
    """
    requirement = (
        f"{new} not inferior to {reference} ({_where(task)}): the {level_words(stats)} "
        f"upper bound of mean {new} - {reference} below the margin (within subjects, for a "
        "margin that is a fraction of the reference mean: of the ratio of the means)"
    )
    rows = _rows(stats, hypothesis, task, metric, "noninferiority")
    rows = rows[rows["comparison"] == f"{new} vs {reference}"]
    ratios = _rows(stats, hypothesis, task, metric, "noninferiority_ratio")
    ratios = ratios[ratios["comparison"] == f"{new} vs {reference}"]
    checks = []
    for form, paired in (("paper", False), ("within", True)):
        name = f"{metric} {task} non-inferior to {reference} ({form})"
        keys = {"metric": metric, "form": form, "requirement": requirement}
        row = rows[rows["note"].str.contains("paired") == paired]
        ratio = ratios[ratios["note"].str.contains("paired")]
        if paired and not ratio.empty:
            row, name = ratio, f"{name}, ratio"
        if not row.empty and "unbounded" in str(row["note"].iloc[0]):
            # Fieller's bound of a reference mean not above 0: no ratio margin is shown.
            why = "bound not below the margin"
            text = f"{name}: Fieller's bound unbounded: {_outcome(False, why)}"
            checks.append(Check(False, text, **keys, reason=why))
            continue
        if row.empty or not np.isfinite(row["ci_high"].iloc[0]):
            shortfall = _shortfall(row)
            reason = "bound not computed" if shortfall is None else TOO_FEW
            text = f"{name}: bound not computed: {_outcome(None, reason)}"
            checks.append(Check(None, text, **keys, reason=reason, shortfall=shortfall))
            continue
        bound = float(row["ci_high"].iloc[0])
        flag = _noninferior_flag(row["noninferior"].iloc[0])
        if flag is not None:
            margin = float(row["margin"].iloc[0])
            text = f"bound {bound:.3g} at margin {margin:.3g} (stats.csv)"
        elif (task, metric) in PAPER_BOUNDS:
            margin = PAPER_BOUNDS[(task, metric)]
            flag, text = bound < margin, f"bound {bound:.3g} vs the paper's {margin:g}"
        else:
            text = f"{name}: bound {bound:.3g}, no margin: {_outcome(None, 'no margin')}"
            checks.append(Check(None, text, **keys, reason="no margin"))
            continue
        reason = "" if flag else "bound not below the margin"
        why = f"{reason} ({new} may be worse than {reference} by the margin or more)"
        text = f"{name}: {text}: {_outcome(flag, why)}"
        checks.append(Check(flag, text, **keys, reason=reason))
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


def _task_means(trials: pd.DataFrame) -> dict[str, dict[str, pd.Series]]:
    return {task: condition_means(trials, [task]) for task in UNKNOWN_TASKS}


def h2_checks(stats: pd.DataFrame, trials: pd.DataFrame) -> list[Check]:
    """H2: CASA before learning superior to PBA (pooled; per task where method x task is
    significant), not inferior to NA (per task)."""
    stats, means = _text(stats), condition_means(trials, list(UNKNOWN_TASKS))
    per_task = _task_means(trials)
    checks = []
    for metric in METRICS:
        key = {"hypothesis": "H2", "metric": metric}
        checks += superiority(
            stats,
            means,
            **key,
            task=POOLED,
            better=CASA_BEFORE_LEARNING,
            worse="PBA",
            task_means=per_task,
        )
        for task in UNKNOWN_TASKS:
            checks += noninferiority(
                stats, **key, task=task, new=CASA_BEFORE_LEARNING, reference="NA"
            )
    return checks


def h3_checks(stats: pd.DataFrame, trials: pd.DataFrame) -> list[Check]:
    """H3: CASA after learning superior to NA (pooled over the misspecified tasks; per task
    where method x task is significant)."""
    stats, means = _text(stats), condition_means(trials, list(UNKNOWN_TASKS))
    per_task = _task_means(trials)
    checks = []
    for metric in METRICS:
        key = {"hypothesis": "H3", "task": POOLED, "metric": metric}
        checks += superiority(
            stats, means, **key, better=CASA_AFTER_LEARNING, worse="NA", task_means=per_task
        )
    return checks
