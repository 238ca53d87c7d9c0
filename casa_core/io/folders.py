"""Checking a dataset: every trial and surveys file below folders, and rules across files.

Files that are neither ``.csv`` nor ``.json`` (a README, a notebook) are not logs:
they are listed as ignored and never read. Hidden files and folders are skipped.
Nothing outside a dataset's folder is read: a symlink resolving outside it is a
``symlink`` problem, and symlinked folders are not followed. Raw files are only read.
The contract is ``docs/data-contracts.md``.

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

from casa_core.io.contract import (
    CONDITION_KEYS,
    INTENT_SUFFIX,
    SCENE_NAME,
    SINGLE_TRIAL_PHASES,
    SURVEYS_NAME,
    TRIAL_SUFFIXES,
)
from casa_core.io.trial_log import inside, load_surveys, load_trial, trial_files, trial_stem
from casa_core.io.validation import Problem
from casa_core.scene import SceneError, load_scene


@dataclass
class FileCheck:
    """The outcome of checking one file of a dataset.

    ``kind`` is ``"trial"`` (the ``.csv`` of a trial, with its ``.json``),
    ``"surveys"``, ``"scene"`` (the dataset's ``scene.yaml``), ``"intent"`` (a learned
    intent kept with the logs, ``*.intent.json``: read by the replay, not here),
    ``"other"`` (not a log: ignored), or, for a path given to
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
        """True when the file has no error (warnings alone leave it usable)."""
        return not self.errors

    @property
    def errors(self) -> list[Problem]:
        """The problems that are errors."""
        return [p for p in self.problems if p.is_error]

    @property
    def warnings(self) -> list[Problem]:
        """The problems that are only warnings."""
        return [p for p in self.problems if not p.is_error]


def _walk(folder: Path) -> tuple[list[Path], list[FileCheck]]:
    """The non-hidden files below ``folder``, and a check for each symlinked folder."""
    found, links = [], []
    # followlinks=False: a symlinked folder is listed in dirs but never entered.
    for root, dirs, files in os.walk(folder, followlinks=False):
        for name in sorted(d for d in dirs if not d.startswith(".")):
            path = Path(root) / name
            if path.is_symlink():
                target = os.path.realpath(path)
                if inside(path, folder):
                    message = f"a symlinked folder (to {target}) is not followed"
                    links.append(
                        FileCheck(
                            path, "other", [Problem(str(path), "", "symlink", message, "warning")]
                        )
                    )
                else:
                    message = (
                        f"a symlinked folder resolving to {target}, outside the dataset folder: "
                        "not read"
                    )
                    links.append(
                        FileCheck(path, "other", [Problem(str(path), "", "symlink", message)])
                    )
        dirs[:] = sorted(
            d for d in dirs if not d.startswith(".") and not (Path(root) / d).is_symlink()
        )
        found += [Path(root) / f for f in files if not f.startswith(".")]
    return sorted(found), links


def _empty_folders(folder: Path, found: list[Path]) -> list[FileCheck]:
    """A warning (``empty-folder``) for each folder below ``folder`` without a file in it.

    A participant's folder left empty (its logs not copied yet) would otherwise pass as
    a dataset without that participant. Only the outermost empty folder is named.
    """
    holding = {parent for path in found for parent in path.relative_to(folder).parents}
    checks = []
    for root, dirs, _ in os.walk(folder, followlinks=False):
        dirs[:] = sorted(
            d for d in dirs if not d.startswith(".") and not (Path(root) / d).is_symlink()
        )
        for name in list(dirs):
            path = Path(root) / name
            if path.relative_to(folder) not in holding:
                dirs.remove(name)
                message = "an empty folder: no logs here (not copied yet?); nothing of it is read"
                checks.append(
                    FileCheck(
                        path, "folder", [Problem(str(path), "", "empty-folder", message, "warning")]
                    )
                )
    return checks


def find_files(folder: Path | str) -> list[Path]:
    """Every non-hidden file below ``folder``, sorted, so that checks run in a fixed order.

    Symlinked folders are not entered.

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
    return _walk(Path(folder))[0]


def _check_trial(stem: Path, root: Path | None) -> FileCheck:
    meta, frame, problems = load_trial(stem, root=root)
    paired = not any(p.rule == "pair" for p in problems)
    return FileCheck(trial_files(stem)[1], "trial", problems, meta if paired else None, frame)


def _condition(meta: dict | None) -> tuple[str, ...] | None:
    """The trial's participant, task, method and phase, when all are text."""
    if not meta:
        return None
    values = [meta.get(k) for k in CONDITION_KEYS]
    key = tuple(v for v in values if isinstance(v, str))
    return key if len(key) == len(values) else None


