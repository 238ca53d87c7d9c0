"""Checks across the rows of a trial's time series: the control tick and the beliefs.

Helpers of :mod:`casa_core.io.validation`; the rules are ``docs/data-contracts.md``'s
time rule (``t-start``, ``tick-rate``, ``tick-irregular``) and ``belief-sum``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from casa_core.io._cells import where_lines
from casa_core.io.contract import BELIEF_SUM_TOLERANCE, TICK, TICK_TOLERANCE
from casa_core.io.problems import Problem


def check_ticks(t: pd.Series, file: str, problems: list) -> None:
    """``t-start``, ``tick-rate`` (errors) and ``tick-irregular`` (a warning)."""
    # Float rounding of t as written (e.g. 0.15000000000000002) is far below this.
    slack = TICK * TICK_TOLERANCE + 1e-9
    finite = t[np.isfinite(t.to_numpy())]
    if len(finite) and finite.iloc[0] > TICK + 1e-9:
        problems.append(
            Problem(
                file,
                f"column 't', line {finite.index[0]}",
                "t-start",
                f"the first tick is at {finite.iloc[0]!r} s; t counts seconds since the "
                f"trial started, from 0 (within one {TICK:g} s tick)",
            )
        )
    steps = finite.diff().iloc[1:]
    if not len(steps):
        return
    median = float(steps.median())
    if abs(median - TICK) > slack:
        problems.append(
            Problem(
                file,
                "column 't'",
                "tick-rate",
                f"the median step between rows is {median:g} s; expected the control tick "
                f"{TICK:g} s (20 Hz) within {TICK_TOLERANCE:.0%} (t in seconds, one row per tick)",
            )
        )
        return
    off = (steps - TICK).abs() > slack
    if off.any():
        problems.append(
            Problem(
                file,
                f"column 't', {where_lines(off)}",
                "tick-irregular",
                f"{int(off.sum())} step(s) from the previous row are not {TICK:g} s within "
                f"{TICK_TOLERANCE:.0%}, e.g. {float(steps[off].iloc[0]):g} s",
                "warning",
            )
        )


def check_belief_sum(frame: pd.DataFrame, file: str, problems: list) -> None:
    """``belief-sum``: the ``belief:NAME`` of a row are a distribution over the intents."""
    beliefs = [c for c in frame.columns if c.partition(":")[0] == "belief"]
    if not beliefs:
        return
    values = frame[beliefs]
    total = values.sum(axis=1)
    bad = np.isfinite(values.to_numpy()).all(axis=1) & ((total - 1.0).abs() > BELIEF_SUM_TOLERANCE)
    if bad.any():
        problems.append(
            Problem(
                file,
                f"columns {', '.join(beliefs)}, {where_lines(bad)}",
                "belief-sum",
                f"the beliefs of a row must sum to 1 (within {BELIEF_SUM_TOLERANCE:g}), "
                f"got {float(total[bad].iloc[0])!r}",
            )
        )
