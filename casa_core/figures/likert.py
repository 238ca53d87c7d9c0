"""The user study's Likert scores (paper, Fig. "likert").

Three panels, one per task (Known Goal, Unknown Goal, Unknown Skill); in each, the
three questions (the robot understood, made it effortless, was useful) along the x
axis and one bar per condition with the mean and standard error on the 1-7 scale.
"""

from __future__ import annotations

import pandas as pd
from matplotlib.figure import Figure

from casa_core import tables
from casa_core.figures import _bars, style
from casa_core.vocabulary import QUESTION_LABELS, TASK_LABELS

SCALE = (1, 7)


def prepare_likert(likert: pd.DataFrame) -> pd.DataFrame:
    """Check ``likert.csv`` rows and add each one's ``condition`` (paper's words).

    Raises
    ------
    ValueError
        Naming the row, if a question is unknown or a score is not an integer 1-7.
    """
    tables.require_columns(
        likert, ["participant", "task", "method", "phase", "question", "score"], "likert"
    )
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


def likert_figure(likert: pd.DataFrame, title: str | None = None) -> Figure:
    """Draw the Likert scores of a study.

    Parameters
    ----------
    likert : DataFrame
        ``likert.csv``: one row per participant, task, condition and question, columns
        ``participant, task, method, phase, question, score`` (and ``source``).
    title : str, optional
        First words of the caption (default "Likert scores").

    Returns
    -------
    Figure
        Three axes, one per task, each with the questions along x; a task without
        survey rows keeps its panel with a note.
    """
    rows = prepare_likert(likert)
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
            _bars.draw_grouped_bars(ax, points, "question", questions, "score", show_points=False)
            ax.set_xticklabels([QUESTION_LABELS[q] for q in questions])
            ax.set_ylim(SCALE[0], SCALE[1] + 0.2)
            ax.set_yticks(range(SCALE[0], SCALE[1] + 1))
        for ax in axes:
            if ax.has_data():
                ax.set_ylabel("Likert score (1-7)")
                ax.yaxis.set_tick_params(labelleft=True)
                break
        _bars.condition_legend(fig, axes)
        caption = style.describe(title or "Likert scores", rows)
        caption += (
            " Bars: mean ± standard error over participants of the answer to: the robot"
            " understood how I wanted the task done; made the interaction more effortless;"
            " the assistance was useful (1 = strongly disagree, 7 = strongly agree)."
        )
        style.add_caption(fig, caption)
    return fig