def _unique_conditions(checks: list[FileCheck]) -> None:
    """Add a ``unique-condition`` problem to each trial that repeats a single-trial condition."""
    conditions: dict[tuple, list[FileCheck]] = {}
    for check in checks:
        key = _condition(check.meta)
        if key is not None and key[3] in SINGLE_TRIAL_PHASES:
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


def _participant_case(checks: list[FileCheck]) -> None:
    """Warn (``participant-case``) on trials whose participant differs from another by case."""
    spellings: dict[str, set[str]] = {}
    for check in checks:
        key = _condition(check.meta)
        if key is not None:
            spellings.setdefault(key[0].casefold(), set()).add(key[0])
    for check in checks:
        key = _condition(check.meta)
        if key is None or len(spellings[key[0].casefold()]) < 2:
            continue
        others = ", ".join(repr(p) for p in sorted(spellings[key[0].casefold()]) if p != key[0])
        check.problems.append(
            Problem(
                str(trial_files(check.file)[0]),
                "key 'participant'",
                "participant-case",
                f"{key[0]!r} differs only by case from {others}: the same person? "
                "they are counted as different participants",
                "warning",
            )
        )


def _surveys_without_trials(surveys: list[FileCheck], trials: list[FileCheck]) -> None:
    """Warn (``survey-trial``) on answers for a participant or condition without a trial."""
    conditions = {key for key in map(_condition, (c.meta for c in trials)) if key is not None}
    participants = {key[0] for key in conditions}
    for check in surveys:
        frame = check.frame
        if frame is None or not len(frame):
            continue
        lines = pd.Series(frame.attrs.get("lines", range(2, len(frame) + 2)), index=frame.index)
        keys = frame[list(CONDITION_KEYS)].apply(tuple, axis=1)
        unknown = ~frame["participant"].isin(participants)
        untried = ~unknown & ~keys.isin(conditions)
        for mask, message in (
            (unknown, "no trial of this participant in the dataset"),
            (untried, "no trial of this participant in this task, method and phase"),
        ):
            if mask.any():
                listed = ", ".join(str(n) for n in lines[mask].head(10))
                more = f" (and {int(mask.sum()) - 10} more)" if mask.sum() > 10 else ""
                where = f"line{'s' if mask.sum() > 1 else ''} {listed}{more}"
                first = frame["participant"][mask].iloc[0]
                check.problems.append(
                    Problem(
                        str(check.file),
                        where,
                        "survey-trial",
                        f"{message} (e.g. participant {first!r}); the answers are kept",
                        "warning",
                    )
                )


def _check_scene(path: Path, root: Path) -> FileCheck:
    """A dataset's ``scene.yaml``, validated as a scene; the problem names the key."""
    if not inside(path, root):
        message = f"resolves to {os.path.realpath(path)}, outside the dataset folder: not read"
        return FileCheck(path, "scene", [Problem(str(path), "", "symlink", message)])
    try:
        load_scene(path)
    except SceneError as error:
        # The message starts with the file, then the dotted key.
        text = str(error).removeprefix(f"{path}: ")
        key, _, message = text.partition(": ")
        where = f"key {key!r}" if message and " " not in key else ""
        problem = Problem(str(path), where, "scene", message if where else text)
        return FileCheck(path, "scene", [problem])
    return FileCheck(path, "scene")


def _classify(path: Path, root: Path | None) -> str | FileCheck:
    """``"surveys"``, ``"trial"`` or a finished check (not a log, a misnamed one, a link out,
    a dataset's scene)."""
    name = str(path)
    if path.name == SURVEYS_NAME:
        return "surveys"
    if path.name == SCENE_NAME and root is not None and path.parent == root:
        return _check_scene(path, root)
    if path.name.lower() == SURVEYS_NAME:
        message = f"Likert answers are read only from files named exactly {SURVEYS_NAME!r}"
        return FileCheck(path, "other", [Problem(name, "", "surveys-name", message)])
    if path.name.endswith(INTENT_SUFFIX):
        return FileCheck(path, "intent")
    if path.suffix in TRIAL_SUFFIXES:
        return "trial"
    if path.suffix.lower() in TRIAL_SUFFIXES:
        message = (
            f"looks like a log but its suffix is not lower case: rename it to "
            f"{path.stem + path.suffix.lower()!r}"
        )
        return FileCheck(path, "other", [Problem(name, "", "suffix", message)])
    if root is not None and path.is_symlink() and not inside(path, root):
        message = f"resolves to {os.path.realpath(path)}, outside the dataset folder: not read"
        return FileCheck(path, "other", [Problem(name, "", "symlink", message)])
    return FileCheck(path, "other")


