"""The commands work from any folder: without --config or --scene they take the package's own.

Each test runs from a temporary folder that holds no config/ (docs/session.md: run it
from any folder), as a lab running ``casa`` from its own data folder does.
"""

from __future__ import annotations

import os

import pytest

from casa_core.cli import all_parsers, build_parser, main
from casa_core.config import DEFAULT_CONFIG
from casa_core.scene import DEFAULT_SCENE
from tests.io.test_logs_synthetic import write_dataset


@pytest.fixture
def elsewhere(tmp_path, monkeypatch):
    """A working directory outside the repository, without config/ or benchmarks/."""
    folder = tmp_path / "elsewhere"
    folder.mkdir()
    monkeypatch.chdir(folder)
    return folder


def test_simulate_without_config_takes_the_packages_settings(elsewhere, capsys):
    # The learn stage of a participant without demonstrations: the config and the scene
    # are read, nothing is learned (quick).
    (elsewhere / "before").mkdir()
    args = ["simulate", "learn", "--participant", "1", "--before", "before"]
    args += ["--task", "unknown_goal", "--library", "lib", "--out", "row.csv"]
    assert main(args) == 0, capsys.readouterr().err
    assert "participant p01, 1 table(s) written" in capsys.readouterr().out
    assert (elsewhere / "row.csv").is_file()


def test_stats_without_config_takes_the_packages_margins(elsewhere, capsys):
    write_dataset(elsewhere / "raw", participants=("p01", "p02"))
    assert main(["process", "raw", "--out", "tables"]) == 0, capsys.readouterr().err
    args = ["stats", "--trials", "tables/trials.csv", "--out-csv", "s.csv", "--out-md", "s.md"]
    assert main(args) == 0, capsys.readouterr().err


@pytest.mark.parametrize("command", ["simulate", "case-study", "stats", "session"])
def test_the_config_help_says_what_is_read_without_it(command):
    text = _help(command)
    assert "default: the package's own settings" in text, command
    assert "config/config.yaml" in text and "from any folder" in text


def _help(command: str) -> str:
    """``casa COMMAND --help``, its whitespace collapsed."""
    parser = next(p for p in all_parsers(build_parser()) if p.prog == f"casa {command}")
    return " ".join(parser.format_help().split())


def test_process_without_scene_takes_the_datasets_own_else_the_packages(
    elsewhere, capsys, monkeypatch
):
    from casa_core import scene as scenes

    read = []
    real = scenes.load_scene
    monkeypatch.setattr(scenes, "load_scene", lambda path=None: read.append(path) or real(path))
    write_dataset(elsewhere / "raw", participants=("p01",), surveys=False)
    assert main(["process", "raw", "--out", "tables"]) == 0, capsys.readouterr().err
    assert read[0] is None  # the package's scene
    own = elsewhere / "raw" / "scene.yaml"
    own.write_text(DEFAULT_SCENE.read_text(encoding="utf-8"), encoding="utf-8")
    assert main(["process", "raw", "--out", "tables"]) == 0, capsys.readouterr().err
    assert read[-1] == own.relative_to(elsewhere)
    # A scene given wins over the dataset's.
    assert main(["process", "raw", "--out", "tables", "--scene", str(DEFAULT_SCENE)]) == 0
    assert read[-1] == DEFAULT_SCENE
    assert "--scene YAML scene file (default: RAW_DIR/scene.yaml if the dataset has one" in (
        _help("process")
    )


def _benchmark(path, end: float) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("s\th:m:s\n5.0\t0:00:05\n", encoding="utf-8")
    os.utime(path, (end, end))


def test_progress_without_a_benchmark_folder_says_where_it_looked(elsewhere, capsys):
    assert main(["progress", "power", "--config", str(DEFAULT_CONFIG)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert f"no benchmark folder {elsewhere / 'benchmarks'}" in captured.err
    assert "--benchmarks" in captured.err and "workflow's folder" in captured.err


def test_progress_reads_a_workflow_elsewhere_with_its_own_unit_configs(elsewhere, tmp_path, capsys):
    # A replicate whose every job has a benchmark, older than its config in the
    # workflow's data/interim: from an earlier configuration, so not counted. The config
    # is found beside the benchmark folder given, not below the working directory.
    workflow = tmp_path / "workflow"
    overlay = tmp_path / "small.yaml"
    overlay.write_text("power: {sizes: [2], replicates: 1}\n", encoding="utf-8")
    config = workflow / "data" / "interim" / "power" / "default" / "r1" / "config.yaml"
    config.parent.mkdir(parents=True)
    config.write_text("{}\n", encoding="utf-8")
    for job in ("participants", "process", "detect"):
        _benchmark(workflow / "benchmarks" / "power" / "default" / "r1" / f"{job}.tsv", 1000.0)
    args = ["progress", "power", "--config", str(DEFAULT_CONFIG), "--config", str(overlay)]
    args += ["--benchmarks", str(workflow / "benchmarks")]
    assert main(args) == 0, capsys.readouterr().err
    assert capsys.readouterr().out.startswith("power: 0/1 replicates done (0/3 jobs)")
    os.utime(config, (500.0, 500.0))  # the config older: the benchmarks count
    assert main(args) == 0
    assert capsys.readouterr().out.startswith("power: 1/1 replicates done (3/3 jobs)")
