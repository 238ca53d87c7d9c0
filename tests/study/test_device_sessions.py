"""A gamepad instead of the keyboard: `casa teleop` and `casa session` driven by a trace.

A trace is the gamepad's raw frames (docs/devices.md), played one per 0.05 s tick. The
moves below are held at full deflection, so each commands a key's 0.05 m/s and the arm
travels 2.5 mm per tick: the Known Goal (green, (0.58, 0.0, 0.3) from the start
(0.45, -0.22, 0.38) of config/scene.yaml) is 0.13 m in x, 0.22 m in y and -0.08 m in z,
52 + 88 + 32 ticks away.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from casa_core.analysis import build_tables
from casa_core.io import SURVEYS_NAME, read_trial, validate_paths
from casa_core.robot.devices import open_device
from casa_core.scene import load_scene
from casa_core.study.session import SessionRecord
from casa_core.study.teleop_session import TrialCutShort, run_teleop
from tests.display import start_xvfb
from tests.study.test_session import MISSING, SHORT, Operator, drive, session_command, settings
from tests.workflow.test_workflow import copy_workflow, snakemake

#: A gamepad frame's raw axes for a reading: SDL reads stick up and left as negative
#: (x+ is -axis 1, y+ -axis 0, z+ -axis 4, rot+ -axis 3); the triggers rest at -1.
HEADER = "t,axis0,axis1,axis2,axis3,axis4,axis5,button0,button1"


def pad_frame(x=0.0, y=0.0, z=0.0, rot=0.0, finish=0) -> str:
    return f"{-y},{-x},-1,{-rot},{-z},-1,{finish},0"


def write_trace(path: Path, frames: list[str]) -> Path:
    rows = [f"{round(i * 0.05, 6)},{frame}" for i, frame in enumerate(frames)]
    path.write_text("\n".join([HEADER, *rows]) + "\n", encoding="utf-8")
    return path


#: At rest (the read made before the trial, which drops presses), then start to green,
#: one axis at a time, then A (finish).
TO_GREEN = (
    [pad_frame()]
    + [pad_frame(x=1)] * 52
    + [pad_frame(y=1)] * 88
    + [pad_frame(z=-1)] * 32
    + [pad_frame()] * 2
)
TO_GREEN += [pad_frame(finish=1), pad_frame()]


def headless_pad_trial(trace: Path, method: str, out: Path) -> Path:
    """A Known Goal trial of p01 driven by the gamepad trace, headless and unpaced."""
    device = open_device("gamepad", trace=trace)
    options = {"gui": False, "countdown": 0, "realtime": False}
    return run_teleop(
        load_scene(), "known_goal", method, "p01", out, device=device, input="gamepad", **options
    )


def test_a_gamepad_trace_drives_a_trial_to_the_known_goal_and_its_log_builds(tmp_path):
    trace = write_trace(tmp_path / "to_green.csv", TO_GREEN)
    stem = headless_pad_trial(trace, "NA", tmp_path / "raw" / "pads" / "p01")
    assert validate_paths([tmp_path / "raw"]) == []
    meta, frame = read_trial(stem)
    assert meta["input"] == "gamepad" and meta["source"] == "human"
    # A reads at tick 174: the trial ends there (the rows of ticks 0..174).
    assert len(frame) == 175 and (frame["keys"] == "").all()
    trials = build_tables(tmp_path / "raw" / "pads", load_scene()).trials
    row = trials.iloc[0]
    assert row["success"] and row["input"] == "gamepad"
    # Three presses (x+, y+, z-); 172 ticks of one full-speed axis each.
    assert row["effort"] == 3 and row["effort_ticks"] == 172
    assert row["command_time"] == pytest.approx(172 * 0.05)
    assert row["command_integral"] == pytest.approx(172 * 0.05)


def test_a_gamepad_unplugged_mid_trial_stops_the_arm_and_keeps_the_trial(tmp_path):
    trace = write_trace(tmp_path / "short.csv", TO_GREEN[:30])  # unplugged at tick 29
    out = tmp_path / "raw" / "p01"
    with pytest.raises(TrialCutShort, match="the arm was stopped and the trial kept"):
        headless_pad_trial(trace, "CASA", out)
    assert validate_paths([tmp_path / "raw"]) == []
    meta, frame = read_trial(out / "known_goal_no_misspecification_CASA")
    assert "ended early, the arm stopped" in meta["notes"] and "trace ended" in meta["notes"]
    assert len(frame) == 30 and frame["command_x"].iloc[-1] == 0.0
    assert frame["command_x"].iloc[:29].eq(0.05).all()


@pytest.mark.skipif(bool(MISSING), reason=f"{' and '.join(MISSING)} not on PATH: no display")
def test_casa_teleop_in_a_window_reaches_the_known_goal_with_a_gamepad(tmp_path):
    trace = write_trace(tmp_path / "to_green.csv", TO_GREEN)
    out = tmp_path / "raw" / "pads" / "p01"
    command = [sys.executable, "-m", "casa_core.cli", "teleop", "--task", "known_goal"]
    command += ["--method", "CASA", "--participant", "p01", "--out", str(out)]
    command += ["--input", "gamepad", "--device-trace", str(trace)]
    server, display = start_xvfb()
    try:
        env = {**os.environ, "DISPLAY": display}
        result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=120)
    finally:
        server.terminate()
        server.wait(timeout=10)
    assert result.returncode == 0, result.stdout + result.stderr
    assert validate_paths([tmp_path / "raw"]) == []
    row = build_tables(tmp_path / "raw" / "pads", load_scene()).trials.iloc[0]
    assert (
        row["success"]
        and row["input"] == "gamepad"
        and row["duration"] == pytest.approx(174 * 0.05)
    )


def test_casa_teleop_refuses_a_missing_device_naming_it(tmp_path, capsys):
    from casa_core.cli import main

    code = main(
        [
            "teleop",
            "--task",
            "known_goal",
            "--method",
            "NA",
            "--participant",
            "p01",
            "--out",
            str(tmp_path),
            "--input",
            "gamepad",
            "--device-trace",
            str(tmp_path / "no.csv"),
        ]
    )
    assert code == 2 and "no.csv" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


# -- a whole session with a gamepad, in a real window ---------------------------------------

#: One trial's worth: the read before it, 20 ticks of x+, 10 at rest, then A. A trial of
#: the short session ends at A (or at its 2 s), and the next one reads on from there.
TRIAL = [pad_frame()] + [pad_frame(x=1)] * 20 + [pad_frame()] * 10 + [pad_frame(finish=1)]


class PadOperator(Operator):
    """The session's participant with a gamepad: keys for the screens, the trace drives."""

    def __init__(self, display: str, shots: Path):
        super().__init__(display, shots)
        self.interrupt = []

    def react(self, kind: str) -> None:
        if kind != "trial":
            super().react(kind)


