"""The one way outputs are written: atomically, readable by the whole lab (mode 0644).

Each output is written to a temporary file in its own folder and renamed over the
target, so readers never see half a file and a killed run leaves the previous file
intact.

Examples
--------
>>> import tempfile, pandas as pd
>>> folder = tempfile.mkdtemp()
>>> path = write_csv(f"{folder}/table.csv", pd.DataFrame({"a": [1, 2]}))
>>> path.read_text()
'a\\n1\\n2\\n'
>>> oct(path.stat().st_mode & 0o777)
'0o644'
"""

from __future__ import annotations

import io
import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import AbstractContextManager, contextmanager
from pathlib import Path

import pandas as pd

from casa_core.io._csv_text import plain_csv_text

#: Permissions of every output: the owner writes, everyone reads (and lists folders).
FILE_MODE = 0o644
FOLDER_MODE = 0o755


@contextmanager
def atomic_path(path: Path | str) -> Iterator[Path]:
    """A temporary path beside ``path``; renamed to ``path`` when the block succeeds.

    For writers that need a file name (matplotlib, torch). The temporary file keeps
    ``path``'s suffix, so that writers that choose a format by suffix still do.
    On an error the temporary file is removed and ``path`` is untouched.

    Examples
    --------
    >>> import tempfile
    >>> target = Path(tempfile.mkdtemp()) / "figure.png"
    >>> with atomic_path(target) as tmp:
    ...     _ = tmp.write_bytes(b"png")
    >>> target.read_bytes()
    b'png'
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=path.suffix)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, FILE_MODE)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


@contextmanager
def _renamed_when_done(paths, *, folders: bool) -> Iterator[list[Path]]:
    """Temporary files (or folders) beside ``paths``, renamed to them when the block succeeds."""
    targets = [Path(path) for path in paths]
    temporaries: list[Path] = []
    try:
        for path in targets:
            path.parent.mkdir(parents=True, exist_ok=True)
            if folders:
                temporaries.append(Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}.")))
            else:
                fd, name = tempfile.mkstemp(
                    dir=path.parent, prefix=f".{path.name}.", suffix=path.suffix
                )
                os.close(fd)
                temporaries.append(Path(name))
        yield list(temporaries)
        for tmp in temporaries:
            os.chmod(tmp, FOLDER_MODE if folders else FILE_MODE)
        for tmp, path in zip(temporaries, targets, strict=True):
            if folders and path.is_dir() and not path.is_symlink():
                shutil.rmtree(path)
            os.replace(tmp, path)
    except BaseException:
        for tmp in temporaries:
            if folders:
                shutil.rmtree(tmp, ignore_errors=True)
            else:
                tmp.unlink(missing_ok=True)
        raise


def atomic_paths(*paths: Path | str) -> AbstractContextManager[list[Path]]:
    """Temporary paths beside ``paths``; all renamed to them only when the block succeeds.

    For outputs that belong together (a dataset's tables): an error while writing any
    of them (a full disk) leaves every target as it was. The renames come last and
    need no space.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> with atomic_paths(folder / "a.csv", folder / "b.csv") as (a, b):
    ...     _ = a.write_text("1"), b.write_text("2")
    >>> [p.name for p in sorted(folder.iterdir())]
    ['a.csv', 'b.csv']
    """
    return _renamed_when_done(paths, folders=False)


def atomic_folders(*paths: Path | str) -> AbstractContextManager[list[Path]]:
    """Temporary folders beside ``paths``; all renamed to them only when the block succeeds.

    For outputs that are folders of files (a participant's logs): a failed or
    interrupted run leaves no folder half filled under a target's name, and the
    temporary ones are removed. A folder already at a target is replaced. The
    temporary folders are hidden (their names start with ``.``), so that readers of
    the folder around them skip them.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> with atomic_folders(folder / "logs") as (logs,):
    ...     _ = (logs / "a.csv").write_text("1")
    >>> [p.relative_to(folder).as_posix() for p in sorted(folder.rglob("*"))]
    ['logs', 'logs/a.csv']
    """
    return _renamed_when_done(paths, folders=True)


def atomic_write_bytes(path: Path | str, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; return the path.

    Examples
    --------
    >>> import tempfile
    >>> atomic_write_bytes(Path(tempfile.mkdtemp()) / "weights.bin", b"1").read_bytes()
    b'1'
    """
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def atomic_write_text(path: Path | str, text: str) -> Path:
    """Write ``text`` (UTF-8, line ends as given) to ``path`` atomically; return the path.

    Examples
    --------
    >>> import tempfile
    >>> atomic_write_text(Path(tempfile.mkdtemp()) / "stats.md", "# H1\\n").read_text()
    '# H1\\n'
    """
    return atomic_write_bytes(path, text.encode("utf-8"))


def frame_to_csv_text(frame: pd.DataFrame) -> str:
    """A table as CSV text: header, ``\\n`` line ends, shortest round-trip floats, no index.

    The same table always gives the same bytes, which keeps processed tables reproducible.

    Examples
    --------
    >>> frame_to_csv_text(pd.DataFrame({"t": [0.0, 0.05], "keys": ["x+", ""]}))
    't,keys\\n0.0,x+\\n0.05,\\n'
    """
    text = plain_csv_text(frame)  # the same text, faster, for a table of plain columns
    if text is not None:
        return text
    buffer = io.StringIO()
    frame.to_csv(buffer, index=False, lineterminator="\n")
    return buffer.getvalue()


def write_csv(path: Path | str, frame: pd.DataFrame) -> Path:
    """Write a table as CSV (:func:`frame_to_csv_text`) atomically; return the path.

    Examples
    --------
    >>> import tempfile
    >>> path = write_csv(Path(tempfile.mkdtemp()) / "t.csv", pd.DataFrame({"x": [0.5]}))
    >>> path.read_text()
    'x\\n0.5\\n'
    """
    return atomic_write_text(path, frame_to_csv_text(frame))
