"""The casa-trial/1 contract: the only reader and writer of trial logs and surveys.

A dataset is a folder. A trial is a pair of files with the same stem anywhere
below it: ``<stem>.json`` (metadata) and ``<stem>.csv`` (one row per control
tick). Likert answers live in files named ``surveys.csv``. The contract is
written out in ``NOTES.md`` section 3; this module enforces it, and every other
module reads and writes logs through it so that one set of rules holds
everywhere.

Checks never stop at the first problem: each reports every :class:`Problem` it
finds (file, where, rule, message) so that a user can fix a file in one pass.
Files that are neither ``.csv`` nor ``.json`` (a README, a notebook) are not
logs: they are listed as ignored and never read. Raw files are only read.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import tempfile
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

SCHEMA = "casa-trial/1"
TASKS = ("familiarization", "known_goal", "unknown_goal", "unknown_skill")
METHODS = ("NA", "PBA", "CASA")
PHASES = (
    "familiarization",
    "no_misspecification",
    "before_learning",
    "demonstration",
    "after_learning",
)
SOURCES = ("human", "simulated")
KEYS = ("x+", "x-", "y+", "y-", "z+", "z-", "rot+", "rot-")
QUESTIONS = ("understood", "effortless", "useful")
SURVEYS_NAME = "surveys.csv"

# Which phases each task can be run in (paper, Sec. V-A): the known goal is the
# well-specified task; the two unknown tasks go through learning.
TASK_PHASES = {
    "familiarization": ("familiarization",),
    "known_goal": ("no_misspecification",),
    "unknown_goal": ("before_learning", "demonstration", "after_learning"),
    "unknown_skill": ("before_learning", "demonstration", "after_learning"),
}
# Demonstrations are given by direct teleoperation; "after learning" names CASA's condition.
PHASE_METHOD = {"demonstration": "NA", "after_learning": "CASA"}
# Phases in which a participant does a condition once; repeats would be double counted.
SINGLE_TRIAL_PHASES = ("no_misspecification", "before_learning", "after_learning")

META_REQUIRED = ("schema", "participant", "task", "method", "phase", "source")
META_OPTIONAL = ("intents", "seed", "started_at", "notes")
FRAME_REQUIRED = ("t", "x", "y", "z", "rot", "keys")
JOINTS = tuple(f"q{i}" for i in range(1, 8))
SURVEY_COLUMNS = ("participant", "task", "method", "phase", "question", "score")
SURVEY_OPTIONAL = ("source",)

# At most this many line numbers are spelled out per (column, rule); the rest are counted.
_MAX_LINES_LISTED = 10


@dataclass(frozen=True, order=True)
class Problem:
    """One way in which a file breaks the contract.

    Attributes
    ----------
    file : str
        The file, as given or found.
    where : str
        The key, column and/or line numbers (line 1 is the CSV header).
    rule : str
        A short name of the rule broken, e.g. ``"required-key"``.
    message : str
        What is wrong and what is expected.
    """

    file: str
    where: str
    rule: str
    message: str

    def __str__(self) -> str:
        where = f": {self.where}" if self.where else ""
        return f"{self.file}{where}: [{self.rule}] {self.message}"


class LogError(ValueError):
    """Raised when a log breaks the contract; ``problems`` lists every problem found."""

    def __init__(self, problems: Sequence[Problem]):
        self.problems = list(problems)
        super().__init__("\n".join(str(p) for p in self.problems))


@dataclass
class FileCheck:
    """The outcome of checking one file of a dataset.

    ``kind`` is ``"trial"`` (the ``.csv`` of a trial, with its ``.json``),
    ``"surveys"`` or ``"other"`` (not a log: ignored). ``meta`` and ``frame``
    hold what was parsed (typed as :func:`read_trial` / :func:`read_surveys`
    return it), so that a checked dataset need not be read twice.
    """

    file: Path
    kind: str
    problems: list[Problem] = field(default_factory=list)
    meta: dict | None = None
    frame: pd.DataFrame | None = field(default=None, repr=False)

    @property
    def ok(self) -> bool:
        return not self.problems


# --------------------------------------------------------------------------- writing


def atomic_write_text(path: Path | str, text: str) -> None:
    """Write ``text`` to ``path`` atomically: a temporary file in the same folder, then rename.

    Readers never see a half-written file, and an interrupted run leaves the old file intact.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as handle:
            handle.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def frame_to_csv_text(frame: pd.DataFrame) -> str:
    """A table as CSV text: header, ``\\n`` line ends, shortest round-trip floats, no index.

    The same table always gives the same bytes, which keeps processed tables reproducible.
    """
    buffer = io.StringIO()
    frame.to_csv(buffer, index=False, lineterminator="\n")
    return buffer.getvalue()


