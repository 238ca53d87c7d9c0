"""Small helpers shared by the statistics modules (input checks: :mod:`casa_core.io.tables`).

Two kinds of trouble are kept apart on purpose:

* malformed input (a missing column, text where numbers belong) is a caller's mistake and
  raises ``ValueError`` naming the column or row and the rule broken;
* degenerate data (too few observations, a missing condition, zero variance) is a fact about
  the study, so the public functions return their usual table with NaN statistics and a
  ``note`` saying why the test was skipped.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd

from casa_core.io.tables import numeric_column, require_columns

#: Relative size below which a sum of squares counts as zero (floating-point noise).
ZERO_SS = 1e-12


class Skipped(Exception):
    """Raised inside an analysis when the data cannot support the test; the message says why."""


def equal_to_rounding(values) -> bool:
    """Whether the values are all equal to rounding (a billionth of their size).

    Statistics of such values are ratios of rounding errors (an F of 4.2 from values equal
    to 15 digits), so the analyses skip them as zero variance.
    """
    values = np.asarray(values, dtype=float)
    return float(np.ptp(values)) <= 1e-9 * float(np.abs(values).max())


def require_representable(values, dv: str) -> None:
    """Raise :class:`Skipped` when the sum of squares of ``values`` overflows double precision.

    Values of 1e154 and beyond (valid numbers, e.g. the error of a trial far out of the
    workspace) give infinite sums of squares, and every F, t or chi-square from them is NaN.
    """
    values = np.asarray(values, dtype=float)
    with np.errstate(over="ignore", invalid="ignore"):
        total = np.sum(np.square(values - values.mean())) if values.size else 0.0
    if not np.isfinite(total):
        largest = float(np.abs(values).max())
        raise Skipped(
            f"values of {dv!r} too large (up to {largest:.3g}): their sum of squares overflows "
            "double precision"
        )


def levels(series: pd.Series) -> list:
    """Distinct values of ``series`` in a stable order: category order, else sorted."""
    if isinstance(series.dtype, pd.CategoricalDtype):
        present = set(series.dropna())
        return [c for c in series.cat.categories if c in present]
    return sorted(series.dropna().unique(), key=str)


def clean(data: pd.DataFrame, dv: str, factors: Sequence[str], what: str) -> pd.DataFrame:
    """A copy with ``dv`` as float and rows lacking ``dv`` or any factor dropped."""
    require_columns(data, [dv, *factors], what)
    out = data[[dv, *factors]].copy()
    out[dv] = numeric_column(data, dv, what)
    out = out.dropna(subset=[dv, *factors])
    for factor in factors:
        # An absent level must not become an all-zero dummy column in a model.
        if isinstance(out[factor].dtype, pd.CategoricalDtype):
            out[factor] = out[factor].cat.remove_unused_categories()
    return out


def skipped_row(columns: Sequence[str], note: str, **known) -> pd.DataFrame:
    """A one-row table with NaN statistics, the given known values and ``note``."""
    row: dict[str, Any] = {column: np.nan for column in columns}
    row.update(known)
    row["note"] = note
    return pd.DataFrame([row], columns=[*columns, "note"])


def complete_cells(frame, dv, within, subject):
    """Cell means per subject, keeping only subjects who have every cell; and a note."""
    cells = frame.groupby([subject, *within], observed=True)[dv].mean().reset_index()
    n_cells = int(np.prod([len(levels(frame[w])) for w in within]))
    counts = cells.groupby(subject, observed=True)[dv].count()
    keep = counts.index[counts == n_cells]
    note = ""
    if len(keep) < len(counts):
        note = f"{len(counts) - len(keep)} participant(s) with missing conditions dropped"
    return cells[cells[subject].isin(keep)], note


def no_error_variance(cells, dv, factors, subject) -> bool:
    """Whether the participants' and the cells' means explain every cell mean (to rounding).

    The error terms of a repeated-measures ANOVA are the participant-by-condition
    interactions; when they vanish, pingouin's F is a ratio of rounding errors.
    """
    wide = cells.pivot_table(index=subject, columns=factors, values=dv, observed=True)
    values = wide.to_numpy(dtype=float)
    grand = values.mean()
    residual = values - values.mean(axis=1, keepdims=True) - values.mean(axis=0) + grand
    total = ((values - grand) ** 2).sum()
    return bool((residual**2).sum() <= 1e-12 * total)


def participants_needed(frame, factors) -> int:
    """The fewest participants with every condition a repeated-measures ANOVA is computed
    with: 2, and more than every term's degrees of freedom (:func:`require_more_participants`).

    >>> participants_needed(pd.DataFrame({"method": ["NA", "PBA", "CASA"]}), ["method"])
    3
    """
    dfs = [len(levels(frame[factor])) - 1 for factor in factors]
    if len(factors) == 2:
        dfs.append(dfs[0] * dfs[1])
    return max(2, *(df + 1 for df in dfs))


def require_more_participants(frame, factors, terms, n: int) -> None:
    """Raise :class:`Skipped` unless ``n`` exceeds every term's degrees of freedom.

    The sphericity test and the Greenhouse-Geisser epsilon estimate the covariance of a
    term's contrasts, singular with ``n <= df`` participants (pingouin divides by zero
    at 2 participants and 3 conditions).
    """
    dfs = [len(levels(frame[factor])) - 1 for factor in factors]
    if len(factors) == 2:
        dfs.append(dfs[0] * dfs[1])
    for term, df in zip(terms, dfs, strict=True):
        if n <= df:
            raise Skipped(
                f"needs more participants with every condition than the {df} degrees of "
                f"freedom of {term!r} (sphericity), got {n}"
            )


#: The skip notes that say a test needs more participants (:func:`require_more_participants`
#: and the "needs at least M participants" of the other analyses), read back by
#: :func:`participants_shortfall`.
_MORE_THAN_DF = re.compile(
    r"needs more participants with every condition than the (\d+) degrees of freedom of "
    r"'[^']*' \(sphericity\), got (\d+)"
)
_AT_LEAST = re.compile(r"needs at least (\d+) participants[^,;]*, got (\d+)")


def participants_shortfall(note: str) -> tuple[int, int] | None:
    """``(got, needed)`` when a skip ``note`` says the test needs more participants, else None.

    ``needed`` is the fewest participants the analysis computes the test with: one more
    than a term's degrees of freedom (:func:`require_more_participants`), or the number a
    "needs at least" note names.

    Examples
    --------
    >>> participants_shortfall("needs more participants with every condition than the 2 "
    ...     "degrees of freedom of 'method' (sphericity), got 2; relative effort is 1")
    (2, 3)
    >>> participants_shortfall("needs at least 2 participants with both conditions, got 1")
    (1, 2)
    >>> participants_shortfall("zero variance") is None
    True
    """
    found = _MORE_THAN_DF.search(str(note))
    if found:
        return int(found[2]), int(found[1]) + 1
    found = _AT_LEAST.search(str(note))
    return (int(found[2]), int(found[1])) if found else None


def as_list(factors: str | Sequence[str]) -> list[str]:
    """One factor name or several, as a list."""
    return [factors] if isinstance(factors, str) else list(factors)
