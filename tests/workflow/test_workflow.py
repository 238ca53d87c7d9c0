"""The Snakemake DAG, run for real on a temporary copy of the workflow.

Steps whose ``casa`` subcommand exists (validate, process) are run; the rest of
the default target is checked with a dry run, which resolves every rule,
wildcard and input without running it.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.io.test_logs_synthetic import ROOT, write_dataset

BIN = Path(sys.executable).parent
# Not named: the README's plain command must read profiles/default by itself.
PROFILE = "profiles/default"
ENV = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}

pytestmark = pytest.mark.pipeline


def snakemake(workdir: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [str(BIN / "snakemake"), "--cores", "1", *args],
        cwd=workdir,
        env=ENV,
        capture_output=True,
        text=True,
        timeout=300,
    )


def copy_workflow(folder: Path) -> Path:
    """The Snakefile, the workflow, its profiles and the configs copied into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    for name in ("Snakefile", "workflow", "config", "profiles"):
        source = ROOT / name
        if source.is_dir():
            shutil.copytree(source, folder / name)
        else:
            shutil.copy(source, folder / name)
    return folder


@pytest.fixture
def repo(tmp_path):
    """The workflow and its configs copied next to a data/raw with two synthetic datasets."""
    copy_workflow(tmp_path)
    write_dataset(tmp_path / "data" / "raw" / "pilot", participants=("p01", "p02"))
    conditions = [("known_goal", m, "no_misspecification") for m in ("NA", "CASA")]
    write_dataset(
        tmp_path / "data" / "raw" / "lab",
        participants=("h1",),
        surveys=False,
        conditions=conditions,
    )
    return tmp_path


def test_lint_is_clean(repo):
    result = snakemake(repo, "--lint")
    assert result.returncode == 0, result.stdout + result.stderr
    assert "Congratulations" in result.stdout + result.stderr


def test_default_target_covers_every_output_of_every_dataset(repo):
    result = snakemake(repo, "--dry-run")
    assert result.returncode == 0, result.stderr
    text = result.stdout + result.stderr
    for ds in ("pilot", "lab"):
        for name in ("trials", "steps", "likert", "stats", "wide", "validation"):
            assert f"data/processed/{ds}/{name}.csv" in text
        assert f"data/processed/{ds}/stats.md" in text
        assert f"figures/{ds}/objective.pdf" in text and f"figures/{ds}/objective.png" in text
    assert "figures/scene.png" in text
    # Likert figures only where there are surveys.
    assert "figures/pilot/likert.png" in text and "figures/lab/likert" not in text
    # Every rule writes a log.
    assert "log: logs/validate/pilot.log" in text


def test_tables_are_built_and_a_new_dataset_is_picked_up(repo):
    targets = [f"data/processed/{ds}/trials.csv" for ds in ("pilot", "lab")]
    result = snakemake(repo, *targets)
    assert result.returncode == 0, result.stderr
    processed = repo / "data" / "processed"
    first = {p.name: p.read_bytes() for p in (processed / "pilot").iterdir()}
    assert set(first) == {"trials.csv", "steps.csv", "likert.csv", "validation.csv"}
    # Nothing to do on a rerun.
    again = snakemake(repo, *targets)
    assert "Nothing to be done" in again.stdout + again.stderr
    # A folder dropped into data/raw joins the default target with no config edit.
    write_dataset(repo / "data" / "raw" / "newcomers", participants=("n1",), surveys=False)
    dry = snakemake(repo, "--dry-run")
    assert "data/processed/newcomers/trials.csv" in dry.stdout
    assert "data/processed/pilot/trials.csv" not in dry.stdout.split("Job stats")[0]
    # Same raw files, same bytes.
    shutil.rmtree(processed / "pilot")
    assert snakemake(repo, targets[0]).returncode == 0
    assert {p.name: p.read_bytes() for p in (processed / "pilot").iterdir()} == first
    # A deleted trial is noticed too (rerun-triggers "input" in the default profile).
    for suffix in (".csv", ".json"):
        (
            repo / "data" / "raw" / "pilot" / "p02" / f"known_goal_PBA_no_misspecification{suffix}"
        ).unlink()
    dry = snakemake(repo, "--dry-run", targets[0])
    assert "Set of input files has changed" in dry.stdout


