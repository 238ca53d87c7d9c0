"""The processed tables: :func:`read_table` with their values intact, and the input checks
for the tidy tables that statistics and figures take (pandas only).

A malformed table (a missing column, text where numbers belong) is a caller's mistake:
these raise ``ValueError`` naming the table, the column, the row and the rule broken.

Examples
--------
>>> import pandas as pd
>>> trials = pd.DataFrame({"error": ["0.1", "high"]})
>>> try:
...     numeric_column(trials, "error", "trials table")
... except ValueError as error:
...     print(error)
trials table: column 'error', row 1: 'high' is not a number
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd


def require_columns(data: pd.DataFrame, columns: Sequence[str], what: str) -> None:
    """Raise ``ValueError`` naming every column of ``columns`` missing from ``data``.

    Examples
    --------
    >>> require_columns(pd.DataFrame({"t": [0.0]}), ["t", "alpha"], "steps")
    Traceback (most recent call last):
    ...
    ValueError: steps: missing column(s) 'alpha' (columns present: ['t'])
    """
    if not isinstance(data, pd.DataFrame):
        raise ValueError(f"{what}: data must be a pandas DataFrame, got {type(data).__name__}")
    missing = [column for column in columns if column not in data.columns]
    if missing:
        names = ", ".join(repr(column) for column in missing)
        raise ValueError(
            f"{what}: missing column(s) {names} (columns present: {list(data.columns)})"
        )


def numeric_column(data: pd.DataFrame, column: str, what: str) -> pd.Series:
    """``data[column]`` as floats; empty cells stay missing, other text or inf is an error.

    Examples
    --------
    >>> numeric_column(pd.DataFrame({"beta": ["1.5", None]}), "beta", "steps").tolist()
    [1.5, nan]
    """
    values = pd.to_numeric(data[column], errors="coerce")
    bad = values.isna() & data[column].notna()
    if bad.any():
        row = bad.idxmax()
        raise ValueError(
            f"{what}: column {column!r}, row {row}: {data[column][row]!r} is not a number"
        )
    infinite = np.isinf(values.to_numpy(dtype=float))
    if infinite.any():
        row = values.index[infinite][0]
        raise ValueError(f"{what}: column {column!r}, row {row}: value is infinite")
    return values.astype(float)


def numeric_columns(data: pd.DataFrame, columns: Sequence[str], what: str) -> pd.DataFrame:
    """A copy of ``data`` with each of ``columns`` as floats (:func:`numeric_column`).

    Examples
    --------
    >>> numeric_columns(pd.DataFrame({"t": ["0", "0.5"]}), ["t"], "steps")["t"].tolist()
    [0.0, 0.5]
    """
    data = data.copy()
    for column in columns:
        data[column] = numeric_column(data, column, what)
    return data


def read_table(path: Path | str) -> pd.DataFrame:
    """Read a processed table (trials, steps, likert, validation) with its values intact.

    pandas' defaults would read the method ``"NA"`` as missing and a participant
    ``"007"`` as the number 7; here only empty cells are missing and identifying
    columns stay text.

    Parameters
    ----------
    path : path or file-like
        A CSV written by :func:`casa_core.analysis.datasets.write_tables` or
        :func:`~casa_core.analysis.datasets.write_validation`.

    Returns
    -------
    pandas.DataFrame

    Examples
    --------
    >>> import io
    >>> table = read_table(io.StringIO("participant,method,score\\n007,NA,5\\n008,,\\n"))
    >>> table["participant"].tolist(), table["method"].tolist()
    (['007', '008'], ['NA', nan])
    """
    text_columns = {c: str for c in ("dataset", "participant", "trial", "intent", "file")}
    return pd.read_csv(path, dtype=text_columns, keep_default_na=False, na_values=[""])
