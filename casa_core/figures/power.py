"""Simulated power against the number of participants, per hypothesis and metric.

Drawn from ``data/processed/power/power.csv`` (:func:`casa_core.stats.power.power_table`):
a panel per hypothesis (rows) and metric (columns); a line per variant (colour) and
analysis (solid: the paper's form, dashed: within subjects), with the Wilson 95 %
interval as error bars; the 80 % line and the paper's N. Given the configuration that
built the table, the caption ends with it on a line of its own.
"""

from __future__ import annotations

from typing import Any

import pandas as pd
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from casa_core.figures import style
from casa_core.io import tables
from casa_core.stats.power import ANALYSES, METRICS, PAPER_N, POWER_COLUMNS

#: The conventional target power.
TARGET = 0.8
LINESTYLES: dict[str, Any] = {"paper": "-", "within": "--"}
#: Okabe-Ito colours, one per variant in the table's order.
COLOURS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000")


def power_figure(power: pd.DataFrame, *, provenance: str = "") -> Figure:
    """Draw power against N: hypotheses as rows, metrics as columns.

    Parameters
    ----------
    power : pandas.DataFrame
        ``power.csv``: columns :data:`casa_core.stats.power.POWER_COLUMNS`.
    provenance : str, optional
        The configuration that built the table (:meth:`casa_core.config.Provenance.line`),
        the caption's last line.

    Returns
    -------
    Figure
        Its panels are named ``"H1 error"`` ... in ``fig.axes_by_name``.
    """
    tables.require_columns(power, POWER_COLUMNS, "power table")
    frame = tables.numeric_columns(power, ["N", "power", "ci_low", "ci_high"], "power table")
    hypotheses = sorted(frame["hypothesis"].unique())
    metrics = [m for m in METRICS if m in set(frame["metric"])]
    variants = list(dict.fromkeys(frame["variant"]))
    colours = {v: COLOURS[i % len(COLOURS)] for i, v in enumerate(variants)}
    sizes = sorted(frame["N"].unique())
    replicates = sorted(frame["replicates"].unique())
    with style.context():
        fig = style.new_figure(2.2 * max(len(metrics), 1) + 0.6, 1.7 * max(len(hypotheses), 1))
        grid = fig.subplots(len(hypotheses), len(metrics), squeeze=False, sharex=True, sharey=True)
        named = {}
        for i, hypothesis in enumerate(hypotheses):
            for j, metric in enumerate(metrics):
                ax = grid[i][j]
                named[f"{hypothesis} {metric}"] = ax
                part = frame[(frame["hypothesis"] == hypothesis) & (frame["metric"] == metric)]
                _panel(ax, part, colours, dodge=_dodges(frame, variants))
                if i == 0:
                    ax.set_title(style.display_name(metric))
                if j == 0:
                    ax.set_ylabel(f"{hypothesis}\npower")
                if i == len(hypotheses) - 1:
                    ax.set_xlabel("participants N")
        for ax in named.values():
            ax.set_ylim(-0.03, 1.03)
            ax.set_xticks(sizes)
        first = grid[0][0]
        first.text(PAPER_N, 1.0, f"paper: N = {PAPER_N} ", color="0.45", fontsize=6.5,
                   va="top", ha="right")  # fmt: skip
        handles = [Line2D([], [], color=colours[v], label=v) for v in variants]
        handles += [
            Line2D([], [], color="0.3", linestyle=LINESTYLES[a], label=f"{a} form")
            for a in ANALYSES
        ]
        fig.legend(handles=handles, loc="outside right upper")
        counts = ", ".join(str(int(r)) for r in replicates)
        style.add_caption(
            fig,
            f"Share of simulated replicate studies ({counts} per point) in which the "
            "hypothesis is detected on the metric (docs/power.md), with Wilson 95% "
            f"intervals; dotted: {TARGET:.0%} power; grey line: the paper's N = {PAPER_N}. "
            "The effects are the model's, not people's.",
            f"{provenance}." if provenance else "",
        )
    fig.axes_by_name = named  # type: ignore[attr-defined]  # our attribute on the Figure
    return fig


def _dodges(frame: pd.DataFrame, variants: list[str]) -> dict:
    """A small shift along N per variant and analysis, so that their error bars part."""
    lines = [(v, a) for v in variants for a in ANALYSES]
    span = max(float(frame["N"].max()), PAPER_N) - min(float(frame["N"].min()), PAPER_N)
    step = 0.012 * (span or 1.0)
    return {line: (k - (len(lines) - 1) / 2) * step for k, line in enumerate(lines)}


def _panel(ax, part: pd.DataFrame, colours: dict, *, dodge: dict) -> None:
    ax.axhline(TARGET, color="0.5", linestyle=":", linewidth=0.9)
    ax.axvline(PAPER_N, color="0.8", linewidth=3, zorder=0)
    for (variant, analysis), line in part.groupby(["variant", "analysis"], sort=False):
        line = line.sort_values("N")
        ax.errorbar(
            line["N"] + dodge.get((variant, analysis), 0.0),
            line["power"],
            yerr=[line["power"] - line["ci_low"], line["ci_high"] - line["power"]],
            color=colours[variant],
            linestyle=LINESTYLES.get(analysis, "-."),
            marker="o",
            markersize=3,
            capsize=2,
            elinewidth=0.7,
        )