def _break(repo: Path) -> None:
    folder = repo / "data" / "raw" / "pilot" / "p01"
    meta_path = folder / "known_goal_NA_no_misspecification.json"
    meta_path.write_text(json.dumps({**json.loads(meta_path.read_text()), "task": "nope"}))
    (folder / "stray.csv").write_text("t,x\n0,1\n")


def test_a_bad_file_stops_its_dataset_only_and_every_problem_is_listed(repo):
    _break(repo)
    targets = [f"data/processed/{ds}/trials.csv" for ds in ("pilot", "lab")]
    result = snakemake(repo, *targets)
    assert result.returncode != 0
    text = result.stdout + result.stderr
    assert "p01/known_goal_NA_no_misspecification.json: key 'task': [enum]" in text
    assert (
        "p01/stray.json: [pair]" in text and "p01/stray.csv: column 'y': [required-column]" in text
    )
    processed = repo / "data" / "processed"
    # keep-going (profiles/default, read without being named): the other dataset builds.
    assert f"workflow specific profile {PROFILE}" in text
    assert (processed / "lab" / "trials.csv").is_file(), text[-3000:]
    assert not (processed / "pilot" / "trials.csv").exists()
    assert not (processed / "pilot" / "validation.csv").exists()

    # allow_invalid=true: the bad files are excluded and listed.
    result = snakemake(repo, *targets, "--config", "allow_invalid=true")
    assert result.returncode == 0, result.stderr
    validation = (processed / "pilot" / "validation.csv").read_text()
    assert "p01/known_goal_NA_no_misspecification.csv,trial,excluded,enum" in validation
    assert "p01/stray.csv,trial,excluded,pair" in validation
    trials = (processed / "pilot" / "trials.csv").read_text()
    assert "p01/known_goal_NA_no_misspecification" not in trials
    assert "p02/known_goal_NA_no_misspecification" in trials


def test_a_failed_build_ends_on_the_rules_own_message_and_the_hint(repo):
    _break(repo)
    result = snakemake(repo, "data/processed/pilot/trials.csv")
    assert result.returncode != 0
    lines = result.stderr.splitlines()

    def last(text: str) -> int:
        return max([i for i, line in enumerate(lines) if text in line], default=-1)

    # Snakemake lists the job's inputs (every raw file) when it starts and when it fails;
    # then the rule, what it said (file, key, rule broken) and the hint.
    order = [
        last("    input: data/raw/pilot/"),
        last("rule validate failed; logs/validate/pilot.log:"),
        last("p01/known_goal_NA_no_misspecification.json: key 'task': [enum]"),
        last("hint: ") if "--config allow_invalid=true" in lines[last("hint: ")] else -1,
    ]
    assert 0 <= order[0] and order == sorted(order), "\n".join(lines[order[0] :])
    # After the hint only Snakemake's own closing lines: its log, the time, the verdict.
    footer = lines[order[-1] + 1 :]
    assert footer[0].startswith("Complete log(s): ") and len(footer) <= 4, footer