def write_trial(stem: Path | str, meta: dict, frame: pd.DataFrame) -> None:
    """Validate a trial and write it as ``<stem>.json`` and ``<stem>.csv``, each atomically.

    Parameters
    ----------
    stem : path
        The trial's path without suffix; folders are created.
    meta : dict
        The metadata (NOTES.md section 3): ``schema``, ``participant``, ``task``,
        ``method``, ``phase``, ``source``; optional ``intents``, ``seed``,
        ``started_at``, ``notes``. ``schema`` defaults to ``"casa-trial/1"``.
    frame : pandas.DataFrame
        One row per control tick with ``t, x, y, z, rot, keys`` and optionally
        ``alpha``, ``q1``..``q7``, ``beta:NAME``, ``belief:NAME``. ``keys`` holds
        space-separated key names; ``""`` (or None/NaN) when no key is held.

    Raises
    ------
    LogError
        Listing every problem; nothing is written then.
    """
    stem = _stem(Path(stem))
    meta = {"schema": SCHEMA, **meta}
    frame = frame.copy()
    if "keys" in frame.columns:
        frame["keys"] = frame["keys"].map(_keys_cell)
    json_file, csv_file = str(_sibling(stem, ".json")), str(_sibling(stem, ".csv"))
    try:
        json_text = json.dumps(meta, indent=2, sort_keys=True, allow_nan=False) + "\n"
    except (TypeError, ValueError) as error:
        # e.g. a numpy integer as seed, or NaN: not plain JSON.
        raise LogError([Problem(json_file, "", "json-value", f"not plain JSON: {error}")]) from None
    csv_text = frame_to_csv_text(frame)
    # Check exactly the text that will land on disk, with the reader's own rules.
    problems = check_meta(meta, json_file)
    _, frame_problems = parse_trial_csv(csv_text, csv_file, meta if not problems else None)
    problems += frame_problems
    if problems:
        raise LogError(problems)
    atomic_write_text(_sibling(stem, ".json"), json_text)
    atomic_write_text(_sibling(stem, ".csv"), csv_text)


def write_surveys(path: Path | str, frame: pd.DataFrame) -> None:
    """Validate Likert answers and write them atomically as a ``surveys.csv``.

    ``frame`` has the columns ``participant, task, method, phase, question,
    score`` and optionally ``source``. Raises :class:`LogError` listing every problem.
    """
    path = Path(path)
    if path.name != SURVEYS_NAME:
        raise LogError([Problem(str(path), "", "surveys-name", f"must be named {SURVEYS_NAME}")])
    text = frame_to_csv_text(frame)
    _, problems = parse_surveys_csv(text, str(path))
    if problems:
        raise LogError(problems)
    atomic_write_text(path, text)


