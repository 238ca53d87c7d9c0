"""A continuous device in the closed loop: its command drives, is logged and is the evidence.

The reference for each expected number: a command equal to what keys command
(:func:`casa_core.robot.keys.keys_to_action`, 0.05 m/s per key) must move the arm
exactly as those keys do, in both teleoperation modes, because both modes turn keys into
that same velocity before anything else (docs/data-contracts.md, the command columns).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd
import pytest

from casa_core.analysis import effort, metrics
from casa_core.assist.tasks import intended_trajectory
from casa_core.config import DEFAULT_CONFIG
from casa_core.io import COMMAND_COLUMNS, read_trial, validate_paths
from casa_core.io.validation import parse_trial_csv
from casa_core.scene import load_scene
from casa_core.study.closed_loop import run_trial
from casa_core.study.command_sources import DeviceCommands, ScriptedCommands
from casa_core.study.key_sources import ScriptedKeys

ORIGINAL_SCENE = load_scene(DEFAULT_CONFIG.with_name("scene-original.yaml"))
#: Keys and the velocity they command (0.05 m/s per key, 0.5 rad/s for rot).
KEY_SCRIPT = [(0.6, ["x+", "y-"]), (0.3, []), (0.4, ["z+", "rot+"])]
COMMAND_SCRIPT = [(0.6, [0.05, -0.05, 0, 0]), (0.3, [0, 0, 0, 0]), (0.4, [0, 0, 0.05, 0.5])]


@pytest.mark.parametrize("mode", ["held", "original"])
def test_a_command_moves_the_arm_exactly_as_the_keys_that_command_it(mode, tmp_path):
    scene = load_scene() if mode == "held" else ORIGINAL_SCENE
    scene = dataclasses.replace(scene, trial_length=None)
    options = {"participant": "p1", "max_duration": 5.0}
    keyed = run_trial(scene, "known_goal", "CASA", ScriptedKeys(KEY_SCRIPT), **options)
    commanded = run_trial(scene, "known_goal", "CASA", ScriptedCommands(COMMAND_SCRIPT), **options)
    pose = ["t", "x", "y", "z", "rot", "alpha", "beta:green", "belief:green"]
    pd.testing.assert_frame_equal(keyed.frame[pose], commanded.frame[pose], check_exact=True)
    assert (commanded.frame["keys"] == "").all()
    assert commanded.meta["input"] == "gamepad" and "input" not in keyed.meta
    np.testing.assert_array_equal(
        commanded.frame[list(COMMAND_COLUMNS)].to_numpy()[:2], [[0.05, -0.05, 0, 0]] * 2
    )
    assert not set(COMMAND_COLUMNS) & set(keyed.frame.columns)
    commanded.write(tmp_path / "p1" / "known_goal_CASA")
    assert validate_paths([tmp_path]) == []
    meta, frame = read_trial(tmp_path / "p1" / "known_goal_CASA")
    assert meta["input"] == "gamepad" and list(frame.columns[5:10]) == ["keys", *COMMAND_COLUMNS]


def test_effort_of_a_command_equals_the_effort_of_the_keys_that_command_it():
    keyed = run_trial(load_scene(), "known_goal", "NA", ScriptedKeys(KEY_SCRIPT), participant="p")
    device = run_trial(
        load_scene(), "known_goal", "NA", ScriptedCommands(COMMAND_SCRIPT), participant="p"
    )
    intended = intended_trajectory("known_goal", load_scene())
    by_keys = metrics.trial_metrics(keyed.frame, intended, dt=0.05)
    by_device = metrics.trial_metrics(device.frame, intended, dt=0.05, input="gamepad")
    # Four presses (x+ y- at 0 s, z+ rot+ at 0.9 s); 12 + 8 held ticks (0.6 s, 0.4 s).
    assert by_keys["effort"] == by_device["effort"] == 4
    assert by_keys["effort_ticks"] == by_device["effort_ticks"] == 2 * 12 + 2 * 8
    # Commands during 0.6 + 0.4 s; two full-speed axes each: 2 * 1.0 s of full speed.
    for measure in (by_keys, by_device):
        assert measure["command_time"] == pytest.approx(1.0, abs=1e-9)
        assert measure["command_integral"] == pytest.approx(2.0, abs=1e-9)
    assert by_device["input"] == "gamepad" and by_keys["input"] == "keyboard"


def test_a_half_deflected_stick_counts_as_held_and_adds_half_a_second_per_second():
    frame = pd.DataFrame(
        {"t": np.round(np.arange(0, 1.05, 0.05), 6), "keys": ""}
        | dict.fromkeys(COMMAND_COLUMNS, 0.0)
    )
    frame.loc[:9, "command_x"] = 0.025  # rows 0..9: 0.5 s at half speed
    frame.loc[10:14, "command_x"] = -0.05  # then reversed at full speed: a second press
    held = effort.held_directions(frame)
    assert effort.presses(held) == 2 and effort.held_ticks(held) == 15
    commands = effort.commanded(frame)
    assert effort.command_time(frame["t"], commands) == pytest.approx(0.75)
    assert effort.command_integral(
        frame["t"], commands, speed=0.05, rot_speed=0.5
    ) == pytest.approx(0.5 * 0.5 + 0.25)


HEADER = "t,x,y,z,rot,keys"
ROWS = ["0,0.45,-0.22,0.38,0", "0.05,0.45,-0.22,0.38,0"]


def _csv(keys=("", ""), command=None) -> str:
    header = HEADER + ("," + ",".join(COMMAND_COLUMNS) if command else "")
    lines = [
        f"{row},{k}" + (f",{command}" if command else "") for row, k in zip(ROWS, keys, strict=True)
    ]
    return "\n".join([header, *lines]) + "\n"


@pytest.mark.parametrize(
    ("meta", "text", "where"),
    [
        ({"input": "gamepad"}, _csv(), "column 'command_x'"),
        ({"input": "spacemouse"}, _csv(("x+", ""), "0,0,0,0"), "column 'keys', line 2"),
        ({}, _csv(command="0,0,0,0"), "column 'command_x'"),
        ({"input": "keyboard"}, _csv(command="0,0,0,0"), "column 'command_x'"),
    ],
)
def test_the_log_refuses_a_device_without_its_command_or_keys_with_one(meta, text, where):
    _, problems = parse_trial_csv(text, "t.csv", meta=meta)
    assert [p.rule for p in problems][:1] == ["input-command"]
    assert problems[0].where == where and "t.csv" in str(problems[0])


def test_a_device_log_with_its_command_parses():
    frame, problems = parse_trial_csv(
        _csv(command="0.05,0,0,0"), "t.csv", meta={"input": "gamepad"}
    )
    assert problems == [] and frame["command_x"].tolist() == [0.05, 0.05]


class _Unplugged:
    """A device that gives full x+ for ``reads`` reads, then is gone."""

    name = "gamepad 'test pad'"

    def __init__(self, reads: int):
        self.left = reads

    def read(self):
        from casa_core.robot.devices import DeviceLost, DeviceReading

        if self.left == 0:
            raise DeviceLost(f"{self.name} was unplugged")
        self.left -= 1
        return DeviceReading(axes=(1.0, 0.0, 0.0, 0.0))


@pytest.mark.parametrize("trial_length", [None, 15.0])
def test_a_device_lost_mid_trial_stops_the_arm_and_ends_the_trial(trial_length):
    scene = dataclasses.replace(load_scene(), trial_length=trial_length)
    # Its first read is dropped (a press before the trial), then ten reads of x+.
    source = DeviceCommands(_Unplugged(11), input="gamepad", speed=0.05, rot_speed=0.5)
    result = run_trial(scene, "known_goal", "NA", source, participant="p", max_duration=30)
    frame = result.frame
    assert source.lost == "gamepad 'test pad' was unplugged" and source.done
    # Ten reads of x+, then the read that failed: its row commands zero and ends the trial.
    assert frame["command_x"].tolist() == [0.05] * 10 + [0.0]
    assert frame["t"].iloc[-1] == pytest.approx(0.5)
    assert frame["x"].iloc[-1] > frame["x"].iloc[0] + 0.02  # it moved while plugged in


def test_a_replay_of_a_device_trial_takes_its_command_and_reproduces_the_log(tmp_path):
    from casa_core.analysis.replay import replay_differences, replay_trial

    scene = load_scene()
    # Toward green (x+, y-; the default layout's start is at x 0.45, y -0.22) at part speed.
    script = [(2.0, [0.04, -0.02, -0.01, 0.0]), (1.5, [0.02, 0.0, 0.0, 0.0])]
    result = run_trial(scene, "known_goal", "CASA", ScriptedCommands(script), participant="p1")
    meta, frame = result.write(tmp_path / "p1" / "known_goal_CASA")
    replayed = replay_trial(meta, frame, scene)
    assert replay_differences(frame, replayed) == {"beta": 0.0, "belief": 0.0, "alpha": 0.0}
    # Without the command (as if no key was held) the replay's inference differs.
    keys_only = frame.drop(columns=list(COMMAND_COLUMNS))
    differs = replay_differences(
        frame, replay_trial({**meta, "input": "keyboard"}, keys_only, scene)
    )
    assert differs["beta"] > 0.01
