"""The expert case study (paper, Fig. "case_study").

One row per task. Left: the confidence ``beta_hat`` in each intent over time with the
robot's intents before learning (for Known Goal, its only run). Middle: the same after
learning, for the misspecified tasks. Right: the human's control authority ``alpha``
over time under PBA and CASA (before and after learning). The misspecification
threshold ``epsilon``, when given, is a dotted line on the confidence panels. Intents
and the participant are named by :func:`casa_core.figures.style.display_name`.
"""

from __future__ import annotations

import pandas as pd
from matplotlib.figure import Figure

from casa_core.figures import style
from casa_core.io import tables
from casa_core.io.contract import CASE_STEPS_COLUMNS
from casa_core.vocabulary import TASK_LABELS

#: Which condition's run fills the confidence panels.
BEFORE = ("CASA", "CASA before learning")
AFTER = "CASA after learning"
#: Series of the alpha panel, in legend order, with their line styles.
ALPHA_SERIES: dict[str, str] = {
    "PBA": "--",
    "CASA": "-",
    "CASA before learning": "-",
    "CASA after learning": "-",
}


def prepare_steps(steps: pd.DataFrame, participant: str | None = None) -> tuple[pd.DataFrame, str]:
    """One participant's steps of the three tasks, with each row's ``condition``.

    Parameters
    ----------
    steps : DataFrame
        ``steps.csv``.
    participant : str, optional
        Whose runs to draw; by default the only one, or the first in sorted order.

    Returns
    -------
    (DataFrame, str)
        The rows and the participant's name.

    Raises
    ------
    ValueError
        If a column is missing, the participant is absent, a value is not a number, or
        one run has two rows for the same time and intent.
    """
    # The figure draws every column but the distance.
    drawn = [column for column in CASE_STEPS_COLUMNS if column != "distance"]
    tables.require_columns(steps, drawn, "steps")
    names = sorted(steps["participant"].astype(str).unique())
    if not names:
        raise ValueError("steps: the table has no rows")
    participant = names[0] if participant is None else str(participant)
    if participant not in names:
        raise ValueError(f"steps: no rows for participant {participant!r}; have {names}")
    rows = steps[steps["participant"].astype(str) == participant]
    rows = rows[rows["task"].isin(list(style.SHOWN_TASKS))].copy()
    rows = tables.numeric_columns(rows, ["t", "alpha", "beta", "belief"], "steps")
    rows = style.label_conditions(rows, "steps")
    twice = rows.duplicated(["task", "condition", "t", "intent"], keep=False)
    if twice.any():
        index = twice.idxmax()
        row = rows.loc[index]
        raise ValueError(
            f"steps row {index}: participant {participant!r}, {row['task']}, "
            f"{row['condition']} has two rows for t = {row['t']} and intent {row['intent']!r}"
        )
    return rows, participant


def case_study_figure(
    steps: pd.DataFrame,
    participant: str | None = None,
    epsilon: float | None = None,
    title: str | None = None,
    *,
    setup: str | None = None,
) -> Figure:
    """Draw confidence and arbitration over time for each task of the case study.

    Parameters
    ----------
    steps : DataFrame
        ``steps.csv``: one row per (tick, intent), columns ``participant, task, method,
        phase, t, alpha, intent, beta, belief`` (and ``distance``, not drawn).
    participant : str, optional
        Whose runs to draw (the case study has one expert); default: the first.
    epsilon : float, optional
        The misspecification threshold (``case_study.epsilon`` of the configuration):
        a dotted line on the confidence panels, named in the legend and the caption.
    title : str, optional
        First words of the caption.
    setup : str, optional
        The setup the data come from: the caption's last line (:func:`.style.setup_line`).

    Returns
    -------
    Figure
        A grid of axes, one row per task present and three columns (confidence before
        learning, confidence after learning, alpha); ``fig.axes_grid[task]`` maps each
        task to its three axes. One legend above the panels names the intents (and the
        threshold); each alpha panel has its own beside it. Panels without data carry a
        note.
    """
    rows, participant = prepare_steps(steps, participant)
    tasks = [t for t in style.SHOWN_TASKS if t in set(rows["task"])]
    if not tasks:
        raise ValueError(f"steps: participant {participant!r} has no rows of a study task")
    colours = style.intent_colours(rows["intent"].dropna().astype(str).unique())
    with style.context():
        fig = style.new_figure(7.0, 1.75 * len(tasks) + 0.5)
        grid = fig.subplots(len(tasks), 3, squeeze=False, sharex="row")
        axes_grid = {}
        for r, task in enumerate(tasks):
            in_task = rows[rows["task"] == task]
            before, after, alpha_ax = grid[r]
            axes_grid[task] = (before, after, alpha_ax)
            before_run = in_task[in_task["condition"].isin(BEFORE)]
            after_run = in_task[in_task["condition"] == AFTER]
            top = max(
                [float(run["beta"].max()) for run in (before_run, after_run) if len(run)]
                + [epsilon or 0.0]
            )
            for ax, run, what in ((before, before_run, "before"), (after, after_run, "after")):
                if run.empty:
                    reason = (
                        "no misspecification:\nnothing to learn"
                        if task == "known_goal" and what == "after"
                        else f"no CASA run {what} learning"
                    )
                    style.note_axes(ax, reason)
                    continue
                _confidence_panel(ax, run, colours, epsilon, 1.12 * top if top > 0 else 1.0)
            _alpha_panel(alpha_ax, in_task)
            before.annotate(
                TASK_LABELS[task],
                (0.0, 0.5),
                xycoords="axes fraction",
                # Left of the tick labels and the y label, whatever the axes' width.
                xytext=(-50, 0),
                textcoords="offset points",
                rotation=90,
                ha="center",
                va="center",
                fontweight="bold",
            )
        titles = ("Before learning", "After learning", "Arbitration")
        for ax, name in zip(grid[0], titles, strict=True):
            ax.set_title(name)
        for ax in grid[-1]:
            if ax.has_data():
                ax.set_xlabel("Time (s)")
        _intent_legend(fig, grid[:, :2].ravel())
        style.add_setup_caption(fig, _caption(rows, participant, epsilon, title), setup)
    fig.axes_grid = axes_grid  # type: ignore[attr-defined]  # our attribute on the Figure
    return fig


