"""Arbitration methods compared along the unknown-goal trajectory (paper, Fig. "alpha_methods").

Left: the robot's belief ``P(goal | trajectory)`` (top) and confidence ``beta_hat``
(bottom) in each known goal over time, while tracking the optimal trajectory to the
unknown goal. Right: the human's control authority ``alpha`` under the distance
(PBA), belief and confidence (CASA) arbitration schemes.
"""

from __future__ import annotations

from typing import Any

import pandas as pd
from matplotlib.figure import Figure

from casa_core.figures import style
from casa_core.io import tables

#: alpha column of arbitration.csv -> (legend label, colour, line style). The distance and
#: confidence schemes take the colours of their methods (PBA, CASA).
ARBITRATIONS: dict[str, tuple[str, str, str]] = {
    "alpha_distance": ("distance (PBA)", style.METHOD_COLOURS["PBA"], "--"),
    "alpha_belief": ("belief", "#CC79A7", "-."),
    "alpha_confidence": ("confidence (CASA)", style.METHOD_COLOURS["CASA"], "-"),
}

COLUMNS = ["t", "intent", "belief", "beta", *ARBITRATIONS]


def prepare_arbitration(arbitration: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Split ``arbitration.csv`` into per-intent series and the per-time alphas.

    Returns
    -------
    per_intent : DataFrame
        ``t, intent, belief, beta``, sorted by intent and time.
    alphas : DataFrame
        One row per ``t`` with the three alpha columns.

    Raises
    ------
    ValueError
        If a column is missing, a value is not a number, or the alphas of one time
        differ between intents' rows (they are properties of the time, not the intent).
    """
    tables.require_columns(arbitration, COLUMNS, "arbitration")
    frame = tables.numeric_columns(
        arbitration[COLUMNS], ["t", "belief", "beta", *ARBITRATIONS], "arbitration"
    )
    alphas = frame.groupby("t", sort=True)[list(ARBITRATIONS)]
    spread = (alphas.max() - alphas.min()).max(axis=1)
    if (spread > 1e-9).any():
        t = spread[spread > 1e-9].index[0]
        raise ValueError(
            f"arbitration: at t = {t} the alpha columns differ between intents' rows; "
            "each time has one alpha per scheme"
        )
    per_intent = frame[["t", "intent", "belief", "beta"]].sort_values(["intent", "t"])
    return per_intent, alphas.first().reset_index()


def arbitration_figure(
    arbitration: pd.DataFrame,
    epsilon: float | None = None,
    title: str | None = None,
    *,
    setup: str | None = None,
) -> Figure:
    """Draw belief, confidence and the three arbitrations' alpha over time.

    Parameters
    ----------
    arbitration : DataFrame
        ``data/processed/case_study/arbitration.csv``: one row per time and known
        intent, columns ``t, intent, belief, beta, alpha_distance, alpha_belief,
        alpha_confidence``.
    epsilon : float, optional
        The confidence threshold of misspecification; drawn as a dotted line on the
        confidence axes when given (it is a setting of the run, not in the table).
    title : str, optional
        First words of the caption.
    setup : str, optional
        The setup the data come from: the caption's last line (:func:`.style.setup_line`).

    Returns
    -------
    Figure
        Axes ``"belief"`` and ``"confidence"`` (left, shared time axis) and ``"alpha"``
        (right); the axes are also reachable by these names as ``fig.axes_by_name``.
        The arbitrations' legend stands beside the alpha axes, clear of the curves.
    """
    per_intent, alphas = prepare_arbitration(arbitration)
    colours = style.intent_colours(per_intent["intent"].unique())
    with style.context():
        fig = style.new_figure(7.0, 2.8)
        axes = fig.subplot_mosaic([["belief", "alpha"], ["confidence", "alpha"]], sharex=True)
        for intent, series in per_intent.groupby("intent", sort=True):
            kwargs: dict[str, Any] = {"color": colours[intent]}
            kwargs["label"] = style.display_name(str(intent))
            axes["belief"].plot(series["t"], series["belief"], **kwargs)
            axes["confidence"].plot(series["t"], series["beta"], **kwargs)
        axes["belief"].set_ylabel("Belief $P(\\theta \\mid \\xi)$")
        axes["belief"].set_ylim(-0.03, 1.03)
        axes["belief"].tick_params(labelbottom=False)
        # Mid-height on the right: the beliefs settle at 0 and 1 there.
        axes["belief"].legend(loc="center right")
        axes["confidence"].set_ylabel("Confidence $\\hat\\beta_\\theta$")
        axes["confidence"].set_xlabel("Time (s)")
        # Room for the threshold when the confidences stay below it (misspecification).
        top = max(float(per_intent["beta"].max()), epsilon or 0.0)
        axes["confidence"].set_ylim(0, 1.15 * top if top > 0 else 1.0)
        if epsilon is not None:
            axes["confidence"].axhline(epsilon, color="0.3", lw=0.7, ls=":")
            axes["confidence"].annotate(
                f"$\\epsilon$ = {epsilon:g}",
                (1.0, epsilon),
                xycoords=("axes fraction", "data"),
                ha="right",
                va="bottom",
                fontsize=7,
                color="0.3",
            )
        for column, (label, colour, dashes) in ARBITRATIONS.items():
            axes["alpha"].plot(alphas["t"], alphas[column], color=colour, ls=dashes, label=label)
        axes["alpha"].set_ylabel("Human's control authority $\\alpha$")
        axes["alpha"].set_xlabel("Time (s)")
        axes["alpha"].set_ylim(-0.03, 1.05)
        # Beside the axes, not on them: inside, "best" lands on the CASA curve.
        axes["alpha"].legend(
            title="arbitration",
            loc="center left",
            bbox_to_anchor=(1.02, 0.5),
            title_fontsize=7.5,
            alignment="left",
        )
        caption = (title or "Arbitration methods along the optimal Unknown Goal trajectory") + "."
        caption += (
            " Left: belief and confidence in each known goal; right: the user's control"
            " authority under distance, belief and confidence arbitration."
        )
        if epsilon is not None:
            caption += f" Dotted: the misspecification threshold epsilon = {epsilon:g}."
        style.add_setup_caption(fig, caption, setup)
    fig.axes_by_name = axes  # type: ignore[attr-defined]  # our attribute on the Figure
    return fig
