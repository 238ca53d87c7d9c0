"""Why a workflow run failed, said last: each failed job's own message, from its log.

Snakemake lists every input of a failed job, once when it starts and again when it
fails; for a dataset that is every raw file, and the job's own message (the file, key
or column and the rule it breaks) scrolls away among them. The workflow's ``onerror:``
handler prints :func:`failure_summary` instead, after all of that: for each job that
failed (its ``Error in rule`` block in Snakemake's log), the last lines of the job's own
log, and the ``allow_invalid`` hint where bad files stopped it.

Examples
--------
>>> import tempfile
>>> folder = Path(tempfile.mkdtemp())
>>> _ = (folder / "validate.log").write_text("p1/a.json: key 'task': [enum] is 'x'\\n")
>>> text = f"Error in rule validate:\\n    jobid: 1\\n    log: {folder}/validate.log\\n"
>>> [job.rule for job in failed_jobs(text)]
['validate']
>>> print(failure_summary(text, allow_invalid=True).splitlines()[-1])
  p1/a.json: key 'task': [enum] is 'x'
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

#: Lines of a job's log shown: enough for the last problems and the checker's count.
TAIL_LINES = 20
#: The rules that take ``--config allow_invalid=true`` (they exclude bad files with it).
ALLOW_INVALID_RULES = ("validate", "process", "replay")
#: How those rules' logs say that bad files stopped them (casa validate, casa replay).
INVALID_WORD = re.compile(r"\binvalid\b")
ALLOW_INVALID_HINT = (
    "to build the dataset without its bad files (excluded and listed in its "
    "validation.csv), rerun with --config allow_invalid=true"
)

_ERROR = re.compile(r"^Error in rule (\S+):$")
_LOG = re.compile(r"^\s+log: (.+?)(?: \(check log file\(s\) for error details\))?$")


@dataclass(frozen=True)
class FailedJob:
    """A job that failed: its rule and the log files it wrote."""

    rule: str
    logs: tuple[str, ...]


def failed_jobs(text: str) -> list[FailedJob]:
    """The jobs of Snakemake's log ``text`` that failed, in the order they failed.

    Examples
    --------
    >>> failed_jobs("Error in rule stats:\\n    jobid: 3\\n    log: a.log, b.log (check log "
    ...             "file(s) for error details)\\nError in rule figure:\\n    jobid: 4\\n")
    [FailedJob(rule='stats', logs=('a.log', 'b.log')), FailedJob(rule='figure', logs=())]
    """
    jobs: list[FailedJob] = []
    rule: str | None = None
    logs: tuple[str, ...] = ()
    for line in text.splitlines():
        started = _ERROR.match(line)
        if started or (rule is not None and not line.startswith(" ")):
            if rule is not None:
                jobs.append(FailedJob(rule, logs))
            rule, logs = (started.group(1), ()) if started else (None, ())
            continue
        found = _LOG.match(line) if rule is not None else None
        if found:
            logs = tuple(part.strip() for part in found.group(1).split(","))
    if rule is not None:
        jobs.append(FailedJob(rule, logs))
    return jobs


def _tail(path: Path) -> list[str]:
    """The last :data:`TAIL_LINES` lines of a log, and how many came before them."""
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError:
        return [f"  (no log {path})"]
    shown = [f"  {line}" for line in lines[-TAIL_LINES:]] or ["  (the log is empty)"]
    earlier = len(lines) - TAIL_LINES
    return ([f"  ({earlier} earlier line(s) in {path})"] if earlier > 0 else []) + shown


def failure_summary(text: str, *, allow_invalid: bool) -> str:
    """What each failed job of Snakemake's log ``text`` said itself, to be printed last.

    Per job, its rule and log, the log's last lines, and :data:`ALLOW_INVALID_HINT` where
    a rule of :data:`ALLOW_INVALID_RULES` stopped on invalid files and ``allow_invalid``
    is off. Empty if no job failed (the run stopped before any job ran).

    Examples
    --------
    >>> print(failure_summary("Error in rule figure:\\n    jobid: 4\\n", allow_invalid=False))
    casa: 1 job(s) failed; what each said (its log's last lines):
    rule figure failed; it has no log:
    """
    jobs = failed_jobs(text)
    if not jobs:
        return ""
    lines = [f"casa: {len(jobs)} job(s) failed; what each said (its log's last lines):"]
    for job in jobs:
        lines.append(f"rule {job.rule} failed; {', '.join(job.logs) or 'it has no log'}:")
        said: list[str] = []
        for log in job.logs:
            said += _tail(Path(log))
        lines += said
        invalid = any(INVALID_WORD.search(line) for line in said)
        if job.rule in ALLOW_INVALID_RULES and invalid and not allow_invalid:
            lines.append(f"  hint: {ALLOW_INVALID_HINT}")
    return "\n".join(lines)
