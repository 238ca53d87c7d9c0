"""How a ``casa`` command ends on an error: a message on stderr and its exit status.

One rule, that of :func:`casa_core.cli.main`: a file or folder that could not be read or
written (an :class:`OSError`: missing, unreadable, read-only, disk full) ends the command
with exit status 1; an input that cannot be used (a bad argument, or a config, scene,
table or log that breaks a rule: a :class:`ValueError`, or a message) with exit status 2.
``casa validate`` finding problems in the files it read ends with 1, by its own rule.
"""

from __future__ import annotations

import sys


def fail(command: str, error: Exception | str) -> int:
    """Print ``casa COMMAND: error`` on stderr; return 1 for an OSError, else 2."""
    print(f"casa {command}: {error}", file=sys.stderr)
    return 1 if isinstance(error, OSError) else 2


def cannot_write(command: str, folder, error: OSError) -> int:
    """Say that ``folder`` could not take the command's outputs (read-only, full); return 1."""
    reason = error.strerror or str(error)
    print(
        f"casa {command}: cannot write into {folder}: {reason} (is the folder writable, "
        "the disk full?); the files already there are unchanged",
        file=sys.stderr,
    )
    return 1
