"""Small helpers shared by the statistics modules (input checks: :mod:`casa_core.tables`).

Two kinds of trouble are kept apart on purpose:

* malformed input (a missing column, text where numbers belong) is a caller's mistake and
  raises ``ValueError`` naming the column or row and the rule broken;
* degenerate data (too few observations, a missing condition, zero variance) is a fact about
  the study, so the public functions return their usual table with NaN statistics and a
  ``note`` saying why the test was skipped.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from casa_core.tables import numeric_column, require_columns


class Skipped(Exception):
    """Raised inside an analysis when the data cannot support the test; the message says why."""


def equal_to_rounding(values) -> bool:
    """Whether the values are all equal to rounding (a billionth of their size).

    Statistics of such values are ratios of rounding errors (an F of 4.2 from values equal
    to 15 digits), so the analyses skip them as zero variance.
    """
    values = np.asarray(values, dtype=float)
    return float(np.ptp(values)) <= 1e-9 * float(np.abs(values).max())


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
    row = {column: np.nan for column in columns}
    row.update(known)
    row["note"] = note
    return pd.DataFrame([row], columns=[*columns, "note"])
