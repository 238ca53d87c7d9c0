"""The user study's Likert scores (paper, Fig. "likert").

Three panels, one per task (Known Goal, Unknown Goal, Unknown Skill); in each, the
three questions (the robot understood, made it effortless, was useful) along the x
axis and one bar per condition with the mean and standard error on the 1-7 scale, and
every participant's answer as a point. Given ``stats.csv``, its H4 rows mark the tests:
brackets for the Holm-corrected Wilcoxon signed-rank tests with p < .05, and the
Friedman test of each question under its name. A significant pair is significant in
either direction, so each bracket says which: ``<`` or ``>`` between its two bars' means,
left to right, and a dashed line where the pair goes against the paper's direction
(CASA, after learning in the misspecified tasks, rated above the other condition).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from casa_core.defaults import SIGNIFICANCE
from casa_core.figures import _bars, style
from casa_core.figures.objective import parse_comparison, stars
from casa_core.io import tables
from casa_core.io.contract import SURVEY_COLUMNS
from casa_core.stats.study import answered_by_model
from casa_core.vocabulary import CASA_AFTER_LEARNING, KNOWN_TASK, QUESTION_LABELS, TASK_LABELS

SCALE = (1, 7)
#: The stats table's analyses the figure shows.
FRIEDMAN, WILCOXON = "friedman", "wilcoxon"
#: Per task, the condition the paper expects to be rated highest (H4's, and Known Goal's
#: CASA): the one the Wilcoxon tests compare with every other.
EXPECTED_HIGHEST = {KNOWN_TASK: "CASA"}
#: A bracket's line: the pair in the paper's direction (or without one), and against it.
WITH_PAPER, AGAINST_PAPER = "-", "--"


def prepare_likert(likert: pd.DataFrame) -> pd.DataFrame:
    """Check ``likert.csv`` rows and add each one's ``condition`` (paper's words).

    Raises
    ------
    ValueError
        Naming the row, if a question is unknown or a score is not an integer 1-7.
    """
    tables.require_columns(likert, SURVEY_COLUMNS, "likert")
    rows = likert[likert["task"].isin(list(style.SHOWN_TASKS))].copy()
    scores = pd.to_numeric(rows["score"], errors="coerce")
    conditions = []
    for index, row in rows.iterrows():
        if row["question"] not in QUESTION_LABELS:
            raise ValueError(
                f"likert row {index}: question {row['question']!r} is not one of "
                f"{', '.join(QUESTION_LABELS)}"
            )
        score = scores[index]
        if pd.isna(score) or not (score == round(score) and SCALE[0] <= score <= SCALE[1]):
            raise ValueError(
                f"likert row {index}: score {row['score']!r} is not an integer "
                f"from {SCALE[0]} to {SCALE[1]}"
            )
        try:
            conditions.append(style.row_condition(str(row["method"]), str(row["phase"])))
        except ValueError as error:
            raise ValueError(f"likert row {index}: {error}") from None
    rows["score"] = scores.astype(float)
    rows["condition"] = conditions
    return rows


def likert_tests(stats: pd.DataFrame | None) -> pd.DataFrame:
    """The Friedman and Wilcoxon rows of ``stats.csv`` (hypothesis H4) that carry a p value.

    Returns
    -------
    DataFrame
        Columns ``analysis`` (``"friedman"`` or ``"wilcoxon"``), ``task``, ``question``,
        ``a``, ``b`` (the two conditions a Wilcoxon row compares; empty for Friedman) and
        ``p`` (for Wilcoxon rows, Holm-adjusted as the stats write it). Skipped tests (no
        p) are left out.

    Raises
    ------
    ValueError
        Naming the stats row, if a comparison is not two conditions or p is not a number.
    """
    columns = ["analysis", "task", "question", "a", "b", "p"]
    if stats is None or stats.empty:
        return pd.DataFrame(columns=columns)
    tables.require_columns(stats, ["analysis", "task", "metric", "comparison", "p"], "stats")
    chosen = stats[stats["analysis"].astype(str).isin([FRIEDMAN, WILCOXON])]
    out = []
    for index, row in chosen.iterrows():
        if pd.isna(row["p"]) or str(row["p"]) == "":
            continue  # a skipped test: its note says why
        p = pd.to_numeric(row["p"], errors="coerce")
        if not np.isfinite(p):
            raise ValueError(f"stats row {index}: p {row['p']!r} is not a number")
        a = b = ""
        if row["analysis"] == WILCOXON:
            try:
                a, b = parse_comparison(row["comparison"])
            except ValueError as error:
                raise ValueError(f"stats row {index}: {error}") from None
        out.append(
            {
                "analysis": str(row["analysis"]),
                "task": str(row["task"]),
                "question": str(row["metric"]),
                "a": a,
                "b": b,
                "p": float(p),
            }
        )
    return pd.DataFrame(out, columns=columns)


def likert_figure(
    likert: pd.DataFrame,
    stats: pd.DataFrame | None = None,
    title: str | None = None,
    *,
    setup: str | None = None,
) -> Figure:
    """Draw the Likert scores of a study.

    Parameters
    ----------
    likert : DataFrame
        ``likert.csv``: one row per participant, task, condition and question, columns
        ``participant, task, method, phase, question, score`` (and ``source``).
    stats : DataFrame, optional
        ``stats.csv``; its ``wilcoxon`` rows with (Holm-adjusted) ``p < .05`` become
        brackets over the two conditions in that task and question, labelled with the
        relation of their means (``<``, ``>``) and the stars, dashed where the pair goes
        against the paper's direction; its ``friedman`` rows are written under each
        question (:func:`likert_tests`).
    title : str, optional
        First words of the caption (default "Likert scores"); answers of simulated
        participants add that they are model output.
    setup : str, optional
        The setup the data come from: the caption's last line (:func:`.style.setup_line`).

    Returns
    -------
    Figure
        Three axes, one per task, each with the questions along x, bars, participants'
        points and the tests' marks; a task without survey rows keeps its panel with a
        note.
    """
    rows = prepare_likert(likert)
    tests = likert_tests(stats)
    questions = list(QUESTION_LABELS)
    with style.context():
        fig = style.new_figure(7.0, 2.3)
        axes = fig.subplots(1, len(style.SHOWN_TASKS), sharey=True)
        for ax, task in zip(axes, style.SHOWN_TASKS, strict=True):
            task_label = TASK_LABELS[task]
            ax.set_title(task_label)
            in_task = rows[rows["task"] == task]
            if in_task.empty:
                style.note_axes(ax, f"no survey answers\nfor {task_label}")
                continue
            points = _bars.participant_means(in_task, ["question", "condition"], "score")
            tops = _bars.draw_grouped_bars(ax, points, "question", questions, "score")
            in_tests = tests[tests["task"] == task]
            ax.set_xticklabels([_question_label(q, in_tests, stats is not None) for q in questions])
            ax.set_ylim(SCALE[0] - 0.3, SCALE[1] + 0.3)
            ax.set_yticks(range(SCALE[0], SCALE[1] + 1))
            means = points.groupby(["question", "condition"], sort=False)["score"].mean()
            brackets, linestyles = _brackets(tops, in_tests, means, _expected_highest(task))
            _bars.draw_brackets(ax, brackets, linestyles)
        for ax in axes:
            if ax.has_data():
                ax.set_ylabel("Likert score (1-7)")
                ax.yaxis.set_tick_params(labelleft=True)
                break
        _bars.condition_legend(fig, axes)
        style.add_setup_caption(fig, _caption(rows, title, stats is not None), setup)
    return fig


def _caption(rows: pd.DataFrame, title: str | None, with_tests: bool) -> str:
    """The figure's caption: what is drawn, from whom, and the tests (``with_tests``)."""
    what = title or "Likert scores"
    if answered_by_model(rows):
        what += (
            " (model output: answers computed by the simulated participants' model,"
            " not people's ratings)"
        )
    caption = style.describe(what, rows)
    caption += (
        " Bars: mean ± standard error over participants of the answer to: the robot"
        " understood how I wanted the task done; made the interaction more effortless;"
        " the assistance was useful (1 = strongly disagree, 7 = strongly agree);"
        " points: participants' answers, spread sideways."
    )
    if with_tests:
        caption += (
            " Stars under each question: Friedman test over the task's conditions (n.s.:"
            f" p ≥ {_p_text(SIGNIFICANCE)}). Brackets:"
            f" Wilcoxon signed-rank tests of {TASK_LABELS[KNOWN_TASK]}'s CASA, and of"
            " CASA after learning in the other tasks, against each other condition,"
            " Holm-corrected over those comparisons per task and question; shown where"
            f" p < {_p_text(SIGNIFICANCE)} (alpha); * p < .05, ** p < .01, *** p < .001;"
            " < or > before the stars: the left bar's mean below or above the right one's;"
            " dashed: against the paper's direction (Known Goal's CASA, or CASA after"
            " learning, rated above the other condition), solid: in it."
        )
    return caption


