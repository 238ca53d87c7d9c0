"""The rules of casa-trial/1: every way a trial's metadata, its CSV or a surveys file can break it.

Checks never stop at the first problem: each reports every :class:`Problem` it finds
(file, where, rule, message) so that a user can fix a file in one pass. The metadata's
rules are in :mod:`casa_core.io.metadata`. The rules work on text and parsed values
only; :mod:`casa_core.io.trial_log` reads and writes the files. The contract itself is
``docs/data-contracts.md`` (data in :mod:`casa_core.io.contract`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from casa_core.io._cells import check_columns, in_range, numeric, read_csv_cells, where_lines
from casa_core.io._ticks import check_belief_sum, check_ticks
from casa_core.io.contract import (
    BELIEF_SUM_TOLERANCE,
    COLUMN_RANGES,
    COMMAND_COLUMNS,
    CONTINUOUS_INPUTS,
    FRAME_OPTIONAL,
    FRAME_REQUIRED,
    INTENT_PREFIXES,
    JOINTS,
    KEYS,
    LIKERT_SCORES,
    SCHEMA,
    SURVEY_ANSWER_KEY,
    SURVEY_COLUMNS,
    SURVEY_ENUMS,
    SURVEY_OPTIONAL,
    TICK,
    TICK_TOLERANCE,
    TIME_RANGE,
)
from casa_core.io.metadata import check_meta, participant_id_problem
from casa_core.io.problems import LogError, Problem

__all__ = [
    "LogError",
    "Problem",
    "check_meta",
    "parse_surveys_csv",
    "parse_trial_csv",
    "participant_id_problem",
]

# --------------------------------------------------------------------------- trial CSV

_FRAME_ALLOWED = "allowed: " + ", ".join(
    [*FRAME_REQUIRED, *FRAME_OPTIONAL, f"{JOINTS[0]}..{JOINTS[-1]}"]
    + [f"{prefix}:NAME" for prefix in INTENT_PREFIXES]
)


_KEY_SET = frozenset(KEYS)


def _known_column(name: str) -> bool:
    if name in FRAME_REQUIRED or name in FRAME_OPTIONAL or name in JOINTS:
        return True
    prefix, _, intent = name.partition(":")
    return prefix in INTENT_PREFIXES and bool(intent.strip())


def _check_keys(keys: pd.Series, file: str, problems: list) -> None:
    tokens = keys.str.split()
    unknown = tokens.map(lambda held: any(k not in KEYS for k in held))
    if unknown.any():
        first = keys[unknown].iloc[0]
        problems.append(
            Problem(
                file,
                f"column 'keys', {where_lines(unknown)}",
                "keys",
                f"got {first!r}; expected space-separated names from {' '.join(KEYS)}, "
                "empty when none",
            )
        )
    repeated = tokens.map(lambda held: len(set(held)) != len(held))
    if repeated.any():
        problems.append(
            Problem(
                file, f"column 'keys', {where_lines(repeated)}", "keys", "a key is listed twice"
            )
        )


def _check_input(cells: pd.DataFrame, meta, file: str) -> list[Problem]:
    """The rule between the metadata's ``input`` and the columns: a continuous device's
    trial logs its command and holds no keys; a keyboard trial logs no command."""
    if not isinstance(meta, dict):
        return []  # without the metadata the device is unknown
    device = meta.get("input", "keyboard")
    present = [c for c in COMMAND_COLUMNS if c in cells.columns]
    if device in CONTINUOUS_INPUTS:
        problems = [
            Problem(
                file,
                f"column {column!r}",
                "input-command",
                f"missing; a trial whose input is {device!r} logs the velocity it commanded "
                f"in {', '.join(COMMAND_COLUMNS)}",
            )
            for column in COMMAND_COLUMNS
            if column not in present
        ]
        if "keys" in cells.columns:
            held = cells["keys"].str.strip() != ""
            if held.any():
                where = f"column 'keys', {where_lines(held)}"
                rule = f"must be empty: a {device} trial holds no keys, its command is logged"
                problems.append(Problem(file, where, "input-command", rule))
        return problems
    return [
        Problem(
            file,
            f"column {column!r}",
            "input-command",
            f"only a trial whose input is one of {', '.join(CONTINUOUS_INPUTS)} logs a "
            f"command; this trial's input is {device!r}",
        )
        for column in present
    ]


def _valid_frame(cells: pd.DataFrame, meta) -> pd.DataFrame | None:
    """The typed table of a trial that breaks no rule, checked on whole arrays; else None.

    Every rule of :func:`parse_trial_csv` below the columns' own, decided on the table at
    once (a written trial is checked and read again once per use, and cell-by-cell
    checks cost most of that). When any rule may be broken, and at the edge of a
    tolerance, it returns None and the checks that name each problem run instead.
    """
    columns = [c for c in cells.columns if c != "keys"]
    if "keys" not in cells.columns or not all(_known_column(c) for c in columns):
        return None
    block = np.empty((len(cells), len(columns)))
    try:
        for j, column in enumerate(columns):  # as numeric() parses a cell
            block[:, j] = np.asarray(cells[column], dtype=float)
    except ValueError:
        return None
    if not np.isfinite(block).all():
        return None
    intents = meta.get("intents") if isinstance(meta, dict) else None
    for j, column in enumerate(columns):
        bounds = COLUMN_RANGES.get(column.partition(":")[0])
        if bounds is not None and ((block[:, j] < bounds[0]) | (block[:, j] > bounds[1])).any():
            return None
        if ":" in column and isinstance(intents, list) and column.partition(":")[2] not in intents:
            return None
    t = block[:, columns.index("t")]
    steps = np.diff(t)
    slack = TICK * TICK_TOLERANCE + 1e-9  # as check_ticks: each step within it, so the median
    if (
        (steps <= 0).any()
        or t.min() < TIME_RANGE[0]
        or t.max() > TIME_RANGE[1]
        or t[0] > TICK + 1e-9
        or (np.abs(steps - TICK) > slack).any()
    ):
        return None
    beliefs = [j for j, c in enumerate(columns) if c.partition(":")[0] == "belief"]
    # Short of the tolerance by more than a sum's rounding in another order.
    if beliefs and (np.abs(block[:, beliefs].sum(axis=1) - 1.0) > BELIEF_SUM_TOLERANCE / 2).any():
        return None
    for held in set(cells["keys"]):  # a trial holds a few distinct key sets
        tokens = held.split()
        if not held.isascii() or len(set(tokens)) != len(tokens) or not set(tokens) <= _KEY_SET:
            return None
    frame = pd.DataFrame(block, columns=columns)
    frame["keys"] = cells["keys"].reset_index(drop=True)
    return frame[list(cells.columns)]


def _check_time(t: pd.Series, file: str, problems: list) -> None:
    """The rules of the time column: strictly increasing, in range, one tick apart."""
    if len(t) > 1:
        not_increasing = t.diff().le(0) & t.notna() & t.shift().notna()
        if not_increasing.any():
            problems.append(
                Problem(
                    file,
                    f"column 't', {where_lines(not_increasing)}",
                    "t-increasing",
                    "t must be strictly increasing (one row per tick, in order)",
                )
            )
    in_range(t, "t", file, problems, *TIME_RANGE)
    if not any(p.rule == "t-increasing" for p in problems):
        check_ticks(t, file, problems)


def parse_trial_csv(
    text: str, file: str, *, meta: dict | None = None
) -> tuple[pd.DataFrame | None, list[Problem]]:
    """Parse a trial's CSV text and check it against casa-trial/1.

    Parameters
    ----------
    text : str
        The file's content.
    file : str
        Its name, used in problems.
    meta : dict, optional
        The trial's metadata; when it lists ``intents``, every ``beta:NAME`` and
        ``belief:NAME`` column must name one of them, and its ``input`` says whether the
        command columns must be there (a continuous device) or must not (the keyboard).

    Returns
    -------
    frame : pandas.DataFrame or None
        Typed table (None when the file cannot be read as a table).
    problems : list of Problem

    Examples
    --------
    >>> text = "t,x,y,z,rot,keys,alpha\\n0,0.45,-0.22,0.38,0,x+,1\\n0.05,0.46,-0.22,0.38,0,,2\\n"
    >>> frame, problems = parse_trial_csv(text, "t.csv")
    >>> frame["keys"].tolist()
    ['x+', '']
    >>> print(problems[0])
    t.csv: column 'alpha', line 3: [range] must be in [0, 1], got np.float64(2.0)
    """
    cells, problems = read_csv_cells(text, file)
    if cells is None:
        return None, problems
    problems += check_columns(
        cells, file, FRAME_REQUIRED, _known_column, f"not part of {SCHEMA}; {_FRAME_ALLOWED}"
    )
    if len(cells) == 0:
        problems.append(Problem(file, "", "non-empty", "no rows; expected one row per tick"))
    elif len(cells) == 1:
        # One tick has no motion and no duration: every metric of the trial is undefined.
        message = "one row; a trial needs at least two ticks (its start and its end)"
        problems.append(Problem(file, "", "two-rows", message))
    problems += _check_input(cells, meta, file)
    if not problems:
        valid = _valid_frame(cells, meta)
        if valid is not None:
            return valid, problems
    intents = meta.get("intents") if isinstance(meta, dict) else None
    frame = pd.DataFrame(index=cells.index)
    for column in cells.columns:
        if column == "keys" or not _known_column(column):
            continue
        values = numeric(cells, column, file, problems)
        frame[column] = values
        bounds = COLUMN_RANGES.get(column.partition(":")[0])
        if bounds is not None:
            in_range(values, column, file, problems, *bounds)
        if ":" in column and isinstance(intents, list):
            name = column.partition(":")[2]
            if name not in intents:
                problems.append(
                    Problem(
                        file,
                        f"column {column!r}",
                        "intent-name",
                        f"intent {name!r} is not in the metadata's intents {intents}",
                    )
                )
    if "t" in frame.columns:
        _check_time(frame["t"], file, problems)
    check_belief_sum(frame, file, problems)
    if "keys" in cells.columns:
        frame["keys"] = cells["keys"]
        _check_keys(cells["keys"], file, problems)
    ordered = [c for c in cells.columns if c in frame.columns]
    return frame[ordered].reset_index(drop=True), problems


# --------------------------------------------------------------------------- surveys


def parse_surveys_csv(text: str, file: str) -> tuple[pd.DataFrame | None, list[Problem]]:
    """Parse a ``surveys.csv`` text and check it, row by row.

    Parameters
    ----------
    text, file : str
        As in :func:`parse_trial_csv`.

    Returns
    -------
    frame : pandas.DataFrame or None
        The answers of the rows without a problem, ``score`` as int; None when the
        file itself is bad (unreadable, a column missing or unknown).
    problems : list of Problem
        Row problems name their lines: those rows are not in ``frame``.

    Examples
    --------
    >>> text = ("participant,task,method,phase,question,score\\n"
    ...         "p01,known_goal,NA,no_misspecification,useful,5\\n")
    >>> frame, problems = parse_surveys_csv(text, "surveys.csv")
    >>> frame["score"].tolist(), problems
    ([5], [])
    >>> bad = text + "p01,known_goal,NA,no_misspecification,fun,8\\n"
    >>> frame, problems = parse_surveys_csv(bad, "surveys.csv")
    >>> len(frame), [(p.where, p.rule) for p in problems]
    (1, [("column 'question', line 3", 'enum'), ("column 'score', line 3", 'likert-score')])
    """
    cells, problems = read_csv_cells(text, file)
    if cells is None:
        return None, problems
    allowed = SURVEY_COLUMNS + SURVEY_OPTIONAL
    problems += check_columns(
        cells,
        file,
        SURVEY_COLUMNS,
        allowed.__contains__,
        f"not part of the surveys contract; allowed: {', '.join(allowed)}",
    )
    if problems:
        return None, problems
    if len(cells) == 0:
        problems.append(Problem(file, "", "no-answers", "a header and no answers", "warning"))
    bad_rows = pd.Series(False, index=cells.index)

    def bad(mask: pd.Series, column: str | None, rule: str, message: str) -> None:
        nonlocal bad_rows
        if mask.any():
            lines = where_lines(mask)
            where = lines if column is None else f"column {column!r}, {lines}"
            problems.append(Problem(file, where, rule, message))
            bad_rows |= mask

    participants = cells["participant"]
    bad(participants.str.strip().eq(""), "participant", "non-empty-string", "is empty")
    reasons = participants.map(lambda p: participant_id_problem(p) if p.strip() else None)
    bad(reasons.notna(), "participant", "participant-id", next(iter(reasons.dropna()), ""))
    for column, values in SURVEY_ENUMS:
        if column not in cells.columns:
            continue  # an optional column
        outside = ~cells[column].isin(values)
        first = cells[column][outside].iloc[0] if outside.any() else ""
        bad(outside, column, "enum", f"got {first!r}, expected one of {', '.join(values)}")
    score_ok = cells["score"].str.strip().isin([str(s) for s in LIKERT_SCORES])
    first = cells["score"][~score_ok].iloc[0] if not score_ok.all() else ""
    bad(
        ~score_ok,
        "score",
        "likert-score",
        f"got {first!r}, expected an integer {LIKERT_SCORES[0]} to {LIKERT_SCORES[-1]}",
    )
    # Which of two answers to the same question is right is unknown: both are left out.
    repeated = cells.duplicated(subset=list(SURVEY_ANSWER_KEY), keep=False)
    bad(
        repeated,
        None,
        "unique-answer",
        "a participant answers each question once per task, method and phase",
    )
    frame = cells[~bad_rows].copy()
    frame["score"] = frame["score"].str.strip().astype(int)
    lines = [int(n) for n in frame.index]
    frame = frame.reset_index(drop=True)
    frame.attrs["lines"] = lines  # each answer's line in the file, for later problems
    return frame, problems
