"""The one reader and the one writer of trial logs and surveys (casa-trial/1).

A trial is written as ``<stem>.json`` and ``<stem>.csv``; both are checked with the
reader's own rules (:mod:`casa_core.io.validation`) before anything is written, and
written atomically (:mod:`casa_core.io.atomic`). Every other module reads and writes
logs through here, so that one set of rules holds everywhere; the contract is
``docs/data-contracts.md``. Raw files are only read.

Examples
--------
>>> import tempfile, pandas as pd
>>> folder = tempfile.mkdtemp()
>>> meta = {"participant": "p01", "task": "known_goal", "method": "NA",
...         "phase": "no_misspecification", "source": "simulated"}
>>> frame = pd.DataFrame({"t": [0.0, 0.05], "x": [0.45, 0.4525], "y": [-0.22, -0.22],
...                       "z": [0.38, 0.38], "rot": [0.0, 0.0], "keys": ["x+", ""]})
>>> _ = write_trial(f"{folder}/p01/trial", meta, frame)
>>> read_meta, read_frame = read_trial(f"{folder}/p01/trial")
>>> read_meta["schema"], read_frame["keys"].tolist()
('casa-trial/1', ['x+', ''])
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import pandas as pd

from casa_core.io.atomic import atomic_write_text, frame_to_csv_text
from casa_core.io.contract import SCHEMA, SURVEYS_NAME, TRIAL_SUFFIXES
from casa_core.io.problems import errors
from casa_core.io.validation import (
    LogError,
    Problem,
    check_meta,
    parse_surveys_csv,
    parse_trial_csv,
)


def trial_stem(path: Path | str) -> Path:
    """The trial's path without the ``.csv`` or ``.json`` suffix (other suffixes stay).

    Examples
    --------
    >>> trial_stem("p01/trial.1.json").as_posix(), trial_stem("p01/trial.1").as_posix()
    ('p01/trial.1', 'p01/trial.1')
    """
    path = Path(path)
    return path.with_suffix("") if path.suffix in TRIAL_SUFFIXES else path


def trial_files(path: Path | str) -> tuple[Path, Path]:
    """The ``.json`` and ``.csv`` of the trial named by ``path`` (either file or its stem).

    Examples
    --------
    >>> [p.as_posix() for p in trial_files("p01/trial.1.csv")]
    ['p01/trial.1.json', 'p01/trial.1.csv']
    """
    stem = trial_stem(path)
    # Not Path.with_suffix: a stem such as "p01.trial" already has a dot.
    return stem.with_name(stem.name + ".json"), stem.with_name(stem.name + ".csv")


def inside(path: Path | str, root: Path | str) -> bool:
    """True when ``path``, symlinks resolved, is ``root`` or below it (resolved too).

    Examples
    --------
    >>> inside("/data/raw/a/p01/t.csv", "/data/raw/a"), inside("/data/raw/b", "/data/raw/a")
    (True, False)
    """
    real, top = os.path.realpath(path), os.path.realpath(root)
    return real == top or real.startswith(top.rstrip(os.sep) + os.sep)


def read_text(path: Path, *, root: Path | None = None) -> tuple[str | None, list[Problem]]:
    """A file's UTF-8 text, or the problem that stops it being read.

    With ``root``, a file that resolves (through symlinks) outside ``root`` is a
    ``symlink`` problem and is not opened. Bytes that are not UTF-8 are a ``utf-8``
    problem naming the line and byte offset; an unreadable file is ``readable``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "t.csv"
    >>> _ = path.write_bytes(b"t,x\\n0,caf\\xe9\\n")
    >>> text, problems = read_text(path)
    >>> text, [(p.where, p.rule) for p in problems]
    (None, [('line 2, byte 9', 'utf-8')])
    """
    name = str(path)
    if root is not None and not inside(path, root):
        where = os.path.realpath(path)
        message = f"resolves to {where}, outside the dataset folder {root}: not read"
        return None, [Problem(name, "", "symlink", message)]
    if not Path(path).is_file():
        # A FIFO or device would block or never end; a broken symlink has nothing to read.
        return None, [Problem(name, "", "readable", "not a regular file: not read")]
    try:
        data = Path(path).read_bytes()
    except OSError as error:
        return None, [Problem(name, "", "readable", f"cannot be read: {error.strerror or error}")]
    try:
        # A UTF-8 byte-order mark (as some spreadsheets write) is not part of the text.
        return data.decode("utf-8-sig"), []
    except UnicodeDecodeError as error:
        line = data[: error.start].count(b"\n") + 1
        byte = data[error.start]
        message = f"byte 0x{byte:02x} is not UTF-8 (latin-1?); save the file as UTF-8 text"
        return None, [Problem(name, f"line {line}, byte {error.start}", "utf-8", message)]


def _missing_pair(path: Path) -> Problem:
    return Problem(str(path), "", "pair", "missing: a trial needs .json and .csv")


# --------------------------------------------------------------------------- reading


def load_meta(path: Path | str, *, root: Path | None = None) -> tuple[dict | None, list[Problem]]:
    """Load a trial's ``.json`` and check it.

    Parameters
    ----------
    path : path
        The ``.json`` file.
    root : path, optional
        The dataset folder: a file resolving outside it is not read (see :func:`read_text`).

    Returns
    -------
    meta : dict or None
        The metadata; None when the file is missing, not JSON or not an object.
    problems : list of Problem

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "t.json"
    >>> _ = path.write_text('{"participant": "p01"}')
    >>> meta, problems = load_meta(path)
    >>> meta, sorted({p.rule for p in problems})
    ({'participant': 'p01'}, ['required-key'])
    >>> load_meta(path.with_name("none.json"))[1][0].rule
    'pair'
    """
    path = Path(path)
    name = str(path)
    if not (path.is_file() or path.is_symlink()):  # a broken link: say so
        return None, [_missing_pair(path)]
    text, problems = read_text(path, root=root)
    if text is None:
        return None, problems
    try:
        meta = json.loads(text)
    except (json.JSONDecodeError, RecursionError) as error:
        return None, [Problem(name, "", "json", f"not valid JSON: {error}")]
    problems = check_meta(meta, name)
    return (meta if isinstance(meta, dict) else None), problems


def load_trial(
    path: Path | str, *, root: Path | None = None
) -> tuple[dict | None, pd.DataFrame | None, list[Problem]]:
    """Read and check one trial without raising: what could be parsed, and every problem.

    Parameters
    ----------
    path : path
        The trial's stem or either of its files.
    root : path, optional
        The dataset folder: a file resolving outside it is not read (see :func:`read_text`).

    Returns
    -------
    meta : dict or None
    frame : pandas.DataFrame or None
        As :func:`read_trial` returns them; None what cannot be read.
    problems : list of Problem
        Of both files, the ``.json``'s first.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> rows = "0,0.45,-0.22,0.38,0,\\n0.05,0.45,-0.22,0.38,0,\\n"
    >>> _ = (folder / "t.csv").write_text("t,x,y,z,rot,keys\\n" + rows)
    >>> meta, frame, problems = load_trial(folder / "t")
    >>> meta, len(frame), [p.rule for p in problems]
    (None, 2, ['pair'])
    """
    json_path, csv_path = trial_files(path)
    meta, problems = load_meta(json_path, root=root)
    frame = None
    if csv_path.is_file() or csv_path.is_symlink():
        text, read_problems = read_text(csv_path, root=root)
        problems += read_problems
        if text is not None:
            frame, frame_problems = parse_trial_csv(text, str(csv_path), meta=meta)
            problems += frame_problems
    else:
        problems.append(_missing_pair(csv_path))
    return meta, frame, problems


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
        Listing every problem of both files, when any is an error (warnings alone pass).

    Examples
    --------
    >>> import tempfile
    >>> try:
    ...     read_trial(f"{tempfile.mkdtemp()}/missing")
    ... except LogError as error:
    ...     print(sorted({p.rule for p in error.problems}))
    ['pair']
    """
    meta, frame, problems = load_trial(stem)
    if errors(problems) or meta is None or frame is None:
        raise LogError(problems)
    return meta, frame


