"""The CSV text pandas writes for a plain table, without pandas' writer.

``DataFrame.to_csv(index=False, lineterminator="\\n")`` turns each float column into
text with numpy's ``astype(str)`` (the shortest repr that reads back to the same
number; missing values as empty fields), then hands the rows to Python's ``csv``
writer, which quotes nothing that holds no comma, quote or line end. For a table of
float, integer and plain-text columns :func:`plain_csv_text` does the same two steps
directly, with Python's ``repr`` for the floats (the same text); for any other table
it returns None and the caller asks pandas.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

_SPECIAL = (",", '"', "\n", "\r")


def _plain(text) -> bool:
    """Whether ``text`` is a str that the csv writer writes as it is (no quotes)."""
    return type(text) is str and not any(c in text for c in _SPECIAL)


def _column_text(values: np.ndarray) -> list[str] | None:
    """A column's fields as pandas writes them, or None for a column it would treat apart."""
    if values.dtype == np.float64:
        # Python's repr is numpy's str of a float64 (the shortest round-trip digits, the
        # same switch to exponents at 1e-4 and 1e16), at half the cost.
        text = list(map(repr, values.tolist()))
        for i in np.flatnonzero(np.isnan(values)).tolist():
            text[i] = ""
        return text
    if values.dtype == np.int64:
        return values.astype(str).tolist()
    if values.dtype == object and all(_plain(v) for v in values):
        return values.tolist()
    return None


def plain_csv_text(frame: pd.DataFrame) -> str | None:
    """``frame.to_csv(index=False, lineterminator="\\n")``'s text, or None (module docstring).

    Examples
    --------
    >>> plain_csv_text(pd.DataFrame({"t": [0.0, 0.05], "keys": ["x+", ""]}))
    't,keys\\n0.0,x+\\n0.05,\\n'
    >>> plain_csv_text(pd.DataFrame({"t": [0.0], "keys": ["a,b"]})) is None  # to be quoted
    True
    """
    names = list(frame.columns)
    # One column (an empty field is quoted then), no rows, or names to quote: pandas' way.
    if len(names) < 2 or len(frame) == 0 or not all(_plain(n) and n for n in names):
        return None
    columns = []
    for i in range(len(names)):
        column = frame.iloc[:, i]
        if not isinstance(column.dtype, (np.dtype, pd.StringDtype)):
            return None  # categorical, nullable numbers, dates...
        text = _column_text(column.to_numpy())
        if text is None:
            return None
        columns.append(text)
    rows = [",".join(row) for row in zip(*columns, strict=True)]
    return ",".join(names) + "\n" + "\n".join(rows) + "\n"
