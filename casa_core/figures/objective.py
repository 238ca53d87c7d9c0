"""The user study's objective metrics (paper, Fig. "study_objective").

Three panels: error, efficiency cost and effort relative to direct teleoperation.
Tasks along the x axis; in each, one bar per condition (NA, PBA, CASA, CASA before /
after learning where they apply) with the mean and standard error over participants,
every participant as a point, and significance brackets from the Tukey HSD rows of
the stats table.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from casa_core import tables
from casa_core.figures import _bars, style
from casa_core.vocabulary import (
    CASA_AFTER_LEARNING,
    CASA_BEFORE_LEARNING,
    CONDITIONS,
    TASK_CONDITIONS,
    TASK_LABELS,
    UNANALYSED_PHASES,
    UNKNOWN_TASKS,
)

#: The panels: trials.csv column, axis label (with units), and the names the stats table
#: may give the metric, in order of preference (the paper tests effort as relative effort).
METRICS: tuple[tuple[str, str, tuple[str, ...]], ...] = (
    ("error", "Error (m$^2$)", ("error",)),
    ("efficiency", "Efficiency cost (m$^2$/s$^2$)", ("efficiency",)),
    ("relative_effort", "Effort (key presses / NA)", ("relative_effort", "effort")),
)

#: How the stats table may name a set of tasks pooled in one analysis (the ANCOVA over
#: the two misspecified tasks).
POOLED_TASKS = {
    "misspecified": UNKNOWN_TASKS,
    "unknown": UNKNOWN_TASKS,
    "all": style.SHOWN_TASKS,
}

SIGNIFICANCE = 0.05


def stars(p: float) -> str:
    """The usual star code of a p value: ``***`` < .001, ``**`` < .01, ``*`` < .05, else ``""``."""
    if p < 0.001:
        return "***"
    if p < 0.01:
        return "**"
    if p < SIGNIFICANCE:
        return "*"
    return ""


def _condition_key(text: str) -> str:
    return re.sub(r"[^a-z]+", " ", text.lower()).strip()


#: Condition names as the stats table may spell them -> the figure's condition names.
_CONDITION_ALIASES = {_condition_key(c): c for c in CONDITIONS} | {
    "casa before": CASA_BEFORE_LEARNING,
    "casa after": CASA_AFTER_LEARNING,
    "casa bl": CASA_BEFORE_LEARNING,
    "casa al": CASA_AFTER_LEARNING,
}


def parse_comparison(text: str) -> tuple[str, str]:
    """The two conditions of a Tukey comparison such as ``"CASA - NA"`` or ``"NA vs PBA"``.

    Separators ``" - "``, ``" vs "``, ``" vs. "`` are understood; names as in
    :data:`casa_core.vocabulary.CONDITIONS`, case, underscores and parentheses
    ignored (``"CASA (before learning)"``, ``"casa_before_learning"``).

    Raises
    ------
    ValueError
        If the text is not two known conditions.
    """
    parts = re.split(r"\s+(?:-|–|vs\.?|versus)\s+", str(text).strip())
    if len(parts) != 2:
        raise ValueError(f"comparison {text!r} is not of the form 'A - B' or 'A vs B'")
    names = []
    for part in parts:
        key = _condition_key(part)
        if key not in _CONDITION_ALIASES:
            raise ValueError(
                f"comparison {text!r}: unknown condition {part!r}; "
                f"expected one of {', '.join(CONDITIONS)}"
            )
        names.append(_CONDITION_ALIASES[key])
    return names[0], names[1]


def _tasks_of(value: object) -> tuple[str, ...]:
    """Tasks a stats row covers: one task, a ``+``/``,``-separated list, or a pooled name."""
    if value is None or (isinstance(value, float) and np.isnan(value)) or str(value) == "":
        return style.SHOWN_TASKS
    text = str(value).strip().lower()
    if text in POOLED_TASKS:
        return POOLED_TASKS[text]
    return tuple(t.strip() for t in re.split(r"[+,;]", text) if t.strip())


def tukey_rows(stats: pd.DataFrame | None, metric_names: tuple[str, ...]) -> pd.DataFrame:
    """The Tukey HSD rows of ``stats`` for one metric (first of ``metric_names`` present).

    Returns a frame with columns ``tasks`` (tuple), ``a``, ``b`` (conditions) and ``p``.
    """
    empty = pd.DataFrame(columns=["tasks", "a", "b", "p"])
    if stats is None or stats.empty:
        return empty
    tables.require_columns(stats, ["analysis", "task", "metric", "comparison", "p"], "stats")
    tukey = stats[stats["analysis"].astype(str).str.contains("tukey", case=False)]
    for name in metric_names:
        rows = tukey[tukey["metric"].astype(str) == name]
        if not rows.empty:
            break
    else:
        return empty
    out = []
    for index, row in rows.iterrows():
        if pd.isna(row["p"]):
            continue  # a skipped test (its note says why): no bracket
        try:
            a, b = parse_comparison(row["comparison"])
        except ValueError as error:
            raise ValueError(f"stats row {index}: {error}") from None
        p = pd.to_numeric(row["p"], errors="coerce")
        if not np.isfinite(p):
            raise ValueError(f"stats row {index}: p {row['p']!r} is not a number")
        out.append({"tasks": _tasks_of(row["task"]), "a": a, "b": b, "p": float(p)})
    return pd.DataFrame(out, columns=["tasks", "a", "b", "p"])


def prepare_trials(trials: pd.DataFrame) -> pd.DataFrame:
    """Trials of the compared tasks and phases, with their ``condition`` (paper's words)."""
    tables.require_columns(
        trials, ["participant", "task", "method", "phase", *[m for m, _, _ in METRICS]], "trials"
    )
    rows = trials[trials["task"].isin(list(style.SHOWN_TASKS))]
    rows = rows[~rows["phase"].isin(UNANALYSED_PHASES)].copy()
    rows = style.label_conditions(rows, "trials")
    return rows


def objective_figure(
    trials: pd.DataFrame, stats: pd.DataFrame | None = None, title: str | None = None
) -> Figure:
    """Draw the objective metrics of a study.

    Parameters
    ----------
    trials : DataFrame
        ``trials.csv`` (one row per trial; columns ``participant, task, method, phase,
        source, error, efficiency, relative_effort``, ...).
    stats : DataFrame, optional
        ``stats.csv``; its Tukey HSD rows (``analysis`` containing "tukey") with
        ``p < 0.05`` become brackets over the two conditions compared, in every task the
        row covers. For a pair of conditions in a task, the row of that task alone wins
        over a row pooled over several tasks (the ANCOVA's over both misspecified
        tasks); a pooled row drawn is said so in the caption. Rows without ``p`` (tests
        the stats skipped) draw nothing.
    title : str, optional
        First words of the caption (default "Objective metrics"); the caption goes on
        with who the participants are (e.g. "simulated participants") and how many.

    Returns
    -------
    Figure
        Three axes (error, efficiency cost, relative effort), tasks along x. Tasks the
        data lack are left out, and a caption names them and any missing condition.
    """
    rows = prepare_trials(trials)
    tasks = [t for t in style.SHOWN_TASKS if t in set(rows["task"])]
    with style.context():
        fig = style.new_figure(7.0, 2.5)
        axes = fig.subplots(1, len(METRICS))
        notes = _missing_notes(rows, tasks)
        pooled = False
        for ax, (metric, label, stat_names) in zip(axes, METRICS, strict=True):
            points = _bars.participant_means(rows, ["task", "condition"], metric)
            if points.empty:
                style.note_axes(ax, f"no {label.split(' (')[0].lower()} in the data")
                continue
            tops = _bars.draw_grouped_bars(ax, points, "task", tasks, metric)
            ax.set_xticklabels([TASK_LABELS[t].replace(" ", "\n") for t in tasks])
            ax.set_ylabel(label)
            ax.set_ylim(bottom=0)
            if metric == "relative_effort":
                # Direct teleoperation is 1 by the metric's definition.
                ax.axhline(1.0, color="0.4", lw=0.6, ls=":", zorder=1)
            brackets, used_pooled = _brackets(tops, tukey_rows(stats, stat_names))
            pooled |= used_pooled
            _bars.draw_brackets(ax, brackets)
        _bars.condition_legend(fig, axes)
        caption = style.describe(title or "Objective metrics", rows)
        caption += (
            " Bars: mean ± standard error over participants; points: participants."
            " Effort: key presses relative to the same participant's NA trial."
        )
        if stats is not None:
            caption += " Brackets: Tukey HSD, * p < .05, ** p < .01, *** p < .001"
            caption += " (pooled over the tasks of the analysis)." if pooled else "."
        style.add_caption(fig, " ".join([caption, *notes]))
    return fig


def _brackets(tops, tukey: pd.DataFrame) -> tuple[list[tuple[float, float, float, str]], bool]:
    """Bracket geometry for the significant Tukey rows whose conditions are drawn.

    A row of one task wins over a row pooled over several tasks for the same pair of
    conditions in that task (the stats table has both for the misspecified tasks).
    """
    chosen: dict[tuple[str, frozenset], tuple[int, float]] = {}
    for row in tukey.itertuples(index=False):
        for task in row.tasks:
            key = (task, frozenset((row.a, row.b)))
            if key not in chosen or len(row.tasks) < chosen[key][0]:
                chosen[key] = (len(row.tasks), row.p)
    brackets = []
    pooled = False
    for (task, pair), (n_tasks, p) in chosen.items():
        label = stars(p)
        if not label or len(pair) != 2 or any((task, c) not in tops for c in pair):
            continue
        xa, xb = (tops[(task, c)][0] for c in pair)
        x0, x1 = min(xa, xb), max(xa, xb)
        base = max(top for (t, _), (x, top) in tops.items() if t == task and x0 <= x <= x1)
        brackets.append((x0, x1, base, label))
        pooled |= n_tasks > 1
    return brackets, pooled


def _missing_notes(rows: pd.DataFrame, tasks: list[str]) -> list[str]:
    """Sentences naming the tasks and conditions the data lack."""
    notes = []
    absent = [TASK_LABELS[t] for t in style.SHOWN_TASKS if t not in tasks]
    if absent:
        notes.append(f"No trials for {', '.join(absent)}.")
    expected = TASK_CONDITIONS
    for task in tasks:
        have = set(rows.loc[rows["task"] == task, "condition"])
        lacking = [c for c in expected[task] if c not in have]
        if lacking:
            notes.append(f"{TASK_LABELS[task]}: no {', '.join(lacking)}.")
    return notes
