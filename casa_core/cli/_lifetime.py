"""A ``casa`` command run by the workflow ends when the workflow's Snakemake process dies.

Snakemake gives each job its own pid in :data:`PARENT_VARIABLE` and runs it with
``exec``, so the command is Snakemake's direct child. On Linux the command then asks
the kernel for SIGTERM when its parent dies (``prctl(PR_SET_PDEATHSIG)``), so that a
Snakemake killed with SIGKILL leaves no job running; SIGTERM unwinds like an error,
so :mod:`casa_core.io.atomic` removes its temporary files and earlier outputs stay.
Outside the workflow (the variable unset) nothing changes: ``nohup casa ...`` still
outlives its shell.
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys

#: The variable the workflow sets to Snakemake's pid (workflow/rules/common.smk).
PARENT_VARIABLE = "CASA_PARENT_PID"
#: ``PR_SET_PDEATHSIG`` of ``<linux/prctl.h>``.
_PR_SET_PDEATHSIG = 1


def _terminated(signum, frame):
    raise SystemExit(128 + signum)


def end_with_parent() -> None:
    """Under the workflow on Linux: exit on SIGTERM, and get SIGTERM when Snakemake dies."""
    parent = os.environ.get(PARENT_VARIABLE, "")
    if not parent.isdigit() or not sys.platform.startswith("linux"):
        return
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(_PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0) != 0:
            return
    except (OSError, AttributeError):
        return
    signal.signal(signal.SIGTERM, _terminated)
    # Snakemake may have died before the request above: then this process is an orphan.
    if os.getppid() != int(parent):
        raise SystemExit(128 + signal.SIGTERM)
