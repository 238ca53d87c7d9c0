"""Checking a dataset: every trial and surveys file below folders, and rules across files.

Files that are neither ``.csv`` nor ``.json`` (a README, a notebook) are not logs:
they are listed as ignored and never read. Hidden files and folders are skipped.
Raw files are only read. The contract is ``docs/data-contracts.md``.

Examples
--------
>>> import tempfile, pathlib
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> _ = (folder / "README.md").write_text("about this dataset")
>>> [(c.kind, c.ok) for c in check_paths([folder])]
[('folder', False), ('other', True)]
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from casa_core.io.contract import CONDITION_KEYS, SINGLE_TRIAL_PHASES, SURVEYS_NAME
from casa_core.io.trial_log import load_surveys, load_trial, trial_files, trial_stem
from casa_core.io.validation import Problem

_LOG_SUFFIXES = (".csv", ".json")


@dataclass
class FileCheck:
    """The outcome of checking one file of a dataset.

    ``kind`` is ``"trial"`` (the ``.csv`` of a trial, with its ``.json``),
    ``"surveys"``, ``"other"`` (not a log: ignored), or, for a path given to
    :func:`check_paths`, ``"folder"`` (without logs) or ``"missing"``. ``meta`` and
    ``frame`` hold what was parsed (typed as :func:`~casa_core.io.read_trial` /
    :func:`~casa_core.io.read_surveys` return it), so that a checked dataset need not
    be read twice.

    Examples
    --------
    >>> check = FileCheck(Path("notes.txt"), "other")
    >>> check.ok, check.problems
    (True, [])
    """

    file: Path
    kind: str
    problems: list[Problem] = field(default_factory=list)
    meta: dict | None = None
    frame: pd.DataFrame | None = field(default=None, repr=False)

    @property
    def ok(self) -> bool:
        """True when the file has no problem."""
        return not self.problems


def find_files(folder: Path | str) -> list[Path]:
    """Every non-hidden file below ``folder``, sorted, so that checks run in a fixed order.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> for name in ("b/t.csv", "a.json", ".git/x", ".hidden.csv"):
    ...     (folder / name).parent.mkdir(exist_ok=True)
    ...     _ = (folder / name).write_text("")
    >>> [p.relative_to(folder).as_posix() for p in find_files(folder)]
    ['a.json', 'b/t.csv']
    """
    folder = Path(folder)
    found = []
    for root, dirs, files in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        found += [Path(root) / f for f in files if not f.startswith(".")]
    return sorted(found)


def _check_trial(stem: Path) -> FileCheck:
    meta, frame, problems = load_trial(stem)
    paired = not any(p.rule == "pair" for p in problems)
    return FileCheck(trial_files(stem)[1], "trial", problems, meta if paired else None, frame)


def _unique_conditions(checks: list[FileCheck]) -> None:
    """Add a ``unique-condition`` problem to each trial that repeats a single-trial condition."""
    conditions: dict[tuple, list[FileCheck]] = {}
    for check in checks:
        meta = check.meta
        if meta and meta.get("phase") in SINGLE_TRIAL_PHASES:
            key = tuple(meta.get(k) for k in CONDITION_KEYS)
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


def check_files(files: Iterable[Path | str]) -> list[FileCheck]:
    """Check the given files as logs: each trial (its ``.csv`` and ``.json``), surveys, others.

    A trial is reported once, under its ``.csv``; a lone ``.json`` or ``.csv`` is a
    ``pair`` problem. Within the given files, a participant's condition in a
    single-trial phase (``SINGLE_TRIAL_PHASES``) must appear once: repeats would be
    counted twice by the statistics.

    Parameters
    ----------
    files : iterable of path
        The files to check; each is read at most once.

    Returns
    -------
    list of FileCheck
        Sorted by file.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (folder / "t.json").write_text("{")
    >>> (check,) = check_files([folder / "t.json"])
    >>> check.file.name, [p.rule for p in check.problems]
    ('t.csv', ['json', 'pair'])
    """
    checks: list[FileCheck] = []
    stems: dict[Path, None] = {}
    for path in sorted({Path(p) for p in files}):
        if path.name == SURVEYS_NAME:
            frame, problems = load_surveys(path)
            checks.append(FileCheck(path, "surveys", problems, frame=frame))
        elif path.suffix in _LOG_SUFFIXES:
            stems[trial_stem(path)] = None
        else:
            checks.append(FileCheck(path, "other"))
    trials = [_check_trial(stem) for stem in stems]
    _unique_conditions(trials)
    checks += trials
    checks.sort(key=lambda c: str(c.file))
    return checks


def check_paths(paths: Iterable[Path | str]) -> list[FileCheck]:
    """Check files and folders (folders recursively); see :func:`check_files`.

    Parameters
    ----------
    paths : iterable of path
        Files (either file of a trial names the pair) and folders.

    Returns
    -------
    list of FileCheck
        First a ``"missing"`` check for each path that does not exist and a ``"folder"``
        check for each folder without logs, then :func:`check_files` of the rest.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> [(c.kind, c.problems[0].rule) for c in check_paths([folder / "nowhere"])]
    [('missing', 'exists')]
    """
    files: list[Path] = []
    problems: list[FileCheck] = []
    for path in map(Path, paths):
        if path.is_dir():
            found = find_files(path)
            files += found
            if not any(f.suffix in _LOG_SUFFIXES for f in found):
                missing = Problem(str(path), "", "non-empty", "no trial logs or surveys found")
                problems.append(FileCheck(path, "folder", [missing]))
        elif path.is_file():
            # A trial named by either file is checked as the pair.
            files.append(path)
            csv_path = trial_files(path)[1]
            if path.suffix == ".json" and csv_path.is_file():
                files.append(csv_path)
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

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (folder / "t.csv").write_text("t,x,y,z,rot,keys\\n0,0.45,-0.22,0.38,0,\\n")
    >>> [str(p).replace(str(folder), "DIR") for p in validate_paths([folder])]
    ['DIR/t.json: [pair] missing: a trial needs .json and .csv']
    """
    return [problem for check in check_paths(paths) for problem in check.problems]
