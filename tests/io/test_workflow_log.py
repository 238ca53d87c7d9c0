"""Why a run failed, from Snakemake's log: each failed job's rule, log tail and hint."""

from __future__ import annotations

from casa_core.io.workflow_log import (
    ALLOW_INVALID_HINT,
    TAIL_LINES,
    FailedJob,
    failed_jobs,
    failure_summary,
)

# Two failed jobs as Snakemake 9.27 writes them to its log (a run of tests/workflow).
SNAKEMAKE_LOG = """\
[Mon Dec  7 09:15:19 2026]
Error in rule validate:
    message: None
    jobid: 1
    input: data/raw/pilot/p01/a.csv, data/raw/pilot/p01/a.json
    output: data/processed/pilot/validation.csv
    log: {validate} (check log file(s) for error details)
    shell:
        exec casa validate data/raw/pilot --report data/processed/pilot/validation.csv
        (command exited with non-zero exit code)
Removing output files of failed job validate since they might be corrupted:
data/processed/pilot/validation.csv
[Mon Dec  7 09:15:20 2026]
Error in rule stats:
    message: None
    jobid: 4
    log: {stats} (check log file(s) for error details)
Exiting because a job execution failed. Look above for error messages
"""


def _logs(tmp_path, validate: str, stats: str) -> str:
    paths = {"validate": tmp_path / "validate.log", "stats": tmp_path / "stats.log"}
    paths["validate"].write_text(validate)
    paths["stats"].write_text(stats)
    return SNAKEMAKE_LOG.format(**{name: str(path) for name, path in paths.items()})


def test_each_failed_job_is_found_with_its_log(tmp_path):
    text = _logs(tmp_path, "", "")
    assert failed_jobs(text) == [
        FailedJob("validate", (str(tmp_path / "validate.log"),)),
        FailedJob("stats", (str(tmp_path / "stats.log"),)),
    ]
    assert failure_summary("Building DAG of jobs...\n", allow_invalid=False) == ""


def test_the_summary_shows_each_logs_tail_and_the_hint_only_where_it_applies(tmp_path):
    problems = [f"p1/t{i}.csv: column 'x': [finite-number] got 'far'" for i in range(30)]
    checked = "casa validate: 30 trial(s) checked, 30 invalid, 30 problem(s)"
    text = _logs(tmp_path, "\n".join([*problems, checked]) + "\n", "invalid margin\n")
    lines = failure_summary(text, allow_invalid=False).splitlines()
    # validate's last TAIL_LINES lines (the count last), then the hint; stats' line, no hint.
    log = tmp_path / "validate.log"
    start = lines.index(f"rule validate failed; {log}:")
    assert lines[start + 1] == f"  ({31 - TAIL_LINES} earlier line(s) in {log})"
    assert lines[start + 2 : start + 2 + TAIL_LINES] == [
        f"  {line}" for line in [*problems, checked][-TAIL_LINES:]
    ]
    assert lines[start + 2 + TAIL_LINES] == f"  hint: {ALLOW_INVALID_HINT}"
    assert lines[-2:] == [f"rule stats failed; {tmp_path / 'stats.log'}:", "  invalid margin"]
    # With allow_invalid already on, the hint would not help.
    assert "hint:" not in failure_summary(text, allow_invalid=True)
