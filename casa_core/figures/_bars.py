"""Grouped bars with mean, standard error and every participant as a point.

Shared by the objective and Likert figures: groups (tasks or questions) along the x
axis, one bar per condition inside each group.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from casa_core.figures import style
from casa_core.vocabulary import CONDITIONS


def participant_means(
    frame: pd.DataFrame, keys: Sequence[str], value: str, *, flags: Sequence[str] = ()
) -> pd.DataFrame:
    """One row per participant and ``keys``: the mean of ``value`` over their trials.

    A participant who repeated a condition contributes one point, so each participant
    weighs the same in the bar's mean and standard error. Each column of ``flags``
    (1.0 true, 0.0 false, NaN unknown) becomes its maximum over those trials: a point is
    flagged when any of its trials is.

    Examples
    --------
    >>> trials = pd.DataFrame({"task": ["a", "a", "a"], "participant": ["p1", "p1", "p2"],
    ...                        "error": [1.0, 3.0, 5.0], "timed_out": [0.0, 1.0, 0.0]})
    >>> participant_means(trials, ["task"], "error", flags=["timed_out"]).values.tolist()
    [['a', 'p1', 2.0, 1.0], ['a', 'p2', 5.0, 0.0]]
    """
    rows = frame.dropna(subset=[value])
    grouped = rows.groupby([*keys, "participant"], as_index=False, sort=False)
    return grouped.agg(**{value: (value, "mean")}, **{flag: (flag, "max") for flag in flags})


#: Beyond this magnitude matplotlib's axis margins and tick labels overflow to infinity.
LARGEST_DRAWN = 1e300


def drawable(values) -> bool:
    """Whether ``values``, their means and standard errors fit a linear axis (all finite).

    Examples
    --------
    >>> drawable([0.5, 2.0]), drawable([1e200, 3e200]), drawable([1e308, 1e308])
    (True, False, False)
    """
    values = np.asarray(values, dtype=float)
    if values.size == 0:
        return True
    with np.errstate(over="ignore"):
        # Bounds every group's sum of squared deviations, hence its standard error.
        squares = np.square(np.ptp(values)) * values.size
    return bool(np.abs(values).max() <= LARGEST_DRAWN and np.isfinite(squares))


def wilson_interval(successes: int, trials: int, *, z: float = 1.959964) -> tuple[float, float]:
    """The Wilson score interval of a proportion ``successes / trials`` (95 % by default).

    ``(p + z^2/2n -+ z sqrt(p(1 - p)/n + z^2/4n^2)) / (1 + z^2/n)`` with ``p = k / n``
    (Wilson, 1927): unlike the normal interval it stays inside [0, 1] and does not
    shrink to a point at 0 or n successes.

    Examples
    --------
    All 11 of 11: the lower end is ``n / (n + z^2)``.

    >>> [round(v, 4) for v in wilson_interval(11, 11)]
    [0.7412, 1.0]
    >>> [round(v, 4) for v in wilson_interval(7, 11)]
    [0.3538, 0.8483]
    """
    if trials <= 0:
        return float("nan"), float("nan")
    p = successes / trials
    scale = 1 + z**2 / trials
    centre = (p + z**2 / (2 * trials)) / scale
    half = z / scale * np.sqrt(p * (1 - p) / trials + z**2 / (4 * trials**2))
    # The interval holds p exactly (0 of n starts at 0, n of n ends at 1); rounding may
    # leave it a hair off, which the error bar would draw as a negative length.
    low, high = min(p, centre - half), max(p, centre + half)
    return float(max(0.0, low)), float(min(1.0, high))


def mean_se(values: np.ndarray) -> tuple[float, float]:
    """Mean and standard error ``sd / sqrt(n)`` (``sd`` with ``n - 1``; 0 for one value)."""
    values = np.asarray(values, dtype=float)
    if values.size == 0:
        return float("nan"), float("nan")
    if values.size == 1:
        return float(values[0]), 0.0
    return float(values.mean()), float(values.std(ddof=1) / np.sqrt(values.size))


def draw_grouped_bars(
    ax,
    points: pd.DataFrame,
    group: str,
    groups: Sequence[str],
    value: str,
    width: float = 0.8,
    show_points: bool = True,
    *,
    marked: str | None = None,
    marked_label: str = "marked",
) -> dict[tuple[str, str], tuple[float, float]]:
    """Draw one bar per (group, condition) with its standard error and participants' points.

    Parameters
    ----------
    ax : matplotlib Axes
    points : DataFrame
        One row per participant, with columns ``group``, ``condition``, ``participant``
        and ``value`` (see :func:`participant_means`).
    group : str
        Column whose values are placed along the x axis, in the order ``groups``.
    groups : sequence of str
        Groups to draw, left to right; a group without rows keeps its slot, empty.
    value : str
        Column of the bar heights.
    width : float
        Width of a whole group on the x axis (a group slot is 1 wide).
    show_points : bool
        Draw every participant as a point over the bar.
    marked : str, optional
        Column of ``points`` (1.0 where true): those participants are drawn as black
        crosses instead of open circles, with the legend label ``marked_label``.
    marked_label : str
        The marked points' label (:func:`condition_legend` shows it after the conditions).

    Returns
    -------
    dict
        ``(group, condition) -> (x centre, top of the bar's data)``, where the top is the
        highest of the error bar and the points: where a bracket may start.
    """
    present = [c for c in CONDITIONS if c in set(points["condition"])]
    # Room for four bars (the misspecified tasks' conditions) in every group, so bars keep
    # one width across panels and figures, also when a dataset has fewer conditions.
    bar_width = width / max(4, _max_conditions_per_group(points, group))
    tops: dict[tuple[str, str], tuple[float, float]] = {}
    for gx, name in enumerate(groups):
        in_group = points[points[group] == name]
        conditions = [c for c in present if c in set(in_group["condition"])]
        offsets = (np.arange(len(conditions)) - (len(conditions) - 1) / 2) * bar_width
        for offset, condition in zip(offsets, conditions, strict=True):
            rows = in_group[in_group["condition"] == condition]
            values = rows[value].to_numpy(dtype=float)
            mean, se = mean_se(values)
            x = gx + offset
            _draw_bar(ax, x, mean, se, bar_width, condition)
            if not show_points:
                tops[(name, condition)] = (x, mean + se)
                continue
            _draw_points(ax, rows, values, x, bar_width, marked, marked_label)
            tops[(name, condition)] = (x, float(np.nanmax([mean + se, *values])))
    ax.set_xticks(range(len(groups)))
    ax.set_xlim(-0.5, len(groups) - 0.5)
    return tops


def _draw_bar(ax, x: float, mean: float, se: float, bar_width: float, condition: str) -> None:
    """Draw one condition's bar at ``x``, in its colour, with its standard error."""
    colour = style.METHOD_COLOURS[condition]
    ax.bar(
        x,
        mean,
        bar_width * 0.9,
        color=colour,
        edgecolor="0.15",
        linewidth=0.5,
        label=condition,
        zorder=2,
    )
    ax.errorbar(x, mean, yerr=se, color="0.1", capsize=2, elinewidth=0.9, capthick=0.9, zorder=4)


def _draw_points(
    ax,
    rows: pd.DataFrame,
    values: np.ndarray,
    x: float,
    bar_width: float,
    marked: str | None,
    marked_label: str,
) -> None:
    """Draw the participants' ``values`` over the bar at ``x``; the marked ones as crosses."""
    # Participants spread evenly (no random jitter) across half the bar, in
    # participant order so the same participant sits at the same place.
    order = np.argsort(rows["participant"].astype(str).to_numpy(), kind="stable")
    spread = np.linspace(-0.22, 0.22, len(values)) if len(values) > 1 else np.zeros(1)
    xs, ys = x + spread * bar_width, values[order]
    flagged = np.zeros(len(values), dtype=bool)
    if marked is not None:
        flagged = rows[marked].to_numpy(dtype=float)[order] == 1.0
    ax.scatter(
        xs[~flagged],
        ys[~flagged],
        s=6,
        facecolor="white",
        edgecolor="0.1",
        linewidth=0.5,
        zorder=5,
    )
    if flagged.any():
        ax.scatter(
            xs[flagged],
            ys[flagged],
            s=16,
            marker="X",
            color="black",
            edgecolor="white",
            linewidth=0.3,
            zorder=5,
            label=marked_label,
        )


def _max_conditions_per_group(points: pd.DataFrame, group: str) -> int:
    counts = points.groupby(group)["condition"].nunique()
    return int(counts.max()) if len(counts) else 1


#: How far (x axis units; a group slot is 1) bracket ends stay from the bar centres.
BRACKET_INSET = 0.03
#: Room (x axis units) kept free beside a bracket for the stars of its neighbour.
LABEL_ROOM = 0.1


def draw_brackets(
    ax,
    brackets: Sequence[tuple[float, float, float, str]],
    linestyles: Sequence[str] | None = None,
) -> None:
    """Draw significance brackets ``(x_left, x_right, base, label)`` stacked without overlap.

    ``base`` is the data height above which the bracket must sit (the highest data under
    it); a bracket overlapping narrower ones along x sits one step above them. The step
    is 9 % of the y range. ``linestyles``, one per bracket (default solid), lets a
    figure tell kinds of brackets apart.
    """
    if not brackets:
        return
    low, high = ax.get_ylim()
    step = 0.09 * (high - low)
    placed: list[tuple[float, float, float]] = []
    styles = list(linestyles) if linestyles is not None else ["-"] * len(brackets)
    widths = [(x1 - x0, x0) for x0, x1, _, _ in brackets]
    for index in sorted(range(len(brackets)), key=widths.__getitem__):
        (x0, x1, base, label), linestyle = brackets[index], styles[index]
        # Narrow brackets first; a wider one goes above every bracket it overlaps.
        # Brackets that meet at a bar count as overlapping: their stars would collide.
        near = [py for px0, px1, py in placed if px0 <= x1 + LABEL_ROOM and x0 <= px1 + LABEL_ROOM]
        above = [py + step for py in near]
        y = max([base + 0.5 * step, *above])
        placed.append((x0, x1, y))
        tick = 0.25 * step
        # Ends pulled in a little, so brackets sharing a bar do not touch.
        x0, x1 = x0 + BRACKET_INSET, x1 - BRACKET_INSET
        ys = [y - tick, y, y, y - tick]
        ax.plot([x0, x0, x1, x1], ys, color="0.1", lw=0.7, linestyle=linestyle, zorder=6)
        ax.text((x0 + x1) / 2, y, label, ha="center", va="bottom", fontsize=7, zorder=6)
    top = max(y for _, _, y in placed) + step
    if top > high:
        ax.set_ylim(low, top)


def condition_legend(fig, axes, *, extra: Sequence[str] = (), ncols: int | None = None) -> None:
    """One legend above the panels with every condition drawn, in the style's order.

    ``extra`` names other labelled artists (e.g. marked points) to list after the
    conditions when drawn; ``ncols`` defaults to one row.
    """
    handles: dict = {}
    for ax in axes:
        for handle, name in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(name, handle)
    order = [c for c in (*CONDITIONS, *extra) if c in handles]
    fig.legend(
        [handles[c] for c in order],
        order,
        loc="outside upper center",
        ncols=ncols or max(1, len(order)),
        handlelength=1.0,
        columnspacing=1.2,
    )


def draw_proportions(ax, rows: pd.DataFrame, value: str, width: float = 0.8) -> None:
    """One bar per condition: the proportion of ``rows`` whose ``value`` is true.

    ``rows`` are trials of one group with a ``condition`` column and ``value`` as 1.0
    (true) or 0.0 (false); NaN rows are left out. Each bar has its Wilson 95 % interval
    (:func:`wilson_interval`) and the counts ``k/n`` above it; bars sit where
    :func:`draw_grouped_bars` puts them, so the panels of one figure line up.
    """
    rows = rows.dropna(subset=[value])
    present = [c for c in CONDITIONS if c in set(rows["condition"])]
    bar_width = width / max(4, len(present))
    offsets = (np.arange(len(present)) - (len(present) - 1) / 2) * bar_width
    for offset, condition in zip(offsets, present, strict=True):
        flags = rows.loc[rows["condition"] == condition, value].to_numpy(dtype=float)
        k, n = int(flags.sum()), len(flags)
        low, high = wilson_interval(k, n)
        share = k / n
        ax.bar(
            offset,
            share,
            bar_width * 0.9,
            color=style.METHOD_COLOURS[condition],
            edgecolor="0.15",
            linewidth=0.5,
            label=condition,
            zorder=2,
        )
        ax.errorbar(
            offset,
            share,
            yerr=[[share - low], [high - share]],
            color="0.1",
            capsize=2,
            elinewidth=0.9,
            capthick=0.9,
            zorder=4,
        )
        ax.text(offset, high + 0.03, f"{k}/{n}", ha="center", va="bottom", fontsize=6)
    ax.set_xticks([0])
    ax.set_xlim(-0.5, 0.5)
    ax.set_ylim(0, 1.22)
    ax.set_yticks([0, 0.25, 0.5, 0.75, 1.0])