def _p_text(p: float) -> str:
    """``0.05`` as APA writes it, ``".05"``."""
    return f"{p:g}".removeprefix("0")


def _question_label(question: str, tests: pd.DataFrame, with_tests: bool) -> str:
    """The question's name and, under it, its Friedman test's stars ("n.s.", "no test")."""
    label = QUESTION_LABELS[question]
    if not with_tests:
        return label
    friedman = tests[(tests["analysis"] == FRIEDMAN) & (tests["question"] == question)]
    if friedman.empty:
        return f"{label}\nno test"
    return f"{label}\n{stars(float(friedman['p'].iloc[0])) or 'n.s.'}"


def _expected_highest(task: str) -> str:
    """The condition the paper expects rated highest in ``task`` (:data:`EXPECTED_HIGHEST`)."""
    return EXPECTED_HIGHEST.get(task, CASA_AFTER_LEARNING)


def _relation(left: float, right: float) -> str:
    """``<``, ``>`` or ``=``: the left bar's mean against the right one's."""
    return "<" if left < right else ">" if left > right else "="


def _brackets(
    tops, tests: pd.DataFrame, means: pd.Series, expected: str
) -> tuple[list[tuple[float, float, float, str]], list[str]]:
    """The significant Wilcoxon rows whose two bars are drawn: bracket geometry, line style.

    Each label is the relation of the two bars' means, left to right, then the stars; the
    line is :data:`AGAINST_PAPER` when ``expected`` is one of the pair and not rated above
    the other, else :data:`WITH_PAPER`.
    """
    brackets, linestyles = [], []
    wilcoxon = tests[tests["analysis"] == WILCOXON]
    for row in wilcoxon.itertuples(index=False):
        label = stars(row.p)
        pair = ((row.question, row.a), (row.question, row.b))
        if not label or any(key not in tops for key in pair):
            continue
        (xa, _), (xb, _) = (tops[key] for key in pair)
        left, right = sorted(pair, key=lambda key: tops[key][0])
        x0, x1 = min(xa, xb), max(xa, xb)
        base = max(top for (q, _), (x, top) in tops.items() if q == row.question and x0 <= x <= x1)
        brackets.append((x0, x1, base, f"{_relation(means[left], means[right])} {label}"))
        against = False
        if expected in (row.a, row.b):
            other = row.b if row.a == expected else row.a
            against = not means[(row.question, expected)] > means[(row.question, other)]
        linestyles.append(AGAINST_PAPER if against else WITH_PAPER)
    return brackets, linestyles