def test_a_badly_named_dataset_folder_fails_alone_with_the_rename_hint(repo):
    for name in ("my data", "robustness"):
        write_dataset(repo / "data" / "raw" / name, participants=("q1",), surveys=False)
    # The default target plans the other datasets, and a failing job per refused folder.
    dry = snakemake(repo, "--dry-run")
    assert dry.returncode == 0, dry.stderr
    assert "data/raw/my data: a dataset folder name must match" in dry.stderr
    for planned in ("logs/refused/my_data.refused", "logs/refused/robustness_data.refused"):
        assert planned in dry.stdout, planned
    assert "data/processed/lab/results.md" in dry.stdout
    # Another dataset named alone: the refused folder is only said to be left out.
    alone = snakemake(repo, "--dry-run", "--config", "datasets=[lab]")
    assert alone.returncode == 0 and "refused_dataset" not in alone.stdout, alone.stderr
    assert "rename it, e.g. to data/raw/my_data, and run again" in alone.stderr
    # The refused folder named as the dataset to build: the same hint, not "not a dataset".
    chosen = snakemake(repo, "--dry-run", "--config", "datasets=[my data]")
    assert chosen.returncode != 0
    said = chosen.stdout + chosen.stderr
    assert "datasets: data/raw/my data is a folder whose name a dataset cannot take" in said
    assert "rename it, e.g. to data/raw/my_data, and choose datasets=[my_data]" in said
    assert "is not a dataset" not in said
    # Run: the other dataset is built, the run fails, and says last how to rename.
    targets = ("data/processed/lab/trials.csv", "logs/refused/my_data.refused")
    result = snakemake(repo, *targets)
    assert result.returncode != 0
    assert (repo / "data" / "processed" / "lab" / "trials.csv").is_file(), result.stderr
    lines = result.stderr.splitlines()
    said = [i for i, line in enumerate(lines) if "rename it, e.g. to data/raw/my_data," in line]
    assert said and lines[said[-1] + 1].startswith("Complete log(s): "), lines[-8:]


FIGURES = ("objective.pdf", "objective.png", "likert.pdf", "likert.png")


def test_default_target_builds_every_table_figure_and_the_report(repo):
    # The whole default target for real on the datasets in data/raw (the simulated study
    # and the case study take minutes; CI builds them with config/ci.yaml), on three
    # participants.
    for ds in ("lab", "pilot"):
        shutil.rmtree(repo / "data" / "raw" / ds)
    write_dataset(repo / "data" / "raw" / "pilot", participants=("p01", "p02", "p03"))
    result = snakemake(repo, "--cores", "2", "--config", "simulate=false")
    assert result.returncode == 0, result.stdout[-3000:]
    processed = repo / "data" / "processed" / "pilot"
    for name in (
        "trials.csv",
        "steps.csv",
        "likert.csv",
        "stats.csv",
        "stats.md",
        "validation.csv",
    ):
        assert (processed / name).stat().st_size > 0, name
    for name in FIGURES:
        head = (repo / "figures" / "pilot" / name).read_bytes()[:8]
        assert head.startswith(b"%PDF" if name.endswith("pdf") else b"\x89PNG"), name
    assert (repo / "figures" / "scene.png").read_bytes()[:4] == b"\x89PNG"
    assert "Nothing to be done" in snakemake(repo, "--dry-run", "--config", "simulate=false").stdout
    report = snakemake(repo, "--report", "report.html", "--config", "simulate=false")
    assert report.returncode == 0, report.stdout[-3000:]
    html = (repo / "report.html").read_text(errors="replace")
    for caption in (
        "Objective metrics of dataset pilot",
        "Likert answers (1-7) of dataset pilot",
        "Statistics of dataset pilot",
        "The scene of the study",
    ):
        assert caption in html


def test_without_simulate_the_simulated_study_is_left_as_it_is(repo):
    # A simulated study already built: its logs and the marker the workflow writes.
    simulated = repo / "data" / "raw" / "simulated"
    write_dataset(simulated, participants=("p1",))
    (simulated / ".complete").touch()
    dry = snakemake(repo, "--dry-run", "--config", "simulate=false")
    assert dry.returncode == 0, dry.stderr
    assert "data/processed/pilot/trials.csv" in dry.stdout
    for folder in ("data/processed/simulated", "figures/simulated", "data/raw/simulated/p"):
        assert folder not in dry.stdout
    assert "data/raw/simulated: the simulated study, left as it is" in dry.stderr


def test_one_dataset_is_built_alone_by_naming_it(repo):
    dry = snakemake(repo, "--dry-run", "--config", "datasets=[lab]")
    assert dry.returncode == 0, dry.stderr
    for output in (
        "data/processed/lab/results.md",
        "data/processed/lab/stats.md",
        "figures/lab/objective.png",
        "data/processed/lab/replay",
    ):
        assert output in dry.stdout, output
    # Nothing else: no other dataset, no simulation, no case study, no variants.
    for other in ("data/processed/pilot", "simulated_participant", "case_study", "robustness"):
        assert other not in dry.stdout, other
    wrong = snakemake(repo, "--dry-run", "--config", "datasets=[nowhere]")
    assert wrong.returncode != 0
    said = wrong.stdout + wrong.stderr
    assert "datasets: nowhere is not a dataset (found: lab, pilot, simulated)" in said