def _confidence_panel(ax, run: pd.DataFrame, colours, epsilon, top: float) -> None:
    # The paper's goals first, in its order, then other (learned) intents by name.
    goals = list(style.GOAL_COLOURS)
    order = sorted(
        run["intent"].astype(str).unique(),
        key=lambda name: (goals.index(name) if name in goals else len(goals), name),
    )
    for intent in order:
        series = run[run["intent"].astype(str) == intent].sort_values("t")
        ax.plot(
            series["t"],
            series["beta"],
            color=colours[str(intent)],
            label=style.display_name(str(intent)),
        )
    if epsilon is not None:
        ax.axhline(epsilon, color="0.3", lw=0.9, ls=":", label=threshold_label(epsilon))
    ax.set_ylim(0, top)
    ax.set_ylabel("Confidence $\\hat\\beta_\\theta$")


def threshold_label(epsilon: float) -> str:
    """Legend words of the threshold line: ``"threshold ε = 1"``."""
    return f"threshold $\\epsilon$ = {epsilon:g}"


def _intent_legend(fig, axes) -> None:
    """One legend above the panels: every intent drawn, then the threshold."""
    handles: dict[str, object] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, handle)
    if handles:
        # The threshold last, after the intents in the panels' order.
        order = sorted(handles, key=lambda label: label.startswith("threshold"))
        fig.legend(
            [handles[label] for label in order],
            order,
            loc="outside upper center",
            ncols=len(order),
            handlelength=1.6,
        )


def _caption(rows: pd.DataFrame, participant: str, epsilon, title) -> str:
    # "simulated": the data says so when steps carry a source.
    sources = sorted(set(rows["source"].dropna().astype(str))) if "source" in rows else []
    who = " ".join([" and ".join(sources), style.display_name(participant)]).strip()
    caption = f"{title or 'Case study'}, {who}."
    if participant in style.PARTICIPANT_NAMES:
        caption += (
            " A simulated operator with expert settings (short delay, little noise, no"
            " lapses) that holds the keys along each task's intended path."
        )
    caption += (
        " Confidence in each intent the robot knows, before and after learning the new"
        " intent, and the user's control authority under PBA and CASA."
    )
    if epsilon is not None:
        caption += (
            f" Dotted: the misspecification threshold epsilon = {epsilon:g}; a CASA trial"
            " flags misspecification when every known intent's confidence stays below it"
            " over the trial's last seconds."
        )
    return caption


def _alpha_panel(ax, in_task: pd.DataFrame) -> None:
    drawn = 0
    for condition, dashes in ALPHA_SERIES.items():
        run = in_task[in_task["condition"] == condition]
        if run.empty:
            continue
        # alpha belongs to the tick; every intent's row of a tick repeats it.
        series = run.groupby("t", sort=True)["alpha"].first()
        ax.plot(
            series.index,
            series.to_numpy(),
            color=style.METHOD_COLOURS[condition],
            ls=dashes,
            label=condition,
        )
        drawn += 1
    if not drawn:
        style.note_axes(ax, "no PBA or CASA run")
        return
    ax.set_ylim(-0.03, 1.05)
    ax.set_ylabel("Control authority $\\alpha$")
    # Beside the panel: inside, it would hide the curves that end low or high.
    ax.legend(loc="center left", bbox_to_anchor=(1.02, 0.5), handlelength=1.6)
