"""A replayed trial (``casa replay``): belief, confidence and alpha over time.

Three panels side by side, as a row of the case study (:mod:`.case_study`): the belief
P(theta | xi) in each intent, the confidence ``beta_hat`` in each intent (with the
misspecification threshold ``epsilon`` dotted, when given) and the user's control
authority ``alpha`` the replayed arbitration gives. It takes the replay table alone
(:data:`casa_core.analysis.replay.COLUMNS`).
"""

from __future__ import annotations

import pandas as pd
from matplotlib.figure import Figure

from casa_core.figures import style
from casa_core.figures.case_study import threshold_label
from casa_core.io import tables

#: The columns the figure reads.
COLUMNS = ["t", "intent", "beta", "belief", "alpha"]
#: The columns it reads of the trial's log, for the logged alpha.
LOGGED_COLUMNS = ["t", "alpha"]
#: The legend's words of the two alpha lines.
REPLAYED_LABEL, LOGGED_LABEL = "replayed $\\alpha$", "logged $\\alpha$"


def replay_figure(
    replayed: pd.DataFrame,
    *,
    epsilon: float | None = None,
    title: str | None = None,
    logged: pd.DataFrame | None = None,
    source: str | None = None,
) -> Figure:
    """Draw one replayed trial's belief, confidence and alpha over time.

    Parameters
    ----------
    replayed : DataFrame
        A replay table: one row per inference step and intent.
    epsilon : float, optional
        The misspecification threshold: a dotted line on the confidence panel.
    title : str, optional
        First words of the caption (e.g. the trial and the settings replayed).
    logged : DataFrame, optional
        The trial's log (``t`` and ``alpha``, one row per control tick): its alpha is
        drawn under the replayed one, as logged.
    source : str, optional
        The trial's ``source``; ``"simulated"`` adds :func:`.style.model_note` to the caption.

    Returns
    -------
    Figure
        Three axes (belief, confidence, alpha); a table without rows gives three
        panels with a note. The replayed alpha is held from each step to the next, as
        the arm applies it.

    Examples
    --------
    >>> rows = pd.DataFrame({"t": [0.5, 0.5, 1.0, 1.0], "intent": ["green", "purple"] * 2,
    ...                      "beta": [1.0, 0.5, 2.0, 0.4], "belief": [0.6, 0.4, 0.8, 0.2],
    ...                      "alpha": [1.0, 1.0, 0.5, 0.5]})
    >>> fig = replay_figure(rows, epsilon=1.0)
    >>> [ax.get_title() for ax in fig.axes]
    ['Belief', 'Confidence', 'Arbitration']
    """
    tables.require_columns(replayed, COLUMNS, "replay")
    rows = tables.numeric_columns(replayed.copy(), ["t", "beta", "belief", "alpha"], "replay")
    if logged is not None:
        tables.require_columns(logged, LOGGED_COLUMNS, "trial log")
        logged = tables.numeric_columns(logged[LOGGED_COLUMNS].copy(), LOGGED_COLUMNS, "trial log")
    goals = list(style.GOAL_COLOURS)
    names = sorted(
        rows["intent"].astype(str).unique(),
        key=lambda name: (goals.index(name) if name in goals else len(goals), name),
    )
    colours = style.intent_colours(names)
    with style.context():
        fig = style.new_figure(7.0, 2.3)
        belief_ax, beta_ax, alpha_ax = fig.subplots(1, 3, sharex=True)
        for ax, name in zip(
            (belief_ax, beta_ax, alpha_ax), ("Belief", "Confidence", "Arbitration"), strict=True
        ):
            ax.set_title(name)
        if rows.empty:
            for ax in (belief_ax, beta_ax, alpha_ax):
                style.note_axes(ax, "no inference step\n(the trial is shorter than 0.5 s)")
        else:
            for name in names:
                series = rows[rows["intent"].astype(str) == name].sort_values("t")
                label = style.display_name(name)
                belief_ax.plot(series["t"], series["belief"], color=colours[name], label=label)
                beta_ax.plot(series["t"], series["beta"], color=colours[name], label=label)
            if epsilon is not None:
                beta_ax.axhline(
                    epsilon, color="0.3", lw=0.9, ls=":", label=threshold_label(epsilon)
                )
            top = max(float(rows["beta"].max()), epsilon or 0.0)
            beta_ax.set_ylim(0, 1.12 * top if top > 0 else 1.0)
            belief_ax.set_ylim(-0.03, 1.05)
            _alpha_lines(alpha_ax, rows, logged)
            belief_ax.set_ylabel("Belief $P(\\theta \\mid \\xi)$")
            beta_ax.set_ylabel("Confidence $\\hat\\beta_\\theta$")
            alpha_ax.set_ylabel("Control authority $\\alpha$")
            for ax in (belief_ax, beta_ax, alpha_ax):
                ax.set_xlabel("Time (s)")
            handles, labels = beta_ax.get_legend_handles_labels()
            more = alpha_ax.get_legend_handles_labels()
            handles, labels = handles + more[0], labels + more[1]
            fig.legend(handles, labels, loc="outside upper center", ncols=len(labels))
        style.add_caption(fig, _caption(title, epsilon, logged is not None, source))
    return fig


def _alpha_lines(ax, rows: pd.DataFrame, logged: pd.DataFrame | None) -> None:
    """The replayed alpha, held from step to step, over the log's alpha per tick."""
    if logged is not None and not logged.empty:
        ax.plot(
            logged["t"],
            logged["alpha"],
            color="0.6",
            lw=3.0,
            drawstyle="steps-post",  # each tick's alpha holds until the next tick
            label=LOGGED_LABEL,
            zorder=1,
        )
    steps = rows.groupby("t", sort=True)["alpha"].first()
    ax.plot(
        steps.index,
        steps.to_numpy(),
        color=style.METHOD_COLOURS["CASA"],
        drawstyle="steps-post",
        label=REPLAYED_LABEL if logged is not None else None,
        zorder=2,
    )
    ax.set_ylim(-0.03, 1.05)


def _caption(title: str | None, epsilon: float | None, logged: bool, source) -> str:
    caption = f"{title or 'Replayed trial'}."
    caption += (
        " Inference redone over the logged trajectory: belief and confidence in each"
        " intent, and the user's control authority under the replayed arbitration"
        " (held from each inference step to the next)."
    )
    if logged:
        caption += (
            " Wide grey: the alpha the log holds at each control tick, the authority the"
            " arm applied; the replayed line lies on it where the replay reproduces the"
            " trial."
        )
    if epsilon is not None:
        caption += f" Dotted: the misspecification threshold epsilon = {epsilon:g}."
    note = style.model_note(source)
    return f"{caption} {note}" if note else caption