def _keys_cell(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    return value


# --------------------------------------------------------------------------- reading


def read_trial(stem: Path | str) -> tuple[dict, pd.DataFrame]:
    """Read and validate one trial.

    Parameters
    ----------
    stem : path
        The trial's path with or without the ``.csv``/``.json`` suffix.

    Returns
    -------
    meta : dict
    frame : pandas.DataFrame
        Numeric columns as float; ``keys`` as str (``""`` when no key is held).

    Raises
    ------
    LogError
        Listing every problem of both files.
    """
    stem = _stem(Path(stem))
    meta, problems = load_meta(_sibling(stem, ".json"))
    csv_path = _sibling(stem, ".csv")
    if not csv_path.is_file():
        problems.append(Problem(str(csv_path), "", "pair", "missing: a trial needs .json and .csv"))
        raise LogError(problems)
    frame, frame_problems = parse_trial_csv(_read_text(csv_path), str(csv_path), meta)
    problems += frame_problems
    if problems:
        raise LogError(problems)
    return meta, frame


def read_surveys(path: Path | str) -> pd.DataFrame:
    """Read and validate a ``surveys.csv``; ``score`` as int. Raises :class:`LogError`."""
    path = Path(path)
    frame, problems = parse_surveys_csv(_read_text(path), str(path))
    if problems:
        raise LogError(problems)
    return frame


def load_meta(path: Path) -> tuple[dict | None, list[Problem]]:
    """Load a trial's ``.json`` and check it; ``(None, problems)`` when unreadable."""
    name = str(path)
    if not path.is_file():
        return None, [Problem(name, "", "pair", "missing: a trial needs .json and .csv")]
    try:
        meta = json.loads(_read_text(path))
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        return None, [Problem(name, "", "json", f"not valid JSON: {error}")]
    problems = check_meta(meta, name)
    return (meta if isinstance(meta, dict) else None), problems


def _read_text(path: Path) -> str:
    with open(path, encoding="utf-8", newline="") as handle:
        return handle.read()


def _stem(path: Path) -> Path:
    return path.with_suffix("") if path.suffix in (".csv", ".json") else path


def _sibling(stem: Path, suffix: str) -> Path:
    # Not Path.with_suffix: a stem such as "p01.trial" already has a dot.
    return stem.with_name(stem.name + suffix)


# --------------------------------------------------------------------------- rules


def check_meta(meta, file: str) -> list[Problem]:
    """Every way in which a trial's metadata breaks casa-trial/1."""
    if not isinstance(meta, dict):
        return [Problem(file, "", "json-object", "the metadata must be a JSON object")]
    problems = []

    def bad(key: str, rule: str, message: str) -> None:
        problems.append(Problem(file, f"key {key!r}", rule, message))

    for key in META_REQUIRED:
        if key not in meta:
            bad(key, "required-key", "missing")
    for key in sorted(set(meta) - set(META_REQUIRED) - set(META_OPTIONAL)):
        allowed = ", ".join(META_REQUIRED + META_OPTIONAL)
        bad(key, "unknown-key", f"not part of {SCHEMA}; allowed keys: {allowed}")
    if "schema" in meta and meta["schema"] != SCHEMA:
        bad("schema", "schema", f"is {meta['schema']!r}, expected {SCHEMA!r}")
    participant = meta.get("participant")
    if "participant" in meta and not (isinstance(participant, str) and participant.strip()):
        bad("participant", "non-empty-string", f"is {participant!r}, expected a non-empty string")
    for key, allowed in (("task", TASKS), ("method", METHODS), ("phase", PHASES)):
        if key in meta and meta[key] not in allowed:
            bad(key, "enum", f"is {meta[key]!r}, expected one of {', '.join(allowed)}")
    if "source" in meta and meta["source"] not in SOURCES:
        bad("source", "enum", f"is {meta['source']!r}, expected one of {', '.join(SOURCES)}")
    task, phase, method = meta.get("task"), meta.get("phase"), meta.get("method")
    if task in TASKS and phase in PHASES and phase not in TASK_PHASES[task]:
        expected = " or ".join(TASK_PHASES[task])
        bad("phase", "task-phase", f"{phase!r} is not a phase of task {task!r} ({expected})")
    if phase in PHASE_METHOD and method in METHODS and method != PHASE_METHOD[phase]:
        bad("method", "phase-method", f"phase {phase!r} is run with {PHASE_METHOD[phase]!r}")
    if "intents" in meta:
        intents = meta["intents"]
        names_ok = isinstance(intents, list) and all(
            isinstance(n, str) and n.strip() for n in intents
        )
        if not names_ok:
            bad("intents", "intent-names", "expected a list of non-empty strings")
        elif len(set(intents)) != len(intents):
            bad("intents", "intent-names", "an intent name is listed twice")
    return problems


def _known_column(name: str) -> bool:
    if name in FRAME_REQUIRED or name == "alpha" or name in JOINTS:
        return True
    prefix, _, intent = name.partition(":")
    return prefix in ("beta", "belief") and bool(intent.strip())


def _lines(mask: pd.Series) -> str:
    lines = [int(i) for i in mask[mask].index]  # tables are indexed by line number
    listed = ", ".join(str(n) for n in lines[:_MAX_LINES_LISTED])
    more = len(lines) - _MAX_LINES_LISTED
    return f"line{'s' if len(lines) > 1 else ''} {listed}" + (
        f" (and {more} more)" if more > 0 else ""
    )


def _read_csv_cells(text: str, file: str) -> tuple[pd.DataFrame | None, list[Problem]]:
    """A CSV as a table of strings indexed by line number (the header is line 1).

    Blank lines are skipped. Returns problems instead of a table for an empty
    file, repeated column names, or rows whose number of fields is not the header's.
    """
    reader = csv.reader(io.StringIO(text))
    try:
        rows = [(reader.line_num, row) for row in reader if row]
    except csv.Error as error:
        return None, [Problem(file, f"line {reader.line_num}", "csv-format", str(error))]
    if not rows:
        return None, [Problem(file, "", "csv-format", "the file is empty; expected a header row")]
    header = rows[0][1]
    duplicates = sorted({c for c in header if header.count(c) > 1})
    if duplicates:
        where = ", ".join(repr(c) for c in duplicates)
        return None, [Problem(file, f"column {where}", "unique-columns", "appears twice")]
    ragged = pd.Series({line: len(row) != len(header) for line, row in rows[1:]}, dtype=bool)
    if ragged.any():
        return None, [
            Problem(
                file,
                _lines(ragged),
                "csv-format",
                f"the header has {len(header)} fields and these lines do not",
            )
        ]
    lines = [line for line, _ in rows[1:]]
    cells = pd.DataFrame([row for _, row in rows[1:]], columns=header, index=lines, dtype=str)
    return cells, []


def _numeric(cells: pd.DataFrame, column: str, file: str, problems: list) -> pd.Series:
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
                f"column {column!r}, {_lines(bad)}",
                "finite-number",
                f"expected a finite number, got {first!r}",
            )
        )
    return values


