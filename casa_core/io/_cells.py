"""CSV text as a table of string cells indexed by line number, and checks on its columns.

The helpers of :mod:`casa_core.io.validation`: each check appends a
:class:`~casa_core.io.problems.Problem` naming the column and the lines (line 1 is the
header, as an editor shows the file) instead of stopping at the first bad cell.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable, Sequence

import numpy as np
import pandas as pd

from casa_core.io.problems import Problem

#: Delimiters a CSV is sometimes written with instead of ',' (by spreadsheets, by hand).
OTHER_DELIMITERS = (";", "\t")
# At most this many line numbers are spelled out per (column, rule); the rest are counted.
MAX_LINES_LISTED = 10


def where_lines(mask: pd.Series) -> str:
    """The lines where ``mask`` is true, e.g. ``"lines 2, 5"``; long runs end "(and N more)"."""
    lines = [int(i) for i in mask[mask].index]  # tables are indexed by line number
    listed = ", ".join(str(n) for n in lines[:MAX_LINES_LISTED])
    more = len(lines) - MAX_LINES_LISTED
    return f"line{'s' if len(lines) > 1 else ''} {listed}" + (
        f" (and {more} more)" if more > 0 else ""
    )


def read_csv_cells(text: str, file: str) -> tuple[pd.DataFrame | None, list[Problem]]:
    """A CSV as a table of strings indexed by line number (the header is line 1).

    Blank lines are skipped. Returns problems instead of a table for an empty
    file, a header of one field holding another delimiter (``;``, tab), repeated column
    names, or rows whose number of fields is not the header's.
    """
    reader = csv.reader(io.StringIO(text))
    try:
        rows = [(reader.line_num, row) for row in reader if row]
    except csv.Error as error:
        return None, [Problem(file, f"line {reader.line_num}", "csv-format", str(error))]
    if not rows:
        return None, [Problem(file, "", "csv-format", "the file is empty; expected a header row")]
    header = rows[0][1]
    wrong = [mark for mark in OTHER_DELIMITERS if len(header) == 1 and mark in header[0]]
    if wrong:
        # A spreadsheet set to a decimal comma saves ';'-separated "CSV": one column here.
        message = (
            f"the header is one field, {header[0][:60]!r}: the file looks separated by "
            f"{wrong[0]!r}; casa-trial/1 files are comma-separated: save it with ',' as the "
            "delimiter (and '.' as the decimal mark)"
        )
        return None, [Problem(file, "line 1", "csv-format", message)]
    duplicates = sorted({c for c in header if header.count(c) > 1})
    if duplicates:
        where = ", ".join(repr(c) for c in duplicates)
        return None, [Problem(file, f"column {where}", "unique-columns", "appears twice")]
    ragged = pd.Series({line: len(row) != len(header) for line, row in rows[1:]}, dtype=bool)
    if ragged.any():
        return None, [
            Problem(
                file,
                where_lines(ragged),
                "csv-format",
                f"the header has {len(header)} fields and these lines do not",
            )
        ]
    lines = [line for line, _ in rows[1:]]
    cells = pd.DataFrame([row for _, row in rows[1:]], columns=header, index=lines, dtype=str)
    return cells, []


def check_columns(
    cells: pd.DataFrame,
    file: str,
    required: Sequence[str],
    known: Callable[[str], bool],
    unknown_message: str,
) -> list[Problem]:
    """``required-column`` for each required column missing, ``unknown-column`` for others."""
    problems = [
        Problem(file, f"column {column!r}", "required-column", "missing")
        for column in required
        if column not in cells.columns
    ]
    return problems + [
        Problem(file, f"column {column!r}", "unknown-column", unknown_message)
        for column in cells.columns
        if not known(column)
    ]


def numeric(cells: pd.DataFrame, column: str, file: str, problems: list) -> pd.Series:
    """The column as floats; adds a problem for every cell that is not a finite number."""
    try:
        # Fast path: every cell parses (NaN and inf included, caught below).
        values = pd.Series(np.asarray(cells[column], dtype=float), index=cells.index)
    except ValueError:
        values = pd.to_numeric(cells[column].str.strip(), errors="coerce").astype(float)
    bad = pd.Series(~np.isfinite(values.to_numpy()), index=cells.index)
    if bad.any():
        first = cells[column][bad].iloc[0]
        problems.append(
            Problem(
                file,
                f"column {column!r}, {where_lines(bad)}",
                "finite-number",
                f"expected a finite number, got {first!r}",
            )
        )
    return values


def in_range(values: pd.Series, column: str, file: str, problems: list, low, high) -> None:
    """Adds a problem for every value of the column outside ``[low, high]``."""
    # Cells that are not finite numbers are reported once, as finite-number.
    outside = np.isfinite(values) & ((values < low) | (values > high))
    if outside.any():
        span = f">= {low:g}" if high == math.inf else f"in [{low:g}, {high:g}]"
        first = values[outside].iloc[0]
        problems.append(
            Problem(
                file,
                f"column {column!r}, {where_lines(outside)}",
                "range",
                f"must be {span}, got {first!r}",
            )
        )