def load_surveys(
    path: Path | str, *, root: Path | None = None
) -> tuple[pd.DataFrame | None, list[Problem]]:
    """Read and check a ``surveys.csv`` without raising; see :func:`parse_surveys_csv`.

    The frame holds the good rows; ``root`` as for :func:`load_trial`.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "surveys.csv"
    >>> _ = path.write_text("participant,task,method,phase,question\\n")
    >>> frame, problems = load_surveys(path)
    >>> frame, [(p.where, p.rule) for p in problems]
    (None, [("column 'score'", 'required-column')])
    """
    path = Path(path)
    text, problems = read_text(path, root=root)
    if text is None:
        return None, problems
    return parse_surveys_csv(text, str(path))


def read_surveys(path: Path | str) -> pd.DataFrame:
    """Read and validate a ``surveys.csv``.

    Returns
    -------
    pandas.DataFrame
        The answers, ``score`` as int.

    Raises
    ------
    LogError
        Listing every problem.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "surveys.csv"
    >>> _ = path.write_text("participant,task,method,phase,question,score\\n"
    ...                     "p01,known_goal,PBA,no_misspecification,understood,6\\n")
    >>> read_surveys(path)[["question", "score"]].values.tolist()
    [['understood', 6]]
    """
    frame, problems = load_surveys(path)
    if errors(problems):
        raise LogError(problems)
    return frame


