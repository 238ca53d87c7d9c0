"""The posterior predictive check of `casa calibrate`: people beside the fitted operators.

One panel per summary (:data:`casa_core.calibration.summaries.SUMMARIES` in the table's
order); along each, the task-method cells. A bar spans the fitted model's central 90%
interval with a tick at its median; the dot is the people's mean, filled where it lies
inside the interval. Cells that were not fitted (the hold-out) have hatched bars.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from casa_core.figures import style
from casa_core.io import tables
from casa_core.vocabulary import TASK_LABELS

COLUMNS = ["task", "method", "summary", "fitted", "people", "simulated_median"]
COLUMNS += ["simulated_low", "simulated_high", "inside"]


def predictive_figure(table: pd.DataFrame, *, title: str = "") -> Figure:
    """The figure of a posterior predictive table (module docstring)."""
    tables.require_columns(table, COLUMNS, "posterior predictive table")
    summaries = list(dict.fromkeys(table["summary"]))
    cells = list(dict.fromkeys(zip(table["task"], table["method"], strict=True)))
    labels = [f"{TASK_LABELS.get(task, task)}\n{method}" for task, method in cells]
    with style.context():
        columns = 3
        rows = -(-len(summaries) // columns)
        fig = style.new_figure(7.0, 2.0 * rows + 0.4)
        axes = fig.subplots(rows, columns, squeeze=False).ravel()
        for ax, name in zip(axes, summaries, strict=False):
            part = table[table["summary"] == name]
            for x, (task, method) in enumerate(cells):
                row = part[(part["task"] == task) & (part["method"] == method)].iloc[0]
                colour = style.METHOD_COLOURS.get(method, "0.5")
                ax.bar(
                    x,
                    row.simulated_high - row.simulated_low,
                    bottom=row.simulated_low,
                    width=0.6,
                    color=colour,
                    alpha=0.35,
                    hatch=None if row.fitted else "///",
                    edgecolor=colour,
                )
                ax.plot([x - 0.3, x + 0.3], [row.simulated_median] * 2, color=colour)
                ax.plot(
                    x,
                    row.people,
                    "o",
                    color="black",
                    markerfacecolor="black" if row.inside else "white",
                    markersize=4,
                )
            ax.set_title(name.replace("_", " "), fontsize=8)
            ax.set_xticks(range(len(cells)), labels, fontsize=5.5, rotation=90)
        for ax in axes[len(summaries) :]:
            ax.set_visible(False)
        style.add_caption(
            fig,
            f"{title}. Bars: the fitted operators' 90% posterior predictive interval "
            "(tick: median; hatched: not fitted, predicted). Dots: the people's mean "
            "(open: outside the interval).",
        )
    return fig


def plot_predictive(table: pd.DataFrame, path: Path | str, *, title: str = "") -> Path:
    """Write the figure of a posterior predictive table as one PNG at ``path``."""
    path = Path(path)
    fig = predictive_figure(table, title=title)
    # save_figure writes prefix.png; the caller's path may be a temporary name.
    with style.context():
        fig.savefig(path, format="png", bbox_inches="tight", dpi=style.PNG_DPI)
    return path


RECOVERY_COLUMNS = ["parameter", "datasets", "coverage", "shrinkage"]


def recovery_figure(table: pd.DataFrame, *, level: float = 0.9, title: str = "") -> Figure:
    """Parameter recovery: coverage of the intervals and shrinkage, per parameter.

    The coverage panel marks the nominal ``level`` and the band in which 95% of coverages
    over as many datasets fall when the intervals are exact (binomial).
    """
    from scipy.stats import binom

    tables.require_columns(table, RECOVERY_COLUMNS, "parameter recovery table")
    names = [name.replace("_", " ") for name in table["parameter"]]
    n = int(table["datasets"].iloc[0])
    band = np.asarray(binom.ppf([0.025, 0.975], n, level)) / n
    low, high = float(band[0]), float(band[1])
    with style.context():
        fig = style.new_figure(7.0, 2.4)
        cover, shrink = fig.subplots(1, 2)
        cover.axhspan(low, high, color="0.9")
        cover.axhline(level, color="0.4", linewidth=0.8)
        cover.bar(range(len(names)), table["coverage"], color="#0072B2", width=0.6)
        cover.set_ylim(0, 1.02)
        cover.set_ylabel(f"coverage of the {level:.0%} intervals")
        shrink.bar(range(len(names)), table["shrinkage"], color="#009E73", width=0.6)
        shrink.set_ylim(min(0.0, float(table["shrinkage"].min())), 1.0)
        shrink.set_ylabel("shrinkage (1 - posterior / prior variance)")
        for ax in (cover, shrink):
            ax.set_xticks(range(len(names)), names, rotation=45, ha="right")
        style.add_caption(
            fig,
            f"{title}. {n} synthetic datasets with known medians. Grey band: where 95% of "
            f"coverages over {n} datasets fall for exact intervals.",
        )
    return fig