def parse_trial_csv(
    text: str, file: str, meta: dict | None = None
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
        ``belief:NAME`` column must name one of them.

    Returns
    -------
    frame : pandas.DataFrame or None
        Typed table (None when the file cannot be read as a table).
    problems : list of Problem
    """
    cells, problems = _read_csv_cells(text, file)
    if cells is None:
        return None, problems
    for column in FRAME_REQUIRED:
        if column not in cells.columns:
            problems.append(Problem(file, f"column {column!r}", "required-column", "missing"))
    for column in cells.columns:
        if not _known_column(column):
            problems.append(
                Problem(
                    file,
                    f"column {column!r}",
                    "unknown-column",
                    "not part of casa-trial/1; allowed: t, x, y, z, rot, keys, alpha, "
                    "q1..q7, beta:NAME, belief:NAME",
                )
            )
    if len(cells) == 0:
        problems.append(Problem(file, "", "non-empty", "no rows; expected one row per tick"))
    intents = meta.get("intents") if isinstance(meta, dict) else None
    frame = pd.DataFrame(index=cells.index)
    for column in cells.columns:
        if column == "keys" or not _known_column(column):
            continue
        values = _numeric(cells, column, file, problems)
        frame[column] = values
        if column == "alpha" or column.startswith("belief:"):
            _range(values, column, file, problems, 0.0, 1.0)
        if column.startswith("beta:"):
            _range(values, column, file, problems, 0.0, math.inf)
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
    if "t" in frame.columns and len(frame) > 1:
        t = frame["t"]
        not_increasing = t.diff().le(0) & t.notna() & t.shift().notna()
        if not_increasing.any():
            problems.append(
                Problem(
                    file,
                    f"column 't', {_lines(not_increasing)}",
                    "t-increasing",
                    "t must be strictly increasing (one row per tick, in order)",
                )
            )
    if "t" in frame.columns:
        _range(frame["t"], "t", file, problems, 0.0, math.inf)
    if "keys" in cells.columns:
        frame["keys"] = cells["keys"]
        _check_keys(cells["keys"], file, problems)
    ordered = [c for c in cells.columns if c in frame.columns]
    return frame[ordered].reset_index(drop=True), problems


def _range(values: pd.Series, column: str, file: str, problems: list, low, high) -> None:
    outside = values.notna() & ((values < low) | (values > high))
    if outside.any():
        span = f">= {low:g}" if high == math.inf else f"in [{low:g}, {high:g}]"
        first = values[outside].iloc[0]
        problems.append(
            Problem(
                file,
                f"column {column!r}, {_lines(outside)}",
                "range",
                f"must be {span}, got {first!r}",
            )
        )


def _check_keys(keys: pd.Series, file: str, problems: list) -> None:
    tokens = keys.str.split()
    unknown = tokens.map(lambda held: any(k not in KEYS for k in held))
    if unknown.any():
        first = keys[unknown].iloc[0]
        problems.append(
            Problem(
                file,
                f"column 'keys', {_lines(unknown)}",
                "keys",
                f"got {first!r}; expected space-separated names from {' '.join(KEYS)}, "
                "empty when none",
            )
        )
    repeated = tokens.map(lambda held: len(set(held)) != len(held))
    if repeated.any():
        problems.append(
            Problem(file, f"column 'keys', {_lines(repeated)}", "keys", "a key is listed twice")
        )


def parse_surveys_csv(text: str, file: str) -> tuple[pd.DataFrame | None, list[Problem]]:
    """Parse a ``surveys.csv`` text and check it; ``score`` becomes int when all are valid."""
    cells, problems = _read_csv_cells(text, file)
    if cells is None:
        return None, problems
    for column in SURVEY_COLUMNS:
        if column not in cells.columns:
            problems.append(Problem(file, f"column {column!r}", "required-column", "missing"))
    allowed = SURVEY_COLUMNS + SURVEY_OPTIONAL
    for column in cells.columns:
        if column not in allowed:
            problems.append(
                Problem(
                    file,
                    f"column {column!r}",
                    "unknown-column",
                    f"not part of the surveys contract; allowed: {', '.join(allowed)}",
                )
            )
    if problems:
        return None, problems
    empty = cells["participant"].str.strip().eq("")
    if empty.any():
        problems.append(
            Problem(file, f"column 'participant', {_lines(empty)}", "non-empty-string", "is empty")
        )
    enums = [("task", TASKS), ("method", METHODS), ("phase", PHASES), ("question", QUESTIONS)]
    if "source" in cells.columns:
        enums.append(("source", SOURCES))
    for column, values in enums:
        outside = ~cells[column].isin(values)
        if outside.any():
            problems.append(
                Problem(
                    file,
                    f"column {column!r}, {_lines(outside)}",
                    "enum",
                    f"got {cells[column][outside].iloc[0]!r}, expected one of {', '.join(values)}",
                )
            )
    score_ok = cells["score"].str.strip().isin([str(s) for s in range(1, 8)])
    if not score_ok.all():
        problems.append(
            Problem(
                file,
                f"column 'score', {_lines(~score_ok)}",
                "likert-score",
                f"got {cells['score'][~score_ok].iloc[0]!r}, expected an integer 1 to 7",
            )
        )
    key = ["participant", "task", "method", "phase", "question"]
    repeated = cells.duplicated(subset=key, keep="first")
    if repeated.any():
        problems.append(
            Problem(
                file,
                _lines(repeated),
                "unique-answer",
                "a participant answers each question once per task, method and phase",
            )
        )
    if problems:
        return None, problems
    frame = cells.copy()
    frame["score"] = frame["score"].str.strip().astype(int)
    return frame.reset_index(drop=True), problems


# --------------------------------------------------------------------------- folders


def find_files(folder: Path | str) -> list[Path]:
    """Every non-hidden file below ``folder``, sorted, so that checks run in a fixed order."""
    folder = Path(folder)
    found = []
    for root, dirs, files in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        found += [Path(root) / f for f in files if not f.startswith(".")]
    return sorted(found)


def check_files(files: Iterable[Path]) -> list[FileCheck]:
    """Check the given files as logs: each trial (its ``.csv`` and ``.json``), surveys, others.

    A trial is reported once, under its ``.csv``; a lone ``.json`` or ``.csv`` is a
    ``pair`` problem. Within the given files, a participant's condition in a
    single-trial phase (:data:`SINGLE_TRIAL_PHASES`) must appear once: repeats
    would be counted twice by the statistics.
    """
    checks: list[FileCheck] = []
    stems: dict[Path, None] = {}
    for path in sorted({Path(p) for p in files}):
        if path.name == SURVEYS_NAME:
            frame, problems = parse_surveys_csv(_read_text(path), str(path))
            checks.append(FileCheck(path, "surveys", problems, frame=frame))
        elif path.suffix in (".csv", ".json"):
            stems[_stem(path)] = None
        else:
            checks.append(FileCheck(path, "other"))
    conditions: dict[tuple, list[FileCheck]] = {}
    for stem in stems:
        check = _check_trial(stem)
        checks.append(check)
        meta = check.meta
        if meta and meta.get("phase") in SINGLE_TRIAL_PHASES:
            key = tuple(meta.get(k) for k in ("participant", "task", "method", "phase"))
            conditions.setdefault(key, []).append(check)
    for key, group in conditions.items():
        if len(group) > 1:
            names = ", ".join(str(c.file) for c in group)
            for check in group:
                check.problems.append(
                    Problem(
                        str(check.file),
                        "",
                        "unique-condition",
                        f"participant {key[0]!r} has {len(group)} trials of task {key[1]!r}, "
                        f"method {key[2]!r}, phase {key[3]!r}: {names}",
                    )
                )
    checks.sort(key=lambda c: str(c.file))
    return checks


def _check_trial(stem: Path) -> FileCheck:
    csv_path = _sibling(stem, ".csv")
    meta, problems = load_meta(_sibling(stem, ".json"))
    frame = None
    if csv_path.is_file():
        frame, frame_problems = parse_trial_csv(_read_text(csv_path), str(csv_path), meta)
        problems += frame_problems
    else:
        problems.append(Problem(str(csv_path), "", "pair", "missing: a trial needs .json and .csv"))
    paired = not any(p.rule == "pair" for p in problems)
    return FileCheck(csv_path, "trial", problems, meta if paired else None, frame)


def check_paths(paths: Iterable[Path | str]) -> list[FileCheck]:
    """Check files and folders (folders recursively); see :func:`check_files`."""
    files: list[Path] = []
    problems: list[FileCheck] = []
    for path in map(Path, paths):
        if path.is_dir():
            found = find_files(path)
            files += found
            if not any(f.suffix in (".csv", ".json") for f in found):
                missing = Problem(str(path), "", "non-empty", "no trial logs or surveys found")
                problems.append(FileCheck(path, "folder", [missing]))
        elif path.is_file():
            # A trial named by either file is checked as the pair.
            files.append(path)
            if path.suffix == ".json" and _sibling(_stem(path), ".csv").is_file():
                files.append(_sibling(_stem(path), ".csv"))
        else:
            problems.append(
                FileCheck(
                    path, "missing", [Problem(str(path), "", "exists", "no such file or folder")]
                )
            )
    return problems + check_files(files)


def validate_paths(paths: Iterable[Path | str]) -> list[Problem]:
    """Every problem of the trials and surveys in the given files and folders.

    Parameters
    ----------
    paths : iterable of path
        Files (either file of a trial names the pair) and folders (searched recursively).

    Returns
    -------
    list of Problem
        Empty when everything follows the contract.
    """
    return [problem for check in check_paths(paths) for problem in check.problems]