def test_a_dataset_missing_conditions_and_surveys_still_gets_stats_and_figures(repo):
    result = snakemake(repo, "figures/lab/objective.png")
    assert result.returncode == 0, result.stdout[-3000:]
    stats = (repo / "data" / "processed" / "lab" / "stats.csv").read_text()
    assert "missing condition(s): PBA" in stats  # the skipped rows say why


def test_config_overrides_reach_the_package_commands(repo):
    # The package commands read data/interim/config.yaml: what Snakemake sees,
    # `--config` overrides (merged into nested keys) and schema defaults included.
    import yaml

    effective = repo / "data" / "interim" / "config.yaml"
    result = snakemake(repo, "--dry-run", "--config", "simulation={max_duration: 20.0}")
    assert result.returncode == 0, result.stdout + result.stderr
    seen = yaml.safe_load(effective.read_text(encoding="utf-8"))
    assert seen["simulation"]["max_duration"] == 20.0
    assert seen["simulation"]["participants"] == 11  # the rest of the file is kept
    config_file = "config/config.yaml"
    assert (repo / config_file).read_text() == (ROOT / config_file).read_text()  # never edited
    assert snakemake(repo, "--dry-run").returncode == 0
    assert yaml.safe_load(effective.read_text())["simulation"]["max_duration"] == 40.0
    assert effective.stat().st_mode & 0o777 == 0o644  # written by casa_core.io.atomic
    # An unchanged config is not rewritten, so that it reruns nothing.
    before = effective.stat().st_mtime_ns
    assert snakemake(repo, "--dry-run").returncode == 0
    assert effective.stat().st_mtime_ns == before


def test_building_another_dataset_leaves_the_configs_and_the_progress_as_they_are(repo):
    # A finished build: the configs written, then every robustness job's benchmark.
    from casa_core.config import load_config
    from casa_core.experiments.progress import target_units

    assert snakemake(repo, "--dry-run").returncode == 0
    interim = repo / "data" / "interim"
    configs = sorted(interim.rglob("config.yaml"))
    units = target_units(load_config(repo / "config" / "config.yaml"), "robustness")
    assert len(configs) == 1 + len(units)  # the study's and each variant's
    for unit, jobs in units.items():
        folder = repo / "benchmarks" / "robustness" / unit
        folder.mkdir(parents=True)
        for job in jobs:
            (folder / f"{job}.tsv").write_text("s\th:m:s\n1.0\t0:00:01\n")
    written = {path: path.stat().st_mtime_ns for path in configs}
    # Another dataset alone, then another choice of targets: no job reads these keys.
    for choice in ("datasets=[lab]", "simulate=false"):
        assert snakemake(repo, "--dry-run", "--config", choice).returncode == 0
        assert {path: path.stat().st_mtime_ns for path in configs} == written, choice
    progress = subprocess.run(
        [str(BIN / "casa"), "progress", "robustness", "--config", "config/config.yaml"],
        cwd=repo,
        env=ENV,
        capture_output=True,
        text=True,
    )
    assert f"robustness: {len(units)}/{len(units)} variants done" in progress.stdout, progress


def test_the_report_after_a_build_of_one_dataset_covers_what_was_built(repo):
    built = snakemake(repo, "--cores", "2", "--config", "datasets=[lab]")
    assert built.returncode == 0, built.stderr[-3000:]
    # The default target (the simulated study, pilot, the case study...) was not built:
    # the report says what was, without naming the datasets.
    report = snakemake(repo, "--report", "report.html")
    assert report.returncode == 0, report.stderr[-3000:]
    html = (repo / "report.html").read_text(errors="replace")
    assert "Objective metrics of dataset lab" in html and "The scene of the study" in html
    assert "dataset pilot" not in html and "dataset simulated" not in html