# --------------------------------------------------------------------------- writing


def _keys_cell(value) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return ""
    return value


def write_trial(stem: Path | str, meta: dict, frame: pd.DataFrame) -> tuple[dict, pd.DataFrame]:
    """Validate a trial and write it as ``<stem>.json`` and ``<stem>.csv``, each atomically.

    Returns the trial as :func:`read_trial` reads it back (the checks parse the text).

    Parameters
    ----------
    stem : path
        The trial's path without suffix; folders are created.
    meta : dict
        The metadata (``docs/data-contracts.md``): ``schema``, ``participant``,
        ``task``, ``method``, ``phase``, ``source``; optional ``intents``, ``seed``,
        ``started_at``, ``notes``, ``max_duration``. ``schema`` defaults to ``"casa-trial/1"``.
    frame : pandas.DataFrame
        One row per control tick with ``t, x, y, z, rot, keys`` and optionally
        ``alpha``, ``q1``..``q7``, ``beta:NAME``, ``belief:NAME``. ``keys`` holds
        space-separated key names; ``""`` (or None/NaN) when no key is held.

    Raises
    ------
    LogError
        Listing every problem; nothing is written then.

    Examples
    --------
    >>> import tempfile, pandas as pd
    >>> meta = {"participant": "p01", "task": "known_goal", "method": "NA",
    ...         "phase": "demonstration", "source": "human"}
    >>> frame = pd.DataFrame({"t": [0.0, 0.05], "x": [0.45, 0.45], "y": [-0.22, -0.22],
    ...                       "z": [0.38, 0.38], "rot": [0.0, 0.0], "keys": [None, None]})
    >>> try:
    ...     write_trial(f"{tempfile.mkdtemp()}/t", meta, frame)
    ... except LogError as error:
    ...     print([(p.where, p.rule) for p in error.problems])
    [("key 'phase'", 'task-phase')]
    """
    json_path, csv_path = trial_files(stem)
    meta = {"schema": SCHEMA, **meta}
    frame = frame.copy()
    if "keys" in frame.columns:
        frame["keys"] = frame["keys"].map(_keys_cell)
    json_file, csv_file = str(json_path), str(csv_path)
    try:
        json_text = json.dumps(meta, indent=2, sort_keys=True, allow_nan=False) + "\n"
    except (TypeError, ValueError) as error:
        # e.g. a numpy integer as seed, or NaN: not plain JSON.
        raise LogError([Problem(json_file, "", "json-value", f"not plain JSON: {error}")]) from None
    csv_text = frame_to_csv_text(frame)
    # Check exactly the text that will land on disk, with the reader's own rules.
    problems = check_meta(meta, json_file)
    parsed, frame_problems = parse_trial_csv(csv_text, csv_file, meta=None if problems else meta)
    problems += frame_problems
    if errors(problems):
        raise LogError(problems)
    atomic_write_text(json_path, json_text)
    atomic_write_text(csv_path, csv_text)
    return json.loads(json_text), parsed


def write_surveys(path: Path | str, frame: pd.DataFrame) -> None:
    """Validate Likert answers and write them atomically as a ``surveys.csv``.

    Parameters
    ----------
    path : path
        Must be named ``surveys.csv``; folders are created.
    frame : pandas.DataFrame
        Columns ``participant, task, method, phase, question, score`` and
        optionally ``source``.

    Raises
    ------
    LogError
        As :func:`write_trial` raises it.

    Examples
    --------
    >>> import tempfile, pandas as pd
    >>> columns = ["participant", "task", "method", "phase", "question", "score"]
    >>> answers = pd.DataFrame([["p01", "known_goal", "NA", "no_misspecification",
    ...                          "useful", 4]], columns=columns)
    >>> path = f"{tempfile.mkdtemp()}/surveys.csv"
    >>> write_surveys(path, answers)
    >>> read_surveys(path)["score"].tolist()
    [4]
    """
    path = Path(path)
    if path.name != SURVEYS_NAME:
        raise LogError([Problem(str(path), "", "surveys-name", f"must be named {SURVEYS_NAME}")])
    text = frame_to_csv_text(frame)
    _, problems = parse_surveys_csv(text, str(path))
    if errors(problems):
        raise LogError(problems)
    atomic_write_text(path, text)