def _check_files(files: Iterable[tuple[Path, Path | None]]) -> list[FileCheck]:
    checks: list[FileCheck] = []
    surveys: list[FileCheck] = []
    stems: dict[Path, Path | None] = {}
    for path, root in sorted(set(files), key=lambda pair: str(pair[0])):
        kind = _classify(path, root)
        if kind == "surveys":
            frame, problems = load_surveys(path, root=root)
            surveys.append(FileCheck(path, "surveys", problems, frame=frame))
        elif kind == "trial":
            stems.setdefault(trial_stem(path), root)
        elif isinstance(kind, FileCheck):
            checks.append(kind)
    trials = [_check_trial(stem, root) for stem, root in stems.items()]
    _unique_conditions(trials)
    _participant_case(trials)
    _surveys_without_trials(surveys, trials)
    checks += trials + surveys
    checks.sort(key=lambda c: str(c.file))
    return checks


def check_files(files: Iterable[Path | str], *, root: Path | str | None = None) -> list[FileCheck]:
    """Check the given files as logs: each trial (its ``.csv`` and ``.json``), surveys, others.

    A trial is reported once, under its ``.csv``; a lone ``.json`` or ``.csv`` is a
    ``pair`` problem. Within the given files, a participant's condition in a
    single-trial phase (``SINGLE_TRIAL_PHASES``) must appear once: repeats would be
    counted twice by the statistics. Warnings: participants that differ only by case
    (``participant-case``), answers without a trial (``survey-trial``).

    Parameters
    ----------
    files : iterable of path
        The files to check; each is read at most once.
    root : path, optional
        The dataset folder: no file resolving outside it is read.

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
    top = None if root is None else Path(root)
    return _check_files((Path(p), top) for p in files)


def check_paths(paths: Iterable[Path | str]) -> list[FileCheck]:
    """Check files and folders (folders recursively); see :func:`check_files`.

    Parameters
    ----------
    paths : iterable of path
        Files (either file of a trial names the pair) and folders. Nothing resolving
        outside a folder given (or, for a file, outside its folder) is read.

    Returns
    -------
    list of FileCheck
        First a ``"missing"`` check for each path that does not exist and a ``"folder"``
        check for each folder without logs (an error for a folder given, a warning,
        ``empty-folder``, for an empty one below it), then :func:`check_files` of the rest.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> [(c.kind, c.problems[0].rule) for c in check_paths([folder / "nowhere"])]
    [('missing', 'exists')]
    """
    files: list[tuple[Path, Path | None]] = []
    problems: list[FileCheck] = []
    for path in map(Path, paths):
        if path.is_dir():
            found, links = _walk(path)
            files += [(f, path) for f in found]
            problems += links + _empty_folders(path, found)
            if not any(f.suffix.lower() in TRIAL_SUFFIXES for f in found):
                missing = Problem(str(path), "", "non-empty", "no trial logs or surveys found")
                problems.append(FileCheck(path, "folder", [missing]))
        elif path.is_file() or path.is_symlink():
            # A trial named by either file is checked as the pair.
            files.append((path, path.parent))
            csv_path = trial_files(path)[1]
            if path.suffix == ".json" and csv_path.is_file():
                files.append((csv_path, path.parent))
        else:
            problems.append(
                FileCheck(
                    path, "missing", [Problem(str(path), "", "exists", "no such file or folder")]
                )
            )
    return problems + _check_files(files)


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
    >>> rows = "0,0.45,-0.22,0.38,0,\\n0.05,0.45,-0.22,0.38,0,\\n"
    >>> _ = (folder / "t.csv").write_text("t,x,y,z,rot,keys\\n" + rows)
    >>> [str(p).replace(str(folder), "DIR") for p in validate_paths([folder])]
    ['DIR/t.json: [pair] missing: a trial needs .json and .csv']
    """
    return [problem for check in check_paths(paths) for problem in check.problems]
