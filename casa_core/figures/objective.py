"""The user study's objective metrics (paper, Fig. "study_objective"), and task success.

One column per task, one row per metric: error, efficiency cost, effort relative to
direct teleoperation, and the success rate. Every panel has its own y scale, so the
Known Goal's small errors read as well as the misspecified tasks' large ones. In each,
one bar per condition (NA, PBA, CASA, CASA before / after learning where they apply):
for the metrics the mean and standard error over participants, every participant as a
point (a cross when the trial ran out of time) and significance brackets from the Tukey
HSD rows of the stats table for that task; for success the proportion of trials that
succeeded (:func:`casa_core.analysis.metrics.task_success`) with its Wilson 95 % interval and
the counts.
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from casa_core.defaults import POUR_TILT_TOLERANCE, SIGNIFICANCE, SUCCESS_RADIUS
from casa_core.figures import _bars, style
from casa_core.io import tables
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

#: The trials.csv columns of the trial's outcome: whether it ran out of time (empty when
#: its log does not say its limit) and whether it succeeded.
TIMED_OUT, SUCCESS = "timed_out", "success"
SUCCESS_AXIS = "Success (share of trials)"
#: The legend's words for a trial that ran out of time.
TIMED_OUT_LABEL = "ran out of time"


def effort_unit(trials: pd.DataFrame) -> str:
    """What effort counts in ``trials``: key presses, or a continuous device's presses (an
    axis leaving its deadzone, casa_core.analysis.effort), by the ``input`` column.

    Examples
    --------
    >>> effort_unit(pd.DataFrame({"input": ["keyboard"]})), effort_unit(pd.DataFrame())
    ('key presses', 'key presses')
    >>> effort_unit(pd.DataFrame({"input": ["gamepad", "keyboard"]}))
    'presses of keys or device axes'
    """
    devices = set(trials["input"].dropna()) if "input" in trials else set()
    if devices <= {"keyboard"}:
        return "key presses"
    return (
        "presses of device axes" if "keyboard" not in devices else "presses of keys or device axes"
    )


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
    """Trials of the compared tasks and phases, with their ``condition`` (paper's words).

    The optional columns ``timed_out`` and ``success`` become 1.0 (true), 0.0 (false)
    or NaN (empty, or the column absent); any other value is an error naming the row.
    """
    tables.require_columns(
        trials, ["participant", "task", "method", "phase", *[m for m, _, _ in METRICS]], "trials"
    )
    rows = trials[trials["task"].isin(list(style.SHOWN_TASKS))]
    rows = rows[~rows["phase"].isin(UNANALYSED_PHASES)].copy()
    rows = style.label_conditions(rows, "trials")
    for column in (TIMED_OUT, SUCCESS):
        rows[column] = _flags(rows[column], column) if column in rows else np.nan
    return rows


#: The cells a true/false column may hold: what pandas writes and reads, and JSON's words.
_FLAG_VALUES = {"true": 1.0, "false": 0.0, "1": 1.0, "0": 0.0, "1.0": 1.0, "0.0": 0.0}


def _flags(values: pd.Series, column: str) -> pd.Series:
    """A true/false column as 1.0 / 0.0, NaN where empty."""
    out = []
    for index, value in values.items():
        if value is None or (isinstance(value, float) and np.isnan(value)) or value == "":
            out.append(np.nan)
            continue
        flag = _FLAG_VALUES.get(str(value).strip().lower())
        if flag is None:
            raise ValueError(f"trials row {index}: {column} {value!r} is not true or false")
        out.append(flag)
    return pd.Series(out, index=values.index, dtype=float)


def objective_figure(
    trials: pd.DataFrame,
    stats: pd.DataFrame | None = None,
    title: str | None = None,
    *,
    setup: str | None = None,
) -> Figure:
    """Draw the objective metrics and the success rate of a study.

    Parameters
    ----------
    trials : DataFrame
        ``trials.csv`` (one row per trial; columns ``participant, task, method, phase,
        source, error, efficiency, relative_effort`` and, when present, ``timed_out``
        and ``success``).
    stats : DataFrame, optional
        ``stats.csv``; its Tukey HSD rows (``analysis`` containing "tukey") with
        ``p < 0.05`` become brackets over the two conditions compared, in the panel
        of every task the row covers. For a pair of conditions in a task, the row of
        that task alone wins over a row pooled over several tasks (the ANCOVA's over
        both misspecified tasks); a pooled row drawn is said so in the caption. Rows
        without ``p`` (tests the stats skipped) draw nothing.
    title : str, optional
        First words of the caption (default "Objective metrics"); the caption goes on
        with who the participants are (e.g. "simulated participants") and how many.
    setup : str, optional
        The setup the data come from: the caption's last line (:func:`.style.setup_line`).

    Returns
    -------
    Figure
        A grid of axes: one row per metric of :data:`METRICS`, then success; one column
        per task present, each panel on its own y scale. Tasks the data lack are left
        out, and a caption names them, any missing condition, and how many trials ran
        out of time.
    """
    rows = prepare_trials(trials)
    tasks = [t for t in style.SHOWN_TASKS if t in set(rows["task"])]
    columns: list[Any] = [*tasks] or [None]  # None: one column of every trial
    with style.context():
        fig = style.new_figure(7.0, 1.6 * (len(METRICS) + 1) + 0.7)
        grid = fig.subplots(len(METRICS) + 1, len(columns), squeeze=False)
        notes = _missing_notes(rows, tasks)
        pooled = False
        for (metric, label, stat_names), axes in zip(METRICS, grid, strict=False):
            tukey = tukey_rows(stats, stat_names)
            for ax, task in zip(axes, columns, strict=True):
                in_task = rows[rows["task"] == task]
                points = _bars.participant_means(
                    in_task, ["task", "condition"], metric, flags=[TIMED_OUT]
                )
                if points.empty:
                    style.note_axes(ax, f"no {label.split(' (')[0].lower()} in the data")
                    continue
                if not _bars.drawable(points[metric]):
                    largest = float(points[metric].abs().max())
                    name = label.split(" (")[0].lower()
                    style.note_axes(ax, f"{name} too large to draw\n(up to {largest:.3g})")
                    continue
                tops = _bars.draw_grouped_bars(
                    ax,
                    points,
                    "task",
                    [task],
                    metric,
                    marked=TIMED_OUT,
                    marked_label=TIMED_OUT_LABEL,
                )
                ax.set_ylim(bottom=0)
                if metric == "relative_effort":
                    # Direct teleoperation is 1 by the metric's definition.
                    ax.axhline(1.0, color="0.4", lw=0.6, ls=":", zorder=1)
                brackets, used_pooled = _brackets(tops, tukey)
                pooled |= used_pooled
                _bars.draw_brackets(ax, brackets)
            axes[0].set_ylabel(label.replace("key presses", effort_unit(rows)))
        _draw_success(grid[-1], rows, columns)
        for ax, task in zip(grid[0], columns, strict=True):
            ax.set_title(TASK_LABELS[task] if task else "")
        for ax in grid.flat:
            ax.set_xticks([])
        _bars.condition_legend(fig, grid.flat, extra=[TIMED_OUT_LABEL])
        caption = " ".join([_caption(rows, stats, pooled, title), *notes])
        style.add_setup_caption(fig, caption, setup)
    return fig


def _draw_success(axes, rows: pd.DataFrame, columns: list) -> None:
    """The last row of panels: each column's success rate (a note where none is known)."""
    for ax, task in zip(axes, columns, strict=True):
        in_task = rows[rows["task"] == task]
        if in_task[SUCCESS].isna().all():
            style.note_axes(ax, "no success in the data")
            continue
        _bars.draw_proportions(ax, in_task, SUCCESS)
    axes[0].set_ylabel(SUCCESS_AXIS)


def _caption(rows: pd.DataFrame, stats, pooled: bool, title: str | None) -> str:
    caption = style.describe(title or "Objective metrics", rows)
    caption += (
        " One column per task, each panel on its own y scale."
        " Bars: mean ± standard error over participants; points: participants."
        f" Effort: {effort_unit(rows)} relative to the same participant's NA trial."
        f" Success: the trial ends with the end effector within {SUCCESS_RADIUS * 100:g} cm"
        " of the end of the intended trajectory (pour: and the cup within"
        f" {POUR_TILT_TOLERANCE:g} rad of the pouring tilt), whether or not it ran out of"
        " time; bars: share of trials, whiskers: Wilson 95% interval, k/n: successes/trials."
    )
    caption += " " + _timed_out_sentence(rows)
    if stats is not None:
        caption += (
            " Brackets: Tukey HSD between the conditions of one task, the pairwise"
            " comparisons after that task's one-way ANOVA (stats.csv analysis 'tukey'),"
            " * p < .05, ** p < .01, *** p < .001"
        )
        caption += (
            "; where a task has no test of its own, the test pooled over the misspecified"
            " tasks (after their ANCOVA)."
            if pooled
            else "."
        )
    return caption


def _timed_out_sentence(rows: pd.DataFrame) -> str:
    """How many trials ran out of time, at what limit, and in which task and condition."""
    known = rows.dropna(subset=[TIMED_OUT])
    if known.empty:
        return "The logs do not say their time limit: trials that ran out of time are not marked."
    out = known[known[TIMED_OUT] == 1.0]
    sentence = f"{len(out)} of {len(known)} trials ran out of time"
    if len(out):
        # The trials that ran out stopped at the limit (to within a tick).
        limits = sorted({f"{d:.0f}" for d in out["duration"]}) if "duration" in out else []
        if limits:
            sentence += f" at {' or '.join(limits)} s"
        sentence += ", drawn as crosses"
        parts = []
        for task in style.SHOWN_TASKS:
            counts = []
            for condition in CONDITIONS:
                cell = known[(known["task"] == task) & (known["condition"] == condition)]
                ran_out = int((cell[TIMED_OUT] == 1.0).sum())
                if ran_out:
                    counts.append(f"{condition} {ran_out} of {len(cell)}")
            if counts:
                parts.append(f"{TASK_LABELS[task]}: {', '.join(counts)}")
        sentence += " (" + "; ".join(parts) + ")"
    sentence += "."
    if len(known) < len(rows):
        sentence += f" {len(rows) - len(known)} logs do not say their limit."
    return sentence


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
