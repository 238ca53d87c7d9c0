"""Reading a session file's arrays with no pickle loaded, and the checks of those arrays."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from casa_core.io import Problem


class SessionError(ValueError):
    """Session files that cannot be imported; ``problems`` lists each, naming the file."""

    def __init__(self, problems: list[Problem]):
        self.problems = problems
        super().__init__("\n".join(map(str, problems)))


#: Stands for an object array of a session file: a pickle, never loaded.
PICKLED = object()


def load_arrays(path: Path) -> dict:
    """The arrays of an ``.npz``, with no pickle loaded; SessionError (rule ``npz``) when
    it cannot be read.

    An object array is stored as a pickle, and loading a pickle can run any code the file
    holds, so each one is left unread (:data:`PICKLED`): the original keeps its goals'
    planned trajectories so, which the import does not use.
    """
    try:
        # np.load takes any other file for a pickle and says how to load it unsafely.
        if not zipfile.is_zipfile(path):
            raise ValueError("the file is not a zip archive")
        with np.load(path, allow_pickle=False) as archive:
            return {key: _array(archive, key) for key in archive.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError) as error:
        message = f"not a readable NumPy .npz archive (a zip of arrays): {error}"
        raise SessionError([Problem(str(path), "", "npz", message)]) from None


def _array(archive, key: str):
    """``archive[key]``, or :data:`PICKLED` for an object array (never unpickled)."""
    try:
        return archive[key]
    except ValueError as error:
        if "allow_pickle" not in str(error):
            raise
        return PICKLED


class Checker:
    """Checks of one session's arrays; every problem names the file, the key and the rule."""

    def __init__(self, file: str, arrays: dict):
        self.file, self.arrays = file, arrays
        self.problems: list[Problem] = []

    def fail(self, key: str, rule: str, message: str) -> None:
        self.problems.append(Problem(self.file, f"key {key!r}", rule, message))

    def array(self, key: str, columns: int | None, *, finite: bool = True):
        """``key`` as a float array of shape (rows,), (rows, columns) or, for columns 0,
        (rows, any); else None. ``finite=False``: NaN and inf allowed (the original's 0/0)."""
        if key not in self.arrays:
            self.fail(key, "required-key", "missing")
            return None
        if self.arrays[key] is PICKLED:
            message = "is an object array (a pickle), which is never loaded: it could run code"
            self.fail(key, "pickle", message)
            return None
        try:
            value = np.asarray(self.arrays[key], dtype=float)
        except (TypeError, ValueError):
            self.fail(key, "numbers", f"must hold numbers, got dtype {self.arrays[key].dtype}")
            return None
        wanted = {None: "(n,)", 0: "(m, goals)"}.get(columns, f"(n, {columns})")
        if value.ndim != (1 if columns is None else 2) or (columns and value.shape[1] != columns):
            self.fail(key, "shape", f"must have shape {wanted}, got {value.shape}")
            return None
        if finite and not np.all(np.isfinite(value)):
            rows = np.flatnonzero(~np.isfinite(value).reshape(len(value), -1).all(axis=1))
            self.fail(key, "finite-number", f"row {rows[0]} is not finite")
            return None
        return value

    def rows(self, key: str, value, expected: int, of: str) -> None:
        if value is not None and len(value) != expected:
            self.fail(key, "rows", f"has {len(value)} rows, {of} has {expected}")

    def increasing(self, key: str, value) -> None:
        if value is None:
            return
        if len(value) and value[0] < 0:
            self.fail(key, "range", f"starts at {value[0]!r} s: times count from the start, >= 0")
        steps = np.diff(value)
        if np.any(steps <= 0):
            row = int(np.flatnonzero(steps <= 0)[0]) + 1
            self.fail(
                key,
                "increasing",
                f"must strictly increase; row {row} is not after row "
                f"{row - 1} ({value[row]!r} <= {value[row - 1]!r})",
            )
