"""profiles/slurm on a real single-node Slurm cluster, against a local run of the same DAG.

The cluster (tests/single_node_slurm.py) is started from Debian's packages for this test
and stopped by its daemons' pids after it. The DAG is one simulated participant's whole
protocol of the CI configuration (one job: simulation before learning, one learned intent
per unknown task, simulation after learning) and the case study with its figure: every kind
of job the study has (directory outputs, torch, fan-out and fan-in), at a quarter of the CI
target's CPU time, since the test runs it twice. Job states come from squeue, as on a
cluster without accounting; where the cluster has accounting, a second test reads them
from sacct, the plugin's default. Docs: docs/cluster.md.
"""

from __future__ import annotations

import importlib.util
import re
import subprocess
from collections import Counter
from pathlib import Path

import pytest

from tests.single_node_slurm import Cluster, accounting_why_not, why_not
from tests.workflow.test_workflow import BIN, ENV, copy_workflow

TARGETS = ("data/raw/simulated/p1/after", "figures/case_study.png")
#: The Slurm jobs of TARGETS, by construction of the workflow's rules (study.smk,
#: figures.smk): one participant's protocol and the case study with its figure.
EXPECTED_JOBS = Counter(
    {
        "simulated_participant": 1,
        "case_study": 1,
        "figure_case_study": 1,
    }
)
# Last: --configfile takes every word after it as a file.
COMMON = ("--configfile", "config/ci.yaml")
# Job states read at once and then every few seconds (the plugin's first wait is 40 s);
# --verbose logs which command read them.
SLURM = (
    "--workflow-profile",
    "profiles/slurm",
    "--slurm-init-seconds-before-status-checks",
    "2",
    "--verbose",
)
# A cluster without accounting: states from squeue, as profiles/slurm's comment says.
SQUEUE = ("--slurm-status-command", "squeue")
TIMEOUT = 1800


def _skip_reason() -> str | None:
    if importlib.util.find_spec("snakemake_executor_plugin_slurm") is None:
        return 'snakemake-executor-plugin-slurm not installed (pip install -e ".[cluster]")'
    return why_not()


pytestmark = [
    pytest.mark.pipeline,
    pytest.mark.skipif(_skip_reason() is not None, reason=str(_skip_reason())),
]


@pytest.fixture(scope="module")
def cluster():
    running = Cluster(accounting=accounting_why_not() is None)
    try:
        yield running.start()
    finally:
        running.stop()


def _snakemake(workdir: Path, *args: str, targets=TARGETS) -> subprocess.Popen:
    with open(workdir / "snakemake.out", "wb") as log:  # the child keeps its own copy
        return subprocess.Popen(
            [str(BIN / "snakemake"), *args, *targets, *COMMON],
            cwd=workdir,
            env=ENV,
            stdout=log,
            stderr=subprocess.STDOUT,
        )


def _finish(proc: subprocess.Popen, workdir: Path) -> str:
    try:
        proc.wait(timeout=TIMEOUT)
    finally:
        if proc.poll() is None:
            proc.terminate()
            proc.wait(timeout=60)
    text = (workdir / "snakemake.out").read_text(errors="replace")
    assert proc.returncode == 0, f"{workdir.name}: snakemake failed\n{text[-4000:]}"
    return text


def _outputs(workdir: Path) -> dict[str, bytes]:
    """Every file of data/ and figures/ but measured times (``*timing*``) and markers."""
    return {
        path.relative_to(workdir).as_posix(): path.read_bytes()
        for top in ("data", "figures")
        for path in sorted((workdir / top).rglob("*"))
        if path.is_file() and "timing" not in path.name and path.name != ".snakemake_timestamp"
    }


def _status_commands(log: str) -> set[str]:
    """The commands the plugin read job states with (its --verbose timing lines)."""
    return set(re.findall(r"Status query timing \(cycle\): command=(\w+)", log))


def _rule(comment: str) -> str:
    """The rule of a job from its Slurm comment: ``rule_<name>[_wildcards_<values>]``."""
    return comment.removeprefix("rule_").split("_wildcards_")[0]


def test_the_slurm_profile_runs_the_dag_through_slurm_with_the_local_outputs(
    cluster, tmp_path_factory
):
    local = copy_workflow(tmp_path_factory.mktemp("local"))
    on_slurm = copy_workflow(tmp_path_factory.mktemp("slurm"))
    # The local reference runs beside the Slurm run: its 2 cores fill the cluster's idle
    # moments (job starts, status polls).
    reference = _snakemake(local, "--cores", "2")
    try:
        log = _finish(_snakemake(on_slurm, *SLURM, *SQUEUE), on_slurm)
    finally:
        _finish(reference, local)

    # Every non-local job went through Slurm and completed there: squeue (MinJobAge)
    # lists them by rule, and slurmctld's job-completion log has each of them.
    jobs = [j for j in cluster.jobs() if Path(j["workdir"]) == on_slurm]
    assert Counter(_rule(j["comment"]) for j in jobs) == EXPECTED_JOBS, jobs
    assert {j["state"] for j in jobs} == {"COMPLETED"}, jobs
    assert Counter(re.findall(r"^rule (\w+):$", log, re.M)) == EXPECTED_JOBS, log[-4000:]
    completed = {
        m["id"]
        for m in re.finditer(
            r"JobId=(?P<id>\d+) .*JobState=COMPLETED .*WorkDir=(?P<dir>\S+)",
            cluster.jobcomp.read_text(),
        )
        if Path(m["dir"]) == on_slurm
    }
    assert completed == {j["id"] for j in jobs}
    assert _status_commands(log) == {"squeue"}
    if cluster.accounting:
        accounted = [j for j in cluster.accounted_jobs() if Path(j["workdir"]) == on_slurm]
        assert sorted(accounted, key=str) == sorted(jobs, key=str)

    # The same bytes as on one machine, tables, trial logs, intents and figures alike.
    expected, produced = _outputs(local), _outputs(on_slurm)
    assert sorted(produced) == sorted(expected)
    assert [name for name in expected if produced[name] != expected[name]] == []
    for part in ("p1/before/", "p1/after/", "p1/intents/", "case_study/steps.csv"):
        assert any(part in name and name.endswith((".csv", ".json")) for name in expected), part


@pytest.mark.skipif(accounting_why_not() is not None, reason=str(accounting_why_not()))
def test_with_accounting_the_profile_reads_job_states_from_sacct(cluster, tmp_path_factory):
    # The plugin's default, as on most clusters: slurmdbd keeps the jobs, sacct reads them.
    workdir = copy_workflow(tmp_path_factory.mktemp("sacct"))
    log = _finish(_snakemake(workdir, *SLURM, targets=("figures/scene.png",)), workdir)
    assert _status_commands(log) == {"sacct"}
    jobs = [j for j in cluster.accounted_jobs() if Path(j["workdir"]) == workdir]
    assert [(_rule(j["comment"]), j["state"]) for j in jobs] == [("figure_scene", "COMPLETED")]
    assert (workdir / "figures" / "scene.png").read_bytes()[:4] == b"\x89PNG"
