"""The paper's claims under each modelling variant: a grid coloured by verdict.

Rows are the claims, columns the variants of ``data/processed/robustness/claims.csv``
(:mod:`casa_core.stats.robustness`); each cell is coloured by its verdict and shows the
number behind it. The default variant's column is framed and labelled.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch, Rectangle

from casa_core.config import DEFAULT_VARIANT
from casa_core.figures import style
from casa_core.io import tables
from casa_core.stats.claims import MODEL_OUTPUT, TOO_FEW, VERDICTS, verdict_kind

#: Verdict -> cell colour (Okabe-Ito: green holds, yellow partly, vermillion differs;
#: greys where the data cannot decide).
VERDICT_COLOURS: dict[str, str] = {
    "holds": "#009E73",
    "partly": "#F0E442",
    "differs": "#D55E00",
    "not testable": "#DDDDDD",
    MODEL_OUTPUT: "#BBBBBB",
    TOO_FEW: "#EEEEEE",
}
COLUMNS = ["claim", "variant", "verdict", "value"]


def verdict_grid(claims: pd.DataFrame) -> tuple[list[str], list[str], np.ndarray, np.ndarray]:
    """Claims, variants, and per cell the verdict's index in :data:`VERDICTS` and the value.

    A cell with no row is -1 (drawn blank). A verdict with its numbers (``not testable:
    too few participants (2, needs 3)``) is its kind (:func:`verdict_kind`); an unknown
    verdict is an error naming it.

    Examples
    --------
    >>> claims = pd.DataFrame({"claim": ["C1", "C1", "H1"], "variant": ["default", "x", "x"],
    ...     "verdict": ["holds", "differs", "partly"], "value": [1.0, 0.2, 0.5]})
    >>> rows, cols, verdicts, values = verdict_grid(claims)
    >>> rows, cols, verdicts.tolist()
    (['C1', 'H1'], ['default', 'x'], [[0, 2], [-1, 1]])
    """
    tables.require_columns(claims, COLUMNS, "robustness claims table")
    for verdict in sorted(set(claims["verdict"])):
        try:
            verdict_kind(verdict)
        except ValueError as error:
            raise ValueError(f"robustness claims table: {error}") from None
    frame = tables.numeric_columns(claims[COLUMNS], ["value"], "robustness claims table")
    rows = list(dict.fromkeys(frame["claim"]))
    cols = list(dict.fromkeys(frame["variant"]))
    verdicts = np.full((len(rows), len(cols)), -1)
    values = np.full((len(rows), len(cols)), np.nan)
    for row in frame.itertuples():
        i, j = rows.index(row.claim), cols.index(row.variant)
        verdicts[i, j] = VERDICTS.index(verdict_kind(row.verdict))
        values[i, j] = row.value
    return rows, cols, verdicts, values


def robustness_figure(claims: pd.DataFrame) -> Figure:
    """Draw claims x variants, each cell coloured by its verdict, the default framed.

    Parameters
    ----------
    claims : pandas.DataFrame
        ``data/processed/robustness/claims.csv``: columns ``claim, variant, verdict,
        value`` at least.

    Returns
    -------
    Figure
        One axes, named ``"grid"`` in ``fig.axes_by_name``.
    """
    rows, cols, verdicts, values = verdict_grid(claims)
    colours = ["#FFFFFF", *VERDICT_COLOURS.values()]  # index -1 (no row) drawn white
    with style.context():
        fig = style.new_figure(1.8 + 1.1 * len(cols), 0.9 + 0.28 * len(rows))
        ax = fig.add_subplot()
        ax.imshow(
            verdicts + 1, cmap=ListedColormap(colours), vmin=0, vmax=len(colours) - 1, aspect="auto"
        )
        for i in range(len(rows)):
            for j in range(len(cols)):
                if verdicts[i, j] >= 0 and not np.isnan(values[i, j]):
                    ax.text(j, i, f"{values[i, j]:.2f}", ha="center", va="center", fontsize=7)
        labels = [f"{c}\n(default)" if c == DEFAULT_VARIANT else c for c in cols]
        ax.set_xticks(range(len(cols)), labels)
        ax.set_yticks(range(len(rows)), rows)
        ax.tick_params(length=0, top=True, labeltop=True, bottom=False, labelbottom=False)
        ax.set_xticks(np.arange(len(cols) + 1) - 0.5, minor=True)
        ax.set_yticks(np.arange(len(rows) + 1) - 0.5, minor=True)
        ax.grid(which="minor", color="white", linewidth=1.5)
        ax.tick_params(which="minor", length=0)
        for spine in ax.spines.values():
            spine.set_visible(False)
        if DEFAULT_VARIANT in cols:
            j = cols.index(DEFAULT_VARIANT)
            ax.add_patch(
                Rectangle(
                    (j - 0.5, -0.5),
                    1,
                    len(rows),
                    fill=False,
                    edgecolor="0.1",
                    lw=1.6,
                    zorder=3,  # above the white grid lines it shares edges with
                    clip_on=False,
                )
            )
        shown = sorted(set(verdicts[verdicts >= 0].tolist()))
        handles = [Patch(facecolor=VERDICT_COLOURS[VERDICTS[k]], label=VERDICTS[k]) for k in shown]
        ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), title="verdict")
        caption = (
            "The paper's claims (rows) judged on the simulated study under each modelling "
            "variant (columns; its setup, layout and teleoperation, as results.md lists it), "
            "the same participants and seeds in each; the number is the share of trials or "
            "checks meeting the claim's criterion."
        )
        if DEFAULT_VARIANT in cols:
            caption += f" Framed: the default variant ({DEFAULT_VARIANT}, the study's config)."
        style.add_caption(fig, caption)
    fig.axes_by_name = {"grid": ax}  # type: ignore[attr-defined]  # our attribute on the Figure
    return fig