def pad_command(out: Path, config: Path, trace: Path) -> list[str]:
    return [*session_command(out, config), "--input", "gamepad", "--device-trace", str(trace)]


@pytest.mark.skipif(bool(MISSING), reason=f"{' and '.join(MISSING)} not on PATH: no display")
def test_a_whole_session_with_a_gamepad_stops_when_it_is_unplugged_and_builds(tmp_path):
    config = tmp_path / "short.yaml"
    config.write_text(SHORT, encoding="utf-8")
    out = tmp_path / "data" / "raw" / "mylab"
    unplugged = write_trace(tmp_path / "five.csv", TRIAL * 5 + TRIAL[:10])
    whole = write_trace(tmp_path / "whole.csv", TRIAL * 40)
    server, display = start_xvfb()
    try:
        operator = PadOperator(display, tmp_path)
        code, first = drive(pad_command(out, config, unplugged), tmp_path, operator)
        assert code == 0, "\n".join(first[-30:])
        folder = out / "P03"
        # Five trials, then the sixth as far as it ran: 10 ticks, then the trace ended.
        assert len(list(folder.glob("*.json"))) == 6
        assert validate_paths([out]) == []
        log = "\n".join(first)
        assert "as far as it ran" in log and "the session stops: the gamepad is gone" in log
        operator.first_instructions = True
        code, second = drive(pad_command(out, config, whole), tmp_path, operator)
        assert code == 0, "\n".join(second[-40:])
    finally:
        server.terminate()
        server.wait(timeout=10)
    assert "session complete" in "\n".join(second)
    record = SessionRecord(folder, "P03", settings(simulation={"demonstrations": 1}))
    plan = [s.spec.stem for s in record.steps() if s.kind == "trial"]
    assert sorted(p.stem for p in folder.glob("*.json")) == sorted(plan)
    assert (folder / SURVEYS_NAME).is_file() and validate_paths([out]) == []
    metas = [read_trial(folder / stem)[0] for stem in plan]
    assert {meta["input"] for meta in metas} == {"gamepad"}
    # The workflow builds the dataset: its tables, statistics and figures.
    copy_workflow(tmp_path)
    built = snakemake(tmp_path, "--cores", "2", "--config", "datasets=[mylab]")
    assert built.returncode == 0, built.stderr[-3000:]
    processed = tmp_path / "data" / "processed" / "mylab"
    trials = pd.read_csv(processed / "trials.csv", keep_default_na=False)
    assert set(trials["input"]) == {"gamepad"} and (trials["command_time"] > 0).all()
    assert (trials["effort"] >= 1).all()
    assert (processed / "stats.csv").is_file() and (tmp_path / "figures" / "mylab").is_dir()
    assert any((tmp_path / "figures" / "mylab").glob("objective.*"))


def test_casa_session_refuses_a_trace_without_a_device(tmp_path):
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "casa_core.cli",
            "session",
            "--participant",
            "P01",
            "--out",
            str(tmp_path),
            "--device-trace",
            str(tmp_path / "t.csv"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 2 and "choose --input gamepad or spacemouse" in result.stderr
