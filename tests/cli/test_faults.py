"""Faults: a full disk, a read-only folder, a killed run.

Each case checks what a user is promised: a clear message naming the folder and no
traceback; the earlier results left as they were; after a SIGKILL of Snakemake no job
of it still running, and a rerun of the same command ending with the bytes of a run
that was never interrupted.
"""

from __future__ import annotations

import errno
import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import pytest

from casa_core.cli import main
from tests.io.test_logs_synthetic import ROOT, write_dataset
from tests.workflow.test_workflow import BIN, ENV, copy_workflow, snakemake

SCENE = str(ROOT / "config" / "scene.yaml")
TABLES = ("trials.csv", "steps.csv", "likert.csv")


def contents(folder: Path) -> dict[str, bytes]:
    """Every file below ``folder`` (hidden ones too: a left temporary file shows)."""
    return {
        p.relative_to(folder).as_posix(): p.read_bytes()
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


@pytest.fixture
def processed(tmp_path):
    """A dataset, its tables written once, and a second dataset whose tables differ."""
    write_dataset(tmp_path / "raw" / "first", participants=("p01", "p02", "p03"))
    write_dataset(tmp_path / "raw" / "second", participants=("p03",), seed=1)
    out = tmp_path / "out"
    assert (
        main(["process", str(tmp_path / "raw" / "first"), "--out", str(out), "--scene", SCENE]) == 0
    )
    return tmp_path, out


def test_a_full_disk_leaves_all_three_tables_as_they_were(processed, monkeypatch, capsys):
    tmp_path, out = processed
    before = contents(out)
    real_write = Path.write_bytes
    calls = []

    def write_until_full(self, data):
        calls.append(self.name)
        if len(calls) == 2:  # trials.csv's temporary is written, steps.csv's is not
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_write(self, data)

    monkeypatch.setattr(Path, "write_bytes", write_until_full)
    raw = str(tmp_path / "raw" / "second")
    capsys.readouterr()
    assert main(["process", raw, "--out", str(out), "--scene", SCENE]) == 1
    error = capsys.readouterr().err
    assert f"cannot write into {out}: No space left on device" in error
    assert "unchanged" in error and "Traceback" not in error
    assert len(calls) == 2
    # The old set, byte for byte, and no temporary file left beside it.
    assert contents(out) == before


def _unwritable(folder: Path) -> bool:
    """Make ``folder`` read-only; for root (who ignores modes) also immutable."""
    folder.chmod(0o555)
    if os.geteuid() == 0:
        subprocess.run(["chattr", "+i", str(folder)], capture_output=True, check=False)
    try:
        (folder / ".probe").touch()
    except OSError:
        return True
    (folder / ".probe").unlink()
    return False


def _writable(folder: Path) -> None:
    if os.geteuid() == 0:
        subprocess.run(["chattr", "-i", str(folder)], capture_output=True, check=False)
    folder.chmod(0o755)


def test_a_read_only_folder_fails_clearly_and_keeps_earlier_results(processed, capsys):
    tmp_path, out = processed
    stats = ["stats", "--trials", str(out / "trials.csv"), "--out-csv", str(out / "stats.csv")]
    stats += ["--out-md", str(out / "stats.md")]
    assert main(stats) == 0
    before = contents(out)
    if not _unwritable(out):
        _writable(out)
        pytest.skip("this file system lets the folder be written whatever its mode")
    try:
        raw = str(tmp_path / "raw" / "second")
        commands = {
            "process": ["process", raw, "--out", str(out), "--scene", SCENE],
            "validate": ["validate", raw, "--report", str(out / "validation.csv")],
            "stats": stats,
        }
        for name, command in commands.items():
            capsys.readouterr()
            assert main(command) == 1, name
            error = capsys.readouterr().err
            assert f"casa {name}: cannot write into {out}: " in error, error
            assert "Traceback" not in error, error
        assert contents(out) == before
    finally:
        _writable(out)


def test_every_command_reports_an_unwritable_output_without_a_traceback(tmp_path, capsys):
    # A command that writes trial logs (the simulation) names the file it could not write
    # and ends without a traceback; commands without a message of their own get one from
    # casa_core.cli.main.
    out = tmp_path / "before"
    out.mkdir()
    if not _unwritable(out):
        _writable(out)
        pytest.skip("this file system lets the folder be written whatever its mode")
    try:
        config = ["--config", str(ROOT / "config" / "config.yaml")]
        config += ["--config", str(ROOT / "config" / "ci.yaml")]
        capsys.readouterr()
        code = main(["simulate", "before", *config, "--participant", "1", "--out", str(out)])
        error = capsys.readouterr().err
        assert code != 0 and error.startswith("casa simulate") and str(out) in error, error
        assert "Traceback" not in error
        assert list(out.iterdir()) == []
    finally:
        _writable(out)


def test_main_turns_any_file_error_into_a_message(monkeypatch, capsys):
    # The last resort for a handler without a message of its own: the file and the reason.
    from casa_core.cli import validate

    def fails(args):
        raise PermissionError(13, "Permission denied", "/lab/out/trials.csv")

    monkeypatch.setattr(validate, "_validate", fails)
    assert main(["validate", "anything"]) == 1
    error = capsys.readouterr().err
    assert error.startswith("casa validate: cannot read or write /lab/out/trials.csv: ")
    assert "Permission denied" in error and "Traceback" not in error


# -- the DAG ------------------------------------------------------------------------------

TARGET = ("data/processed/pilot/stats.csv", "--config", "simulate=false")


@pytest.fixture
def repo(tmp_path):
    copy_workflow(tmp_path)
    write_dataset(tmp_path / "data" / "raw" / "pilot", participants=("p01", "p02", "p03"))
    return tmp_path


@pytest.mark.pipeline
def test_statistics_beside_deleted_or_regenerated_tables_are_rebuilt(repo):
    assert snakemake(repo, *TARGET).returncode == 0
    processed = repo / "data" / "processed" / "pilot"
    stats = processed / "stats.csv"
    first = stats.stat().st_mtime_ns
    # Tables deleted (as a failed processing step leaves them): Snakemake alone would keep
    # the statistics of the tables that are gone; the dry run says they will be rebuilt.
    (processed / "trials.csv").unlink()
    dry = snakemake(repo, "--dry-run", *TARGET)
    assert f"{stats.relative_to(repo)}: its tables are missing" in dry.stderr, dry.stderr
    assert stats.is_file()  # a dry run changes nothing
    result = snakemake(repo, *TARGET)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "rule process" in result.stdout + result.stderr
    second = stats.stat().st_mtime_ns
    assert second > first and (processed / "stats.md").stat().st_mtime_ns > first
    # Regenerated tables with other rows rerun the statistics (newer and another checksum;
    # Snakemake reruns nothing for the same bytes, which give the same statistics).
    trials = processed / "trials.csv"
    trials.write_text("".join(trials.read_text().splitlines(keepends=True)[:-1]))
    later = time.time() + 10
    os.utime(trials, (later, later))
    dry = snakemake(repo, "--dry-run", *TARGET)
    table = dry.stdout.split("Job stats:")[1].split("total")[0].splitlines()
    assert [line.split()[0] for line in table[3:] if line.strip()] == ["stats"], dry.stdout


def _processes_in(folder: Path) -> list[str]:
    """The command lines of the processes running in ``folder`` (their working directory)."""
    found = []
    for proc in Path("/proc").iterdir():
        if not proc.name.isdigit():
            continue
        try:
            if Path(os.readlink(proc / "cwd")) != folder:
                continue
            state = (proc / "stat").read_text().rsplit(")", 1)[1].split()[0]
            command = (proc / "cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue  # ended meanwhile, or not ours to read
        if state != "Z":
            found.append(command)
    return found


def _wait_for(condition, timeout: float) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.05)
    return False


def _kill_when(repo: Path, point) -> None:
    """Start the run, SIGKILL Snakemake once ``point(repo)``; no job of it may remain."""
    run = subprocess.Popen(
        [str(BIN / "snakemake"), "--cores", "1", *TARGET],
        cwd=repo,
        env=ENV,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,  # so that cleanup below can reach a stray job
    )
    try:
        assert _wait_for(lambda: point(repo.resolve()), 60), (
            "the run ended before the point to kill it"
        )
        run.send_signal(signal.SIGKILL)
        run.wait(timeout=10)
        gone = _wait_for(lambda: not _processes_in(repo.resolve()), 2)
        assert gone, f"still running after Snakemake's SIGKILL: {_processes_in(repo.resolve())}"
    finally:
        try:
            os.killpg(run.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


@pytest.mark.pipeline
def test_a_run_killed_anywhere_and_rerun_gives_the_bytes_of_an_uninterrupted_run(tmp_path):
    # The reference: the same DAG, never interrupted.
    reference = copy_workflow(tmp_path / "reference")
    write_dataset(reference / "data" / "raw" / "pilot", participants=("p01", "p02", "p03"))
    result = snakemake(reference, *TARGET)
    assert result.returncode == 0, result.stderr[-3000:]
    expected = contents(reference / "data" / "processed")
    assert {"pilot/validation.csv", "pilot/trials.csv", "pilot/stats.csv"} <= set(expected)

    processed = Path("data") / "processed" / "pilot"
    points = {
        # validate's casa command running
        "validating": lambda repo: any(" validate " in c for c in _processes_in(repo)),
        # the tables being built from the validated logs
        "processing": lambda repo: any(" process " in c for c in _processes_in(repo)),
        # after trials.csv, while the statistics (seconds long) are computed: a job left
        # running would still run when the check below looks
        "computing statistics": lambda repo: (
            (repo / processed / "trials.csv").is_file()
            and any(" stats " in c for c in _processes_in(repo))
        ),
    }
    for name, point in points.items():
        repo = copy_workflow(tmp_path / name)
        shutil.copytree(reference / "data" / "raw", repo / "data" / "raw")
        _kill_when(repo, point)
        # A killed Snakemake leaves its lock: removed as `snakemake --unlock` does (which
        # its message asks for), then the same command; rerun-incomplete (profiles/default)
        # redoes a half-finished job.
        shutil.rmtree(repo / ".snakemake" / "locks")
        result = snakemake(repo, *TARGET)
        assert result.returncode == 0, (name, result.stderr[-3000:])
        assert contents(repo / "data" / "processed") == expected, name
